// Floes on the 3D BEM basin (fluid/bem3d.hpp) through the Sea interface, as on
// the spectral sea: the static start stays at rest, a floe heaves with a
// basin's sloshing mode, and floes collide on it. Issue 19, "Validation".
#include <doctest/doctest.h>

#include <array>
#include <cmath>
#include <vector>
#include <sstream>
#include <string>

#include "core/config.hpp"
#include "coupling/scenario.hpp"
#include "coupling/simulation.hpp"
#include "sim_energy.hpp"

using namespace floesim;
using floesim::test::energy;

TEST_SUITE_BEGIN("coupling");

namespace {

Simulation make(const std::string& text) { return Simulation(build_scenario(parse_config(text, "bem3d.toml", "."))); }

// A basin 8 m x 4 m x 2 m (0.25 m cells): every test shares its cached set-up.
const std::string kBasin =
    "[sea]\nmodel = \"bem\"\ndims = 2\nsize = [8.0, 4.0]\ncells = [32, 16]\ndepth = 2.0\nrho = 1000.0\n";

std::string square(double x0, double y0, double side, double vx = 0.0) {
  std::ostringstream t;
  const double h = side / 2;
  t << "[[floes.floe]]\nvertices = [[" << x0 - h << ", " << y0 - h << "], [" << x0 + h << ", " << y0 - h << "], ["
    << x0 + h << ", " << y0 + h << "], [" << x0 - h << ", " << y0 + h << "]]\nthickness = 0.1\nvelocity = [" << vx
    << ", 0.0]\n";
  return t.str();
}

}  // namespace

TEST_CASE("3D BEM basin: a floe at rest on a calm basin stays at rest") {
  // The run starts from the floes' static equilibrium on the sea (MODEL.md §1):
  // with no waves and no forcing nothing may move. Draft d = 917 * 0.1 / 1000 m.
  // The floe's edges are off the grid lines: with the cell footprint kernel
  // (the one a walled basin uses) a floe whose edges lie on grid lines gets a
  // net horizontal push at the start, on the spectral sea too (measured with
  // this floe at (4, 2): 7.6e-4 m/s spectral with footprint = "cell", 8.6e-4
  // m/s here); off the lines 3.4e-5 and 4.1e-5 m/s. Pure gravity: the static
  // start is hydrostatic (coupling/floe_sea.hpp), and with sigma = 0.073 N/m
  // the mismatch sloshes the basin and pushes the floe to 2.2e-4 m/s.
  const double d = 917.0 * 0.1 / 1000.0;
  std::ostringstream t;
  t << "[run]\nt_end = 5.0\ndt_max = 0.01\noutput_interval = 5.0\n" << kBasin << "sigma = 0.0\n"
    << "[coupling]\nlaw = \"strong\"\nstiffness = 100.0\n[forcing]\nocean_drag = 0.0\nair_drag = 0.0\n"
    << square(4.1, 2.1, 1.5);
  Simulation sim = make(t.str());
  double worst = 0.0, speed = 0.0;
  while (sim.time() < 5.0) {
    sim.step(5.0);
    const auto& s = sim.floes().state[0];
    worst = std::max(worst, std::abs(s.heave));
    speed = std::max(speed, std::hypot(s.vx, s.vy));
  }
  MESSAGE("largest heave " << worst << " m, largest horizontal speed " << speed << " m/s");
  CHECK(worst < 0.005 * d);
  CHECK(speed < 1e-4);
}

