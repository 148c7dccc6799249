// The floe's edge on the sea grid (coupling/floe_sea.hpp, "Partly covered
// cells"): floating depth against Archimedes as the cells refine, the energy
// landscape of a floe translated across a cell (cogging), and the two slow
// motions the cogging used to stop: two floes sent at each other, and a floe
// drifting in the wind. Each test names its analytic reference.
#include <doctest/doctest.h>

#include <cmath>
#include <sstream>
#include <string>

#include "coupling/simulation.hpp"
#include "sim_energy.hpp"

using namespace floesim;
using floesim::test::energy;

TEST_SUITE_BEGIN("coupling");

namespace {

constexpr double kDraft = 917.0 / 1025.0;  // rho_i h / rho_w for h = 1 m

Simulation make(const std::string& text) { return Simulation(build_scenario(parse_config(text, "subcell.toml", "."))); }

std::string square(double x0, double y0, double L, const std::string& extra = "") {
  std::ostringstream t;
  t << "[[floes.floe]]\nvertices = [[" << x0 << ", " << y0 << "], [" << x0 + L << ", " << y0 << "], [" << x0 + L
    << ", " << y0 + L << "], [" << x0 << ", " << y0 + L << "]]\nthickness = 1.0\n"
    << extra;
  return t.str();
}

// A 100 m periodic box, depth 50 m, n x n cells, no drag, pure gravity.
std::string box(int n, double K, double dt_max = 0.01) {
  std::ostringstream t;
  t << "[run]\nt_end = 100.0\ndt_max = " << dt_max << "\noutput_interval = 1.0\n"
    << "[sea]\nmodel = \"spectral\"\ndims = 2\nsize = [100.0, 100.0]\ncells = [" << n << ", " << n
    << "]\ndepth = 50.0\nsigma = 0.0\n"
    << "[coupling]\nlaw = \"strong\"\nstiffness = " << K << "\n";
  return t.str();
}

// Depth of floe 0's bottom below the far-field water level (cell 0).
double depth(Simulation& sim) { return sim.sea_elevation()[0] - sim.floe_sea()->bottom(sim.floes(), 0); }

}  // namespace

TEST_CASE("floating depth converges to the Archimedes draft d (1 + 1/K) as the cells refine") {
  // Archimedes: a floe of density 917 and thickness 1 m floats with its bottom
  // d = 917 / 1025 m below the free level; the penalty's compliance adds
  // d / K (the penetration that carries the weight). A 20 m square set off the
  // grid lines (edges in the middle of cells), on 1.56, 0.78 and 0.39 m cells,
  // after 2 s of free motion from the static start. The sub-cell law makes the
  // static depth exact at any resolution (measured: relative errors -2.4e-5,
  // -3.0e-5, -2.8e-5; before it, -2.2%, -1.3%, -2.2% with the floe sliding
  // into the grid's cogging wells).
  const double K = 100.0, exact = kDraft * (1.0 + 1.0 / K);
  for (int n : {64, 128, 256}) {
    Simulation sim = make(box(n, K) + "[forcing]\nocean_drag = 0.0\nair_drag = 0.0\n" + square(40.3, 40.3, 20.0));
    while (sim.time() < 2.0) sim.step(2.0);
    const double err = depth(sim) / exact - 1.0;
    MESSAGE("dx = " << 100.0 / n << " m: depth / d (1 + 1/K) - 1 = " << err << ", heave " << sim.floes().state[0].heave);
    CHECK(std::abs(err) < 1e-4);
  }
  // Long-crested flume (dims = 1), the floe spanning its width, edges inside cells.
  for (int n : {100, 200, 400}) {
    std::ostringstream t;
    t << "[run]\ndt_max = 0.01\n[sea]\nmodel = \"spectral\"\ndims = 1\nsize = [100.0, 10.0]\ncells = [" << n
      << ", 1]\ndepth = 50.0\nsigma = 0.0\n[coupling]\nlaw = \"strong\"\nstiffness = " << K
      << "\n[forcing]\nocean_drag = 0.0\nair_drag = 0.0\n"
      << "[[floes.floe]]\nvertices = [[40.3, 0.0], [60.3, 0.0], [60.3, 10.0], [40.3, 10.0]]\nthickness = 1.0\n";
    Simulation sim = make(t.str());
    while (sim.time() < 2.0) sim.step(2.0);
    const double err = depth(sim) / exact - 1.0;
    MESSAGE("flume dx = " << 100.0 / n << " m: depth / d (1 + 1/K) - 1 = " << err);
    CHECK(std::abs(err) < 1e-4);
  }
}

