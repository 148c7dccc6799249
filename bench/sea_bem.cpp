// floesim_bench_sea_bem: BEM basin set-up and step cost, and accuracy, against
// panel count. Rectangular lab tank L = 1 m, H = 0.1 m (the validation tank):
// the accuracy column is the worst relative error of the first 10 sloshing
// frequencies against omega_n^2 = (g k_n + sigma k_n^3 / rho) tanh(k_n H).
// A step: bench/dense_sea_step.hpp; the set-up is timed once (each size is built fresh).
// CSV on stdout.
//
// usage: floesim_bench_sea_bem [max_surface_panels = 800] [repeats = 50]

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <numbers>
#include <vector>

#include "fluid/bem.hpp"
#include "bench/dense_sea_step.hpp"
#include "fluid/waves.hpp"
#include "tests/fluid/sea_cases.hpp"

using namespace floesim;
using namespace floesim::fluid;

int main(int argc, char** argv) {
  const int max_ns = argc > 1 ? std::atoi(argv[1]) : 800;
  const int repeats = argc > 2 ? std::atoi(argv[2]) : 50;
  std::printf("surface_panels,panels,setup_s,step_us,worst_error_modes_1_10\n");
  for (int ns = 25; ns <= max_ns; ns *= 2) {
    const SeaParams p = cases::lab_tank_bem(ns);
    BemSea sea(p);  // each size is a cache miss: setup_seconds is a fresh set-up
    const Dispersion d = Dispersion::of(p);
    double worst = 0.0;
    for (int n = 1; n <= 10; ++n)
      worst = std::max(worst, std::abs(sea.frequencies()[n - 1] / d.omega(n * std::numbers::pi) - 1.0));
    const double best = bench::best_step_us(sea, repeats);
    std::printf("%d,%d,%.4f,%.2f,%.3e\n", ns, sea.panels(), sea.setup_seconds(), best, worst);
    std::fflush(stdout);
  }
  return 0;
}