TEST_CASE("3D BEM basin: a floe in a steady wind reaches the free-drift speed") {
  // The drag through the BEM sea's Sea interface, as on the spectral sea
  // (test_subcell.cpp). Quadratic drag (coupling/drift.hpp): steady state
  // rho_a C_a U_a^2 = rho_w C_w u^2, u = sqrt(rho_a C_a / (rho_w C_w)) U_a,
  // reached from rest as u tanh(t / tau), tau = rho_i h / (rho_w C_w u)
  // = 8.7 s here (a large C_w so that the floe, 1 m on a basin 8 m long,
  // reaches it within 0.9 m of drift, before the wall). The calm basin has no
  // incident waves: the drag is relative to still water. Measured 0.976 u
  // (mean over 30..40 s; 0.975 over 30..58 s, so not the basin's 4 s
  // sloshing), 0.992 u on 16 x 8 cells and 0.989 u on 48 x 24: the walled
  // basin's cell footprint kernel drags a little on the grid, as on the
  // spectral sea (0.84 u there with the cell kernel and a drag ten times
  // weaker; docs/coupling.md, "Footprints"). Drag relative to the sea's own
  // velocity under the floe would give about 0.89 u, and no drag no steady
  // speed at all.
  const double rho_a = 1.3, Ca = 1.7e-3, Cw = 0.5, Ua = 10.0;
  const double u = std::sqrt(rho_a * Ca / (1000.0 * Cw)) * Ua;
  std::ostringstream t;
  t << "[run]\nt_end = 40.0\ndt_max = 0.05\noutput_interval = 40.0\nthreads = 1\n" << kBasin
    << "[coupling]\nlaw = \"strong\"\nstiffness = 100.0\nintegrator = \"implicit\"\n"
    << "[forcing]\nocean_drag = " << Cw << "\nair_drag = " << Ca << "\nair_density = " << rho_a << "\nwind = [" << Ua
    << ", 0.0]\n" << square(2.1, 2.1, 1.0);
  Simulation sim = make(t.str());
  double mean = 0.0;
  while (sim.time() < 40.0 - 1e-9) {
    const double dt = sim.step(40.0);
    if (sim.time() > 30.0 + 1e-9) mean += sim.floes().state[0].vx * dt / 10.0;
  }
  MESSAGE("mean drift speed over 30..40 s: " << mean << " m/s = " << mean / u << " of the free drift " << u
                                             << " m/s; x at 40 s " << sim.floes().state[0].x << " m");
  CHECK(mean > 0.97 * u);
  CHECK(mean < 1.005 * u);
  // Across the wind only the basin's cross modes, which the floe (0.1 m off
  // the centre line, its edges off the grid lines) excites a little: 9e-5 m/s.
  CHECK(std::abs(sim.floes().state[0].vy) < 1e-2 * u);
}

TEST_CASE("3D BEM basin: a small floe heaves with the sloshing mode (1,0) at its frequency and amplitude") {
  // Standing mode cos(pi x / L) of amplitude a (the initial surface); a floe
  // 1 m wide at x0 = 1 m, far shorter than the 16 m wave and far stiffer in
  // heave (sqrt(g / d) = 10.3 rad/s against omega = 1.59 rad/s), follows the
  // surface: heave amplitude a cos(pi x0 / L) (the long-wave limit of
  // MODEL.md §4; the floe's dynamic amplification 1 / (1 - omega^2 d / g)
  // adds 2.3%, averaging cos over the floe's width removes 0.3%).
  const double a = 0.01, L = 8.0, x0 = 1.0;
  std::ostringstream t;
  t << "[run]\nt_end = 30.0\ndt_max = 0.01\noutput_interval = 30.0\n" << kBasin
    << "[sea.waves]\nkind = \"standing\"\namplitude = " << a << "\nwavelength = 16.0\n"
    << "[coupling]\nlaw = \"strong\"\nstiffness = 100.0\n[forcing]\nocean_drag = 0.0\nair_drag = 0.0\n"
    << square(x0, 2.0, 1.0);
  Simulation sim = make(t.str());
  const double k = M_PI / L, omega = std::sqrt(9.81 * k * std::tanh(k * 2.0));
  const double period = 2 * M_PI / omega;
  double c = 0.0, s = 0.0;
  while (sim.time() < 5.0 * period - 1e-9) {
    const double t0 = sim.time();
    const double dt = sim.step(5.0 * period);
    if (t0 >= period) {
      const double tm = t0 + 0.5 * dt, z = sim.floes().state[0].heave;
      c += z * std::cos(omega * tm) * dt;
      s += z * std::sin(omega * tm) * dt;
    }
  }
  const double amplitude = 2.0 / (4.0 * period) * std::hypot(c, s);
  const double expected = a * std::cos(k * x0);
  MESSAGE("heave amplitude at omega " << amplitude << " m, surface amplitude there " << expected << " m");
  CHECK(amplitude == doctest::Approx(expected).epsilon(0.1));
  // In phase with the surface (cos(omega t) at t = 0: c dominates).
  CHECK(std::abs(c) > 5.0 * std::abs(s));
}

TEST_CASE("3D BEM basin: two floes collide on a sloshing sea without overlap, failures or energy growth") {
  // The strong law conserves energy; the collisions (e = 0.4) can only remove it.
  std::ostringstream t;
  t << "[run]\nt_end = 6.0\ndt_max = 0.01\noutput_interval = 1.0\n" << kBasin
    << "[sea.waves]\nkind = \"standing\"\namplitude = 0.02\nwavelength = 16.0\n"
    << "[coupling]\nlaw = \"strong\"\nstiffness = 100.0\n[forcing]\nocean_drag = 0.0\nair_drag = 0.0\n"
    << square(3.0, 2.0, 1.0, 0.3) << square(4.1, 2.1, 1.0, -0.3);
  Simulation sim = make(t.str());
  const test::EnergyRun run = test::run_tracking_energy(sim, 6.0);
  CHECK(sim.collision_stats().lcps > 0);
  CHECK(sim.collision_stats().failures == 0);
  CHECK(run.top < run.start * (1.0 + 1e-3));
  CHECK(energy(sim, "total") < run.start);
}