TEST_CASE("cogging: the static energy of a floe translated across a cell is flat") {
  // Exact reference: a floe's hydrostatic energy does not depend on where it
  // sits, so the static minimum of (sea potential + penalty + weight), the
  // energy a slowly moving floe feels, must not vary as the floe is moved by
  // a fraction of a cell. Measured over 9 positions across one 1.56 m cell
  // (a 10 m floe, K = 100), relative to rho_w g d^2 L dx / 2, the size of the
  // edge cells' hydrostatic energy. Measured: 2.7e-14 (round-off); 0.38
  // with the law before the sub-cell weight.
  const double K = 100.0, dx = 100.0 / 64, L = 10.0;
  double lo = INFINITY, hi = -INFINITY;
  for (int k = 0; k <= 8; ++k) {
    const double s = dx * k / 8.0;
    Simulation sim = make(box(64, K) + "[forcing]\nocean_drag = 0.0\nair_drag = 0.0\n" + square(40.0 + s, 40.4, L));
    const double e = energy(sim, "sea_potential") + sim.floe_sea()->penalty_energy() +
                     sim.floes().mass[0] * 9.81 * sim.floe_sea()->bottom(sim.floes(), 0);
    lo = std::min(lo, e);
    hi = std::max(hi, e);
  }
  const double scale = 0.5 * 1025.0 * 9.81 * kDraft * kDraft * L * dx;
  MESSAGE("static energy variation across a cell: " << hi - lo << " J = " << (hi - lo) / scale
                                                      << " x rho_w g d^2 L dx / 2");
  CHECK((hi - lo) < 1e-3 * scale);
}

TEST_CASE("two floes sent at each other from 20 m apart at 0.5 m/s meet on 1.56 m cells") {
  // Reference: free floes on a calm sea keep their momentum (no drag) and
  // would meet after 20 s. On the sea each first loses some speed to the
  // depression it has to set moving and the waves that start radiates
  // (0.5 -> 0.41 m/s in 2 s, then 0.44 m/s: docs/coupling.md); measured:
  // first contact at t = 23.0 s (31.9 s with the cell kernel, whose grid
  // wave resistance kept slowing them). Before the sub-cell law they stayed
  // trapped within 0.6 m of their start. Collisions
  // (e = 0.4) are the only dissipation: the total energy may not grow beyond
  // the splitting error (measured 1.3e-4 of it).
  Simulation sim = make(box(64, 100.0) + "[forcing]\nocean_drag = 0.0\nair_drag = 0.0\n" +
                        square(20.0, 45.0, 10.0, "velocity = [0.5, 0.0]\n") +
                        square(50.0, 45.5, 10.0, "velocity = [-0.5, 0.0]\n"));
  double first = -1.0;
  const test::EnergyRun run = test::run_tracking_energy(sim, 40.0, [&](const Simulation& s) {
    if (first < 0.0 && s.collision_stats().lcps > 0) first = s.time();
  });
  MESSAGE("first collision at t = " << first << " s (free flight: 20 s); x = " << sim.floes().state[0].x << ", "
                                    << sim.floes().state[1].x);
  CHECK(sim.collision_stats().lcps > 0);
  CHECK(first > 20.0);
  CHECK(first < 25.0);
  CHECK(run.top < run.start * (1.0 + 5e-4));
}

