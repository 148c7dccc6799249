// Floe–sea penalty coupling (coupling/floe_sea.hpp, MODEL.md §4–5): validation
// against closed forms and conservation laws. Each test says which.

#include <doctest/doctest.h>

#include <cmath>
#include <sstream>
#include <string>

#include "core/config.hpp"
#include "coupling/footprint.hpp"
#include "coupling/penalty_law.hpp"
#include "coupling/scenario.hpp"
#include "coupling/simulation.hpp"
#include "sim_energy.hpp"
#include "fluid/sea.hpp"

using namespace floesim;
using floesim::test::energy;

namespace {

Simulation make(const std::string& text) { return Simulation(build_scenario(parse_config(text, "floe_sea.toml", "."))); }

// One square floe of side L, thickness 1 m, in a periodic spectral box.
std::string one_floe(double L, const std::string& sea, const std::string& extra, double x0 = 50.0, double y0 = 50.0) {
  std::ostringstream t;
  t << "[run]\nt_end = 10.0\ndt_max = 0.01\noutput_interval = 1.0\n"
    << sea << "\n[forcing]\nocean_drag = 0.0\nair_drag = 0.0\n"
    << "[[floes.floe]]\nvertices = [[" << x0 - L / 2 << ", " << y0 - L / 2 << "], [" << x0 + L / 2 << ", "
    << y0 - L / 2 << "], [" << x0 + L / 2 << ", " << y0 + L / 2 << "], [" << x0 - L / 2 << ", " << y0 + L / 2
    << "]]\nthickness = 1.0\n"
    << extra;
  return t.str();
}

const std::string kSea2d =
    "[sea]\nmodel = \"spectral\"\ndims = 2\nsize = [100.0, 100.0]\ncells = [64, 64]\ndepth = 50.0\n";

}  // namespace

