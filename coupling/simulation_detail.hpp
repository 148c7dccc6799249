#pragma once
// What the files of Simulation share and no other unit needs
// (simulation.cpp: the step's phases; simulation_collide.cpp: the
// collisions, the advance and the detection; simulation_report.cpp: the
// sums and reports a caller reads).

#include <cstddef>
#include <cstdint>

#include "coupling/simulation.hpp"

namespace floesim::simulation_detail {

// Steps are never cut below this fraction of dt_max by the collision limit;
// when the limit asks for less, the step is taken at the floor and counted
// (the advance's sub-step floor, the overlap's halvings, the warning).
constexpr double kFloorFraction = 1e-6;

}  // namespace floesim::simulation_detail

namespace floesim {

template <class F>
void Simulation::for_owned(F&& f) const {
  // Any partition of the floes among the ranks gives the same exact sums;
  // the owners by place are the partition the state held by owner will have
  // (docs/parallel.md, "Exact sums"). They are a partition of the present
  // floes once assigned (drift, detection) and until a split adds a floe.
  const std::size_t n = scenario_.floes.size();
  if (comm_.serial()) {
    for (std::size_t i = 0; i < n; ++i) f(i);
  } else if (owners_.owner().size() == n) {
    for (const std::uint32_t i : owners_.mine()) f(std::size_t{i});
  } else {
    const parallel::Range r = comm_.share(n);
    for (std::size_t i = r.begin; i < r.end; ++i) f(i);
  }
}

}  // namespace floesim