TEST_CASE("a floe in a steady wind reaches the free-drift speed, on a calm sea and in a swell") {
  // Quadratic drag (coupling/drift.hpp): steady state rho_a C_a U_a^2 =
  // rho_w C_w u^2, u = sqrt(rho_a C_a / (rho_w C_w)) U_a (the air drag does
  // not depend on the ice velocity; the ocean drag is relative to the incident
  // waves' orbital velocity, whose mean under a floe is 0 in linear waves).
  // Reached from rest as u tanh(t / tau), tau = m / (rho_w C_w u A) = 137 s.
  // Measured (docs/coupling.md, "Footprints"): 0.9995 u on the calm sea. Two
  // things held the floe back before, each caught by this test: the cell
  // kernel's footprint (a cell's load rate jumps as an edge enters it,
  // radiating grid waves: 0.84 u on these cells, 0.75 u on cells half as
  // wide), and drag relative to the sea's whole velocity under the floe,
  // which holds the return flow of the depression the floe pushes along
  // (0.89 u). The swell (1 cm, 100 m: mean orbital velocity 0 under a 10 m
  // floe) makes the run keep an incident sea, so the second is tested too.
  const double rho_a = 1.3, Ca = 1.7e-3, Cw = 0.05, Ua = 20.0;
  const double u = std::sqrt(rho_a * Ca / (1025.0 * Cw)) * Ua;
  std::ostringstream f;
  f << "[forcing]\nocean_drag = " << Cw << "\nair_drag = " << Ca << "\nair_density = " << rho_a << "\nwind = [" << Ua
    << ", 0.0]\n";
  std::string swell;
  SUBCASE("calm sea") {}
  SUBCASE("swell") { swell = "[sea.waves]\nkind = \"regular\"\namplitude = 0.01\nwavelength = 100.0\n"; }
  Simulation sim = make(box(64, 100.0) + swell + f.str() + square(40.3, 45.3, 10.0));
  double mean = 0.0;
  while (sim.time() < 1000.0) {
    const double dt = sim.step(1000.0);
    if (sim.time() > 600.0) mean += sim.floes().state[0].vx * dt / 400.0;
  }
  MESSAGE("mean drift speed over 600..1000 s: " << mean << " m/s = " << mean / u << " of the free drift " << u << " m/s");
  CHECK(mean == doctest::Approx(u).epsilon(0.01));
}

TEST_CASE("percussion on a sea: the pieces of a split float where their parent did, no cascade") {
  // examples/percussion.toml on a calm sea (K = 100): a hexagon strikes a
  // 50 m x 32 m floe, both split once, as without the sea (docs/fracture.md).
  // Reference: a split changes no energy but the collision's, so the total
  // energy may only fall. The pieces of a split must keep their parent's
  // reference bottom, which the floes' displaced water raises above 0 (here
  // by 0.18 m); set to -d (1 + 1/K) instead, they started 0.18 m deep in the
  // water: the penalty jumped from 1.6e5 J to 2.1e7 J at the split and the
  // pieces broke each other (528 splits by t = 13 s, measured).
  std::ostringstream t;
  t << "[run]\nt_end = 8.0\ndt_max = 0.1\noutput_interval = 1.0\n"
    << "[sea]\nmodel = \"spectral\"\ndims = 2\nsize = [128.0, 64.0]\ncells = [128, 64]\ndepth = 50.0\n"
    << "[coupling]\nlaw = \"strong\"\nstiffness = 100.0\n"
    << "[[floes.floe]]\nvertices = [[40, 16], [90, 16], [92, 36], [85, 48], [45, 46]]\nthickness = 1.0\n"
    << "[[floes.floe]]\nvertices = [[39.98, 28], [35.98, 34.9282], [27.98, 34.9282], [23.98, 28], [27.98, 21.0718], "
       "[35.98, 21.0718]]\nvelocity = [0.5, 0.0]\nthickness = 1.0\n"
    << "[contact]\nrestitution = 0.3\nfriction = 0.3\n"
    << "[fracture]\nenabled = true\ncriterion = \"stress\"\nstrength = 0.5e6\nyoung = 6.0e9\npoisson = 0.3\n"
    << "split = true\nmesh_size = 1.5\nduration = 0.01\n";
  Simulation sim = make(t.str());
  const test::EnergyRun run = test::run_tracking_energy(sim, 8.0);
  std::size_t alive = 0;
  for (std::size_t i = 0; i < sim.floes().size(); ++i) alive += std::isfinite(sim.floes().state[i].x) ? 1 : 0;
  MESSAGE("floes at the end: " << alive << ", largest total energy / initial - 1: " << run.top / run.start - 1.0);
  CHECK(alive == 4);  // each floe split once
  CHECK(run.top < run.start * (1.0 + 1e-4));
}

TEST_SUITE_END();
