#pragma once
// Test helpers for the energy bookkeeping of a Simulation (its
// /diagnostics/energy columns, docs/coupling.md).
#include <doctest/doctest.h>

#include <algorithm>
#include <string>

#include "coupling/simulation.hpp"

namespace floesim::test {

// The energy column `name` (J) at the present state.
inline double energy(const Simulation& sim, const std::string& name) {
  const Energies e = sim.energies();
  for (std::size_t k = 0; k < e.names.size(); ++k)
    if (e.names[k] == name) return e.values[k];
  FAIL("no energy column " << name);
  return 0.0;
}

struct EnergyRun {
  double start = 0.0;  // total energy at the start (J)
  double top = 0.0;    // the highest total energy at any step's end (J)
};

// Steps sim to t_end, calling after_step(sim) after each step; returns the
// total energy at the start and the highest it reached.
template <class F>
EnergyRun run_tracking_energy(Simulation& sim, double t_end, F&& after_step) {
  EnergyRun r;
  r.start = r.top = energy(sim, "total");
  while (sim.time() < t_end) {
    sim.step(t_end);
    r.top = std::max(r.top, energy(sim, "total"));
    after_step(sim);
  }
  return r;
}
inline EnergyRun run_tracking_energy(Simulation& sim, double t_end) {
  return run_tracking_energy(sim, t_end, [](const Simulation&) {});
}

}  // namespace floesim::test
