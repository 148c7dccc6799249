// floesim_bench_sea_bem: BEM basin set-up and step cost, and accuracy, against
// panel count. Rectangular lab tank L = 1 m, H = 0.1 m (the validation tank):
// the accuracy column is the worst relative error of the first 10 sloshing
// frequencies against omega_n^2 = (g k_n + sigma k_n^3 / rho) tanh(k_n H).
// A step is kick + flow + elevation + kick, minimum of `repeats` after a warm-up
// (shared machine); the set-up is timed once (each size is built fresh).
// CSV on stdout.
//
// usage: floesim_bench_sea_bem [max_surface_panels = 800] [repeats = 50]

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <numbers>
#include <vector>

#include "fluid/bem.hpp"
#include "fluid/waves.hpp"
#include "tests/fluid/sea_cases.hpp"

using namespace floesim;
using namespace floesim::fluid;
using clock_type = std::chrono::steady_clock;

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
    std::printf("%d,%d,%.4f,%.2f,%.3e\n", ns, sea.panels(), sea.setup_seconds(), best, worst);
    std::fflush(stdout);
    if (sink == 12345.0) std::printf("#\n");
  }
  return 0;
}
