#pragma once
// The step of the BEM seas' benches (bench/sea_bem.cpp, bench/sea_bem3d.cpp):
// kick + flow + elevation + kick with a fixed non-uniform pressure, as the
// coupling drives a sea; the minimum over `repeats` after one warm-up step
// (the machine is shared), in microseconds.

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <vector>

#include "fluid/sea.hpp"

namespace floesim::bench {

inline double best_step_us(fluid::Sea& sea, int repeats) {
  using clock_type = std::chrono::steady_clock;
  std::vector<double> p0(sea.grid().size(), 10.0), p1(sea.grid().size(), -10.0);
  p0[0] = 50.0;
  double sink = 0.0;
  auto step = [&] {
    sea.kick(p0, 0.005);
    sea.flow(0.01);
    sink += sea.elevation()[0];
    sea.kick(p1, 0.005);
  };
  step();
  double best = 1e300;
  for (int r = 0; r < repeats; ++r) {
    const auto a = clock_type::now();
    step();
    best = std::min(best, std::chrono::duration<double, std::micro>(clock_type::now() - a).count());
  }
  if (sink == 12345.0) std::printf("#\n");  // keeps the elevation from being optimised away
  return best;
}

}  // namespace floesim::bench