TEST_CASE("3D BEM basin, lowest modes only: a floe's motion converges to the one with all modes as the cut rises") {
  // The same floe (1 m, 4 x 4 cells) on the same sloshing sea with all 511
  // modes and with the 256 and 448 lowest (bem_modes). The floe's pressure
  // has the sharp edges of its footprint: its local, quasi-static response
  // (a dimple as deep as the draft) needs the short modes, so the cut changes
  // the floe's heave and drift far more than the waves' (measured over 4 s,
  // heave difference / largest heave: 1.9 at 128 modes, 0.27 at 256, 9.0e-3 at
  // 400, 2.6e-3 at 448, 5.6e-4 at 500; drift 1.9, 1.3, 0.28, 0.17, 1.3e-3).
  auto run = [](int modes) {
    std::ostringstream t;
    t << "[run]\nt_end = 4.0\ndt_max = 0.01\noutput_interval = 4.0\n" << kBasin << "bem_modes = " << modes << "\n"
      << "[sea.waves]\nkind = \"standing\"\namplitude = 0.02\nwavelength = 16.0\n"
      << "[coupling]\nlaw = \"strong\"\nstiffness = 100.0\n[forcing]\nocean_drag = 0.0\nair_drag = 0.0\n"
      << square(1.1, 2.1, 1.0);
    Simulation sim = make(t.str());
    // Sampled every 0.05 s (the steps' lengths depend on the fastest mode kept).
    std::vector<std::array<double, 2>> track;
    for (int k = 1; k <= 80; ++k) {
      while (sim.time() < 0.05 * k - 1e-12) sim.step(0.05 * k);
      track.push_back({sim.floes().state[0].heave, sim.floes().state[0].x});
    }
    return track;
  };
  const auto all = run(0);
  double heave = 0.0, drift = 0.0;
  for (const auto& s : all) {
    heave = std::max(heave, std::abs(s[0]));
    drift = std::max(drift, std::abs(s[1] - all[0][1]));
  }
  CHECK(heave > 0.01);
  std::vector<std::array<double, 2>> worst;  // per cut: largest heave and drift differences
  for (int modes : {256, 448}) {
    const auto low = run(modes);
    REQUIRE(low.size() == all.size());
    worst.push_back({0.0, 0.0});
    for (std::size_t i = 0; i < all.size(); ++i) {
      worst.back()[0] = std::max(worst.back()[0], std::abs(low[i][0] - all[i][0]));
      worst.back()[1] = std::max(worst.back()[1], std::abs(low[i][1] - all[i][1]));
    }
    MESSAGE(modes << " modes: heave difference " << worst.back()[0] / heave << ", drift difference "
                  << worst.back()[1] / drift << " (of the largest heave " << heave << " m and drift " << drift << " m)");
  }
  CHECK(worst[1][0] < 0.01 * heave);
  CHECK(worst[1][1] < 0.3 * drift);
  CHECK(worst[0][0] > 10.0 * worst[1][0]);
}

