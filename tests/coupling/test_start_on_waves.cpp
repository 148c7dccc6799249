// The start of a coupled run (coupling/floe_sea.hpp, "Start"): floes are put
// at rest on the sea's initial waves by the static problem, so at t = 0 the
// penalty holds exactly each floe's weight and moments, even where the waves
// curve under a floe more than the penalty's compliance draft / K.
#include <doctest/doctest.h>

#include <cmath>
#include <sstream>

#include "coupling/simulation.hpp"

using namespace floesim;

TEST_SUITE_BEGIN("coupling");

namespace {

// A square of side 16 m and a triangle on a regular wave of 40 m (the wave's
// curvature lifts the middle of the square by A (1 - cos(k 8 m)) = 0.48 A
// against its corners) or on a calm sea.
Simulation floes_on_wave(double amplitude, double stiffness) {
  std::ostringstream t;
  t << "[run]\ndt_max = 0.01\n"
    << "[sea]\nmodel = \"spectral\"\ndims = 2\nsize = [80.0, 80.0]\ncells = [64, 64]\ndepth = 30.0\n";
  if (amplitude > 0.0) t << "[sea.waves]\nkind = \"regular\"\namplitude = " << amplitude << "\nwavelength = 40.0\n";
  t << "[coupling]\nstiffness = " << stiffness << "\n"
    << "[[floes.floe]]\nvertices = [[10.0, 10.0], [26.0, 10.0], [26.0, 26.0], [10.0, 26.0]]\nthickness = 1.0\n"
    << "[[floes.floe]]\nvertices = [[45.0, 40.0], [62.0, 44.0], [50.0, 58.0]]\nthickness = 2.0\n";
  return Simulation(build_scenario(parse_config(t.str(), "start.toml", ".")));
}

}  // namespace

TEST_CASE("floes start at rest on the waves: the penalty holds their weight and moments at t = 0") {
  for (double K : {100.0, 1000.0}) {
    const Simulation calm = floes_on_wave(0.0, K), sim = floes_on_wave(0.6, K);
    const Floes& f = sim.floes();
    REQUIRE(sim.floe_sea() != nullptr);
    const auto loads = sim.floe_sea()->loads();
    for (std::size_t i = 0; i < f.size(); ++i) {
      const double weight = f.mass[i] * 9.81, size = std::sqrt(f.area[i]);
      MESSAGE("K = " << K << ", floe " << i << ": net vertical force " << loads[i].vertical[0] << " N, moments "
                     << loads[i].vertical[1] << ", " << loads[i].vertical[2] << " N m (weight " << weight << " N)");
      CHECK(std::abs(loads[i].vertical[0]) < 1e-8 * weight);
      CHECK(std::abs(loads[i].vertical[1]) < 1e-8 * weight * size);
      CHECK(std::abs(loads[i].vertical[2]) < 1e-8 * weight * size);
      // Heave is measured from the calm equilibrium: 0 on the calm sea, and
      // within the wave's amplitude on the waves.
      CHECK(std::abs(calm.floes().state[i].heave) < 1e-9);
      CHECK(std::abs(f.state[i].heave) <= 0.6);
    }
    // The spring holds the weight with about the calm sea's penetration
    // draft / K: the curvature the bottom cannot follow is taken by the water,
    // not by the spring (with the waves merely superposed on the calm start,
    // the spring would hold up to 0.48 A = 0.29 m of it over the square:
    // 1.5e6 J at K = 100, 1.2e7 J at K = 1000, measured).
    const double extra = sim.floe_sea()->penalty_energy() - calm.floe_sea()->penalty_energy();
    MESSAGE("K = " << K << ": penalty energy " << sim.floe_sea()->penalty_energy() << " J on the waves, "
                   << calm.floe_sea()->penalty_energy() << " J calm");
    CHECK(extra < 0.5 * calm.floe_sea()->penalty_energy() + 1e-3 * 0.5 * sim.floe_sea()->kappa() * 0.29 * 0.29 * 256.0);
  }
}

TEST_SUITE_END();