TEST_SUITE("coupling") {

TEST_CASE("footprint pieces tile the floe exactly, wherever it sits on the grid") {
  // Exact geometry: the area pieces sum to the polygon's area and first
  // moment (Green's theorem), and the edge pieces to its perimeter, for a
  // non-convex floe at positions that put vertices on and off grid lines.
  Floes floes;
  FloeInput in;
  in.vertices = {{0, 0}, {7.3, 0}, {7.3, 5.1}, {3.2, 2.0}, {0, 5.1}};  // a notch: non-convex
  floes.add(make_floe_shape(in), in);
  const std::uint8_t include[] = {1};
  fluid::SurfaceGrid grid{2, 32, 32, 64.0, 64.0, fluid::GridEdge::periodic};
  double perimeter = 0.0;
  for (std::size_t k = 0; k < in.vertices.size(); ++k)
    perimeter += (in.vertices[(k + 1) % in.vertices.size()] - in.vertices[k]).norm();
  for (const Vec2& at : {Vec2{10.0, 10.0}, Vec2{10.37, 11.91}, Vec2{0.5, 63.2}}) {
    for (double yaw : {0.0, 0.7}) {
      floes.state[0].x = at.x();
      floes.state[0].y = at.y();
      floes.state[0].yaw = yaw;
      Footprints fp;
      build_footprints(floes, include, grid, fp);
      double area = 0.0, length = 0.0;
      Vec2 first = Vec2::Zero();
      for (std::size_t k = 0; k < fp.cell.size(); ++k) {
        area += fp.area[k];
        first += fp.area[k] * fp.centroid[k];
      }
      for (std::size_t k = 0; k < fp.edge_cell.size(); ++k) length += fp.edge_length[k];
      CHECK(area == doctest::Approx(floes.area[0]).epsilon(1e-12));
      CHECK(first.norm() < 1e-10 * floes.area[0]);  // centroid at G
      CHECK(length == doctest::Approx(perimeter).epsilon(1e-12));
      for (std::size_t k = 0; k < fp.edge_cell.size(); ++k) CHECK(fp.find(0, fp.edge_cell[k]) >= 0);
    }
  }
}

TEST_CASE("obstacle problem: closed-form Kelvin–Voigt restitution, strong -> 1, weak -> 0, blend inverted") {
  // Strong law (s = 1): a spring, so the exit speed equals the entry speed.
  for (double K : {10.0, 1e3, 1e5}) CHECK(obstacle_restitution(1.0, K) == doctest::Approx(1.0).epsilon(1e-6));
  // Weak law (s = 0): e -> 0 as K grows (seed 000, Theorem 2.2: the limit absorbs the impact).
  double last = 1.0;
  for (double K : {10.0, 100.0, 1e3, 1e4}) {
    const double e = obstacle_restitution(0.0, K);
    CHECK(e < last);
    last = e;
  }
  CHECK(last < 0.01);
  // For K >> 1 the contact is a linear spring–dashpot (Kelvin–Voigt) whose
  // restitution is exp(-zeta pi / sqrt(1 - zeta^2)), zeta = (1 - s) sqrt(K / s) / 2.
  const double K = 1e6;
  for (double zeta : {0.1, 0.3, 0.6}) {
    // Solve (1 - s) sqrt(K / s) / 2 = zeta for s near 1.
    double s = 1.0 - 2.0 * zeta / std::sqrt(K);
    for (int k = 0; k < 50; ++k) s = 1.0 - 2.0 * zeta * std::sqrt(s / K);
    const double exact = std::exp(-zeta * M_PI / std::sqrt(1.0 - zeta * zeta));
    CHECK(obstacle_restitution(s, K) == doctest::Approx(exact).epsilon(0.01));
  }
  // Blend: the calibration table reproduces a requested e within 0.02 (issue #6).
  for (double Kc : {100.0, 1000.0}) {
    const BlendCalibration cal = calibrate_blend(Kc);
    for (double e : {0.1, 0.3, 0.5, 0.7, 0.9}) {
      const double s = cal.share_for(e);
      CHECK(obstacle_restitution(s, Kc) == doctest::Approx(e).epsilon(0.02 / e));
    }
  }
}

TEST_CASE("floating equilibrium: the static start is at rest, displaces its weight, and sits at draft rho_i h / rho_w") {
  // Archimedes: a floe of density 917 and thickness 1 m displaces M / rho_w of
  // water and floats with its bottom d = 917 / 1025 m below the water level;
  // the penalty adds its compliance d / K (the penetration that carries the
  // weight). The start must be an equilibrium of the discrete dynamics: the
  // heave stays below 0.5 % of d over 10 s.
  const double d = 917.0 / 1025.0;
  {
    Simulation sim = make(one_floe(20.0, kSea2d, "[coupling]\nlaw = \"strong\"\nstiffness = 100.0\n"));
    double worst = 0.0;
    while (sim.time() < 10.0) {
      sim.step(10.0);
      worst = std::max(worst, std::abs(sim.floes().state[0].heave));
    }
    CHECK(worst < 0.005 * d);
    // Displaced volume: the depression of the sea below the far-field level.
    const std::span<const double> eta = sim.sea_elevation();
    const double level = eta[0], cell = (100.0 / 64) * (100.0 / 64);
    double volume = 0.0;
    for (double e : eta) volume += (level - e) * cell;
    CHECK(volume == doctest::Approx(sim.floes().mass[0] / 1025.0).epsilon(0.005));
  }
  // The bottom's depth below the water level: exact at any resolution with
  // the sub-cell law (tests/coupling/test_subcell.cpp); here in a flume
  // (dims = 1, the floe spanning its width) with L / dx = 400, within 0.5 %. Pure
  // gravity (sigma = 0): at dx = 5 cm capillarity would stiffen the shortest
  // waves by 3 %, which the hydrostatic static start neglects.
  for (double K : {100.0, 1000.0}) {
    std::ostringstream t;
    t << "[run]\nt_end = 5.0\ndt_max = 0.01\n"
      << "[sea]\nmodel = \"spectral\"\ndims = 1\nsize = [200.0, 10.0]\ncells = [4000, 1]\ndepth = 50.0\nsigma = 0.0\n"
      << "[coupling]\nlaw = \"strong\"\nstiffness = " << K << "\n[forcing]\nocean_drag = 0.0\nair_drag = 0.0\n"
      << "[[floes.floe]]\nvertices = [[90.0, 0.0], [110.0, 0.0], [110.0, 10.0], [90.0, 10.0]]\nthickness = 1.0\n";
    Simulation sim = make(t.str());
    while (sim.time() < 5.0) sim.step(5.0);
    const double level = sim.sea_elevation()[0];
    const double depth = level - sim.floe_sea()->bottom(sim.floes(), 0);
    CHECK(depth == doctest::Approx(d * (1.0 + 1.0 / K)).epsilon(0.005));
    CHECK(std::abs(sim.floes().state[0].heave) < 0.005 * d);
  }
}

TEST_CASE("strong law without drag conserves the total energy, with a second-order error in dt") {
  // MODEL.md §5: with the strong law, no drag and no forcing the staggered
  // loop is a Strang splitting of a Hamiltonian system: energy conserved to
  // O(dt^2). A floe on a wavy sea, pushed sideways and spinning (so the
  // horizontal forces -dV/dG work too), over 10^4 steps.
  auto drift = [](double dt, int steps) {
    std::ostringstream extra;
    extra << "velocity = [0.3, 0.1]\nangular_velocity = 0.01\n"
          << "[coupling]\nlaw = \"strong\"\nstiffness = 100.0\n"
          << "[sea.waves]\nkind = \"regular\"\namplitude = 0.1\nwavelength = 25.0\n";
    std::string text = one_floe(12.0, kSea2d, extra.str());
    const std::string from = "dt_max = 0.01", to = "dt_max = " + std::to_string(dt);
    text.replace(text.find(from), from.size(), to);
    Simulation sim = make(text);
    const double e0 = energy(sim, "total");
    double worst = 0.0;
    for (int k = 0; k < steps; ++k) {
      sim.step(1e9);
      worst = std::max(worst, std::abs(energy(sim, "total") - e0));
    }
    return worst / e0;
  };
  // Over the same 20 s: dt = 0.004 s (5000 steps) and 0.002 s (10^4 steps).
  // Below dt ~ 0.002 s the ratio falls (measured 2.3 from 0.002 to 0.001 s):
  // the penalty energy is only C^1 where a piece's contact opens or a floe
  // edge enters a cell, which limits the splitting's order there.
  const double e0 = drift(0.004, 5000);
  const double e1 = drift(0.002, 10000);
  MESSAGE("relative energy error: dt = 0.004 s: " << e0 << ", dt = 0.002 s: " << e1);
  CHECK(e1 < 1e-4);
  CHECK(e0 / e1 > 3.0);  // second order: 4 in the limit
}

TEST_CASE("footprints moved between rebuilds: the strong law's energy error grows with the reach, builds fall") {
  // coupling/moving_footprint.hpp: between rebuilds the forces are the exact
  // gradient of the energy on the moved pieces, so the splitting conserves
  // it as above; a rebuild changes a boundary piece by O(reach^2) of a cell,
  // and the energy with it. Rebuilds come about 1 / reach times as often,
  // so the error grows about as the reach. The floe of the test above at
  // dt = 0.004 s.
  auto drift = [](double reach) {
    std::ostringstream extra;
    extra << "velocity = [0.3, 0.1]\nangular_velocity = 0.01\n"
          << "[coupling]\nlaw = \"strong\"\nstiffness = 100.0\nfootprint_reach = " << reach << "\n"
          << "[sea.waves]\nkind = \"regular\"\namplitude = 0.1\nwavelength = 25.0\n";
    std::string text = one_floe(12.0, kSea2d, extra.str());
    const std::string from = "dt_max = 0.01";
    text.replace(text.find(from), from.size(), "dt_max = 0.004");
    Simulation sim = make(text);
    const double e0 = energy(sim, "total");
    double worst = 0.0;
    for (int k = 0; k < 5000; ++k) {
      sim.step(1e9);
      worst = std::max(worst, std::abs(energy(sim, "total") - e0));
    }
    return std::pair{worst / e0, sim.floe_sea()->footprint_rebuilds()};
  };
  const auto [e_exact, builds_exact] = drift(0.0);
  const auto [e_fine, builds_fine] = drift(0.01);
  const auto [e_coarse, builds_coarse] = drift(0.04);
  MESSAGE("relative energy error over 20 s: reach 0: " << e_exact << " (" << builds_exact << " builds), 0.01: "
          << e_fine << " (" << builds_fine << "), 0.04: " << e_coarse << " (" << builds_coarse << ")");
  CHECK(builds_fine < builds_exact / 5);
  CHECK(e_fine < 1e-4);
  CHECK(e_coarse / e_fine > 3.0);
}

TEST_CASE("drop test: the strong law rebounds, the weak law does not, and waves carry energy away") {
  // The seed's slamming configuration (seed 000 §1): a floe released above
  // the surface with a downward speed. Strong law: elastic limit, total energy
  // conserved; weak law: the impact energy is absorbed (total energy drops).
  auto drop = [](const std::string& law, double& rebound, double& radiated, double& lost) {
    std::string text = one_floe(10.0, kSea2d,
                                "heave = 1.5\nheave_rate = -2.0\n[coupling]\nlaw = \"" + law +
                                    "\"\nstiffness = 1000.0\nstart = \"given\"\n");
    // The impact is resolved with omega_pen dt = 0.1 (the stability limit is 1).
    text.replace(text.find("dt_max = 0.01"), 13, "dt_max = 0.0005");
    Simulation sim = make(text);
    const double e0 = energy(sim, "total");
    rebound = 0.0;
    double min_heave = 1e9;
    while (sim.time() < 3.0) {
      sim.step(3.0);
      const FloeState& s = sim.floes().state[0];
      min_heave = std::min(min_heave, s.heave);
      if (s.heave < 0.5) rebound = std::max(rebound, s.heave_rate);  // after the impact
    }
    CHECK(min_heave < 0.5);  // it did hit the water
    radiated = energy(sim, "sea_kinetic") + energy(sim, "sea_potential");
    lost = (e0 - energy(sim, "total")) / e0;
  };
  double rs, ws, ls, rw, ww, lw;
  drop("strong", rs, ws, ls);
  drop("weak", rw, ww, lw);
  MESSAGE("rebound speed: strong " << rs << " m/s, weak " << rw << " m/s; energy lost: strong " << ls << ", weak "
                                   << lw);
  CHECK(std::abs(ls) < 1e-3);
  CHECK(lw > 0.05);
  CHECK(rs > rw);
  CHECK(ws > 0.0);
  CHECK(ww > 0.0);
}

TEST_CASE("a small floe follows long waves and barely heaves in short ones") {
  // Long-wave limit (MODEL.md §4, hydrostatics): heave / wave amplitude -> 1
  // as wavelength / floe length grows; for waves shorter than the floe the
  // pressure averages out over the footprint (the heave of a rigid floe in a
  // wave of length lambda = L is 0 in the quasi-static limit: sin(kL/2)/(kL/2)).
  auto response = [](double wavelength) {
    std::ostringstream t;
    t << "[run]\nt_end = 100.0\ndt_max = 0.01\noutput_interval = 1.0\n"
      << "[sea]\nmodel = \"spectral\"\ndims = 1\nsize = [320.0, 10.0]\ncells = [320, 1]\ndepth = 100.0\n"
      << "[sea.waves]\nkind = \"regular\"\namplitude = 0.05\nwavelength = " << wavelength << "\n"
      << "[coupling]\nlaw = \"strong\"\nstiffness = 100.0\n"
      << "[forcing]\nocean_drag = 0.0\nair_drag = 0.0\n"
      << "[[floes.floe]]\nvertices = [[155.0, 0.0], [165.0, 0.0], [165.0, 10.0], [155.0, 10.0]]\nthickness = 0.5\n";
    Simulation sim = make(t.str());
    // The heave's Fourier component at the wave frequency over periods 2..6
    // (the start excites the floe's own heave frequency, sqrt(g / d), which
    // this filters out, as it does the mean).
    const double omega = std::sqrt(9.81 * 2 * M_PI / wavelength * std::tanh(2 * M_PI / wavelength * 100.0));
    const double period = 2 * M_PI / omega;
    double c = 0.0, s = 0.0;
    while (sim.time() < 6.0 * period - 1e-9) {
      const double t0 = sim.time();
      const double dt = sim.step(6.0 * period);
      if (t0 >= 2.0 * period) {
        const double tm = t0 + 0.5 * dt, z = sim.floes().state[0].heave;
        c += z * std::cos(omega * tm) * dt;
        s += z * std::sin(omega * tm) * dt;
      }
    }
    return 2.0 / (4.0 * period) * std::hypot(c, s) / 0.05;
  };
  const double long_wave = response(160.0), short_wave = response(10.0);
  MESSAGE("heave / amplitude: lambda = 160 m: " << long_wave << ", lambda = 10 m: " << short_wave);
  CHECK(long_wave == doctest::Approx(1.0).epsilon(0.1));
  CHECK(short_wave < 0.3);
}

TEST_CASE("two floes in waves collide: LCP impulses and the penalty coexist without overlap or blow-up") {
  // Energy: without drag or wind the only work is the collisions' (e = 0.4,
  // dissipative) so the total energy may fall but not grow beyond the
  // splitting error. No overlap is the loop's invariant (it throws otherwise).
  // The floes start 0.2 m apart (test_subcell.cpp sends two from 20 m apart).
  std::ostringstream t;
  t << "[run]\nt_end = 40.0\ndt_max = 0.01\noutput_interval = 1.0\n" << kSea2d
    << "[sea.waves]\nkind = \"regular\"\namplitude = 0.2\nwavelength = 50.0\n"
    << "[coupling]\nlaw = \"strong\"\nstiffness = 100.0\n"
    << "[forcing]\nocean_drag = 0.0\nair_drag = 0.0\n"
    << "[[floes.floe]]\nvertices = [[39.0, 45.0], [49.0, 45.0], [49.0, 55.0], [39.0, 55.0]]\nvelocity = [0.5, 0.0]\n"
    << "[[floes.floe]]\nvertices = [[49.2, 46.0], [59.2, 46.0], [59.2, 56.0], [49.2, 56.0]]\nvelocity = [-0.5, 0.0]\n";
  Simulation sim = make(t.str());
  const test::EnergyRun run = test::run_tracking_energy(sim, 40.0);
  CHECK(sim.collision_stats().lcps > 0);
  CHECK(sim.collision_stats().failures == 0);
  CHECK(run.top < run.start * (1.0 + 1e-4));
  CHECK(energy(sim, "total") < run.start);
}

}  // TEST_SUITE