TEST_CASE("3D BEM basin, lowest modes with the static correction: a floe's motion is the one with all modes") {
  // Reference: the full-mode dense sea (all 511 modes), stepped by the same
  // implicit integrator. The same floe (1 m, 4 x 4 cells) in the same 2 cm
  // sloshing wave over 4 s, on the 128 and 256 lowest modes with and without
  // the static correction of the dropped modes (fluid/static_correction.hpp):
  // the correction carries the floe's local, quasi-static dimple that the
  // cut drops. Heave and drift differences over the largest heave and drift.
  auto run = [](int modes, bool correct) {
    std::ostringstream t;
    t << "[run]\nt_end = 4.0\ndt_max = 0.01\noutput_interval = 4.0\n" << kBasin << "bem_modes = " << modes << "\n"
      << (correct ? "bem_static_correction = true\n" : "")
      << "[sea.waves]\nkind = \"standing\"\namplitude = 0.02\nwavelength = 16.0\n"
      << "[coupling]\nlaw = \"strong\"\nstiffness = 100.0\nintegrator = \"implicit\"\n"
      << "[forcing]\nocean_drag = 0.0\nair_drag = 0.0\n" << square(1.1, 2.1, 1.0);
    Simulation sim = make(t.str());
    std::vector<std::array<double, 2>> track;
    const double e0 = energy(sim, "total");
    double top = e0;
    for (int k = 1; k <= 80; ++k) {
      while (sim.time() < 0.05 * k - 1e-12) {
        sim.step(0.05 * k);
        top = std::max(top, energy(sim, "total"));
      }
      track.push_back({sim.floes().state[0].heave, sim.floes().state[0].x});
    }
    MESSAGE(modes << " modes" << std::string(correct ? ", corrected" : "") << ": total energy " << e0 << " J, at 4 s "
                  << energy(sim, "total") << " J, largest " << top << " J");
    if (correct) {
      // The corrected implicit step only absorbs: the dropped modes' static
      // part takes the work 1/2 dF^T R dF more than it stores per step
      // (docs/sea.md, "Static correction"): measured 1.6e-5 (128 modes) and
      // 7e-6 (256) of the energy over 4 s. It starts from the full-mode
      // sea's energy (71.7633 J; 99.73 J cut to 128 modes without it).
      CHECK(top <= e0 * (1.0 + 1e-9));
      CHECK(energy(sim, "total") > e0 * (1.0 - 1e-4));
    }
    return track;
  };
  const auto all = run(0, false);
  double heave = 0.0, drift = 0.0;
  for (const auto& s : all) {
    heave = std::max(heave, std::abs(s[0]));
    drift = std::max(drift, std::abs(s[1] - all[0][1]));
  }
  CHECK(heave > 0.01);
  auto differences = [&](const std::vector<std::array<double, 2>>& low) {
    std::array<double, 2> worst = {0.0, 0.0};
    REQUIRE(low.size() == all.size());
    for (std::size_t i = 0; i < all.size(); ++i) {
      worst[0] = std::max(worst[0], std::abs(low[i][0] - all[i][0]) / heave);
      worst[1] = std::max(worst[1], std::abs(low[i][1] - all[i][1]) / drift);
    }
    return worst;
  };
  std::array<double, 2> cut[2], corrected[2];
  const int kept[2] = {128, 256};
  for (int m = 0; m < 2; ++m) {
    cut[m] = differences(run(kept[m], false));
    corrected[m] = differences(run(kept[m], true));
    MESSAGE(kept[m] << " modes: heave difference " << cut[m][0] << " cut, " << corrected[m][0]
                    << " corrected; drift difference " << cut[m][1] << " cut, " << corrected[m][1]
                    << " corrected (of the largest heave " << heave << " m and drift " << drift << " m)");
  }
  // Measured: 128 modes, heave 2.08 cut, 3.0e-3 corrected; drift 3.45,
  // 3.1e-2. 256 modes: heave 0.26, 2.5e-3; drift 1.28, 1.4e-2.
  for (int m = 0; m < 2; ++m) {
    CHECK(corrected[m][0] < cut[m][0] / 50.0);
    CHECK(corrected[m][1] < cut[m][1] / 50.0);
    CHECK(corrected[m][0] < 0.01);
    CHECK(corrected[m][1] < 0.05);
  }
}

TEST_CASE("3D BEM basin, lowest modes with the static correction: a floe at rest stays at rest") {
  // 128 of 511 modes, corrected: the static start (the floe's dimple, held by
  // the sea's static part from the start) is the corrected sea's equilibrium,
  // as it is the full sea's (sigma = 0: the static response is local).
  const double d = 917.0 * 0.1 / 1000.0;
  std::ostringstream t;
  t << "[run]\nt_end = 5.0\ndt_max = 0.01\noutput_interval = 5.0\n" << kBasin << "sigma = 0.0\nbem_modes = 128\n"
    << "bem_static_correction = true\n[coupling]\nlaw = \"strong\"\nstiffness = 100.0\nintegrator = \"implicit\"\n"
    << "[forcing]\nocean_drag = 0.0\nair_drag = 0.0\n" << square(4.1, 2.1, 1.5);
  Simulation sim = make(t.str());
  const double e0 = energy(sim, "total");
  double worst = 0.0, speed = 0.0, energy_change = 0.0;
  while (sim.time() < 5.0) {
    sim.step(5.0);
    const auto& s = sim.floes().state[0];
    worst = std::max(worst, std::abs(s.heave));
    speed = std::max(speed, std::hypot(s.vx, s.vy));
    energy_change = std::max(energy_change, std::abs(energy(sim, "total") - e0));
  }
  MESSAGE("largest heave " << worst << " m, largest horizontal speed " << speed << " m/s, largest energy change "
                           << energy_change << " J");
  CHECK(worst < 0.005 * d);
  CHECK(speed < 1e-4);
}

TEST_SUITE_END();
