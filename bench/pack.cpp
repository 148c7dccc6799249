// floesim_bench_pack [REPEATS] [MAX_FLOES]: time generate_pack (core/pack_generator.hpp)
// on named scenarios at 500, 2000 and 10000 floes; prints CSV on stdout.
// The box grows with N (side 100 sqrt(N) m) so the mean floe size stays the
// same. Kept: the minimum (and median) over REPEATS runs after a warm-up; the
// machine is shared, and the minimum is the figure least disturbed by others.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <vector>

#include "core/pack_generator.hpp"

using namespace floesim;

namespace {

struct Scenario {
  const char* name;
  double concentration;
  SizeDistribution sizes;
};

SizeDistribution power_law(double alpha, double ratio) {
  SizeDistribution s;
  s.kind = SizeDistribution::Kind::power_law;
  s.exponent = alpha;
  s.min_size = 1.0;
  s.max_size = ratio;
  return s;
}

}  // namespace

int main(int argc, char** argv) {
  const int repeats = argc > 1 ? std::max(1, std::atoi(argv[1])) : 5;
  const std::size_t max_floes = argc > 2 ? static_cast<std::size_t>(std::atol(argv[2])) : 10000;
  const std::vector<Scenario> scenarios = {
      {"uniform_c50", 0.5, {}},
      {"uniform_c90", 0.9, {}},
      {"power2.5_r20_c70", 0.7, power_law(2.5, 20.0)},
  };
  std::printf("scenario,floes,concentration,repeats,time_ms_min,time_ms_median,newton_iterations,"
              "achieved_concentration,max_area_error,min_gap_m,required_gap_m\n");
  for (std::size_t n : {std::size_t{500}, std::size_t{2000}, std::size_t{10000}}) {
    if (n > max_floes) break;
    for (const Scenario& sc : scenarios) {
      PackOptions o;
      o.floes = n;
      o.concentration = sc.concentration;
      o.width = o.height = 100.0 * std::sqrt(static_cast<double>(n));
      o.sizes = sc.sizes;
      o.seed = 1;
      GeneratedPack pack = generate_pack(o);  // warm-up
      std::vector<double> ms;
      for (int r = 0; r < repeats; ++r) {
        const auto start = std::chrono::steady_clock::now();
        pack = generate_pack(o);
        ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count());
      }
      std::sort(ms.begin(), ms.end());
      std::printf("%s,%zu,%.2f,%d,%.1f,%.1f,%zu,%.6f,%.1e,%.4g,%.4g\n", sc.name, n, sc.concentration, repeats,
                  ms.front(), ms[ms.size() / 2], pack.newton_iterations, pack.concentration, pack.max_area_error,
                  pack.min_gap, pack.required_gap);
      std::fflush(stdout);
    }
  }
  return 0;
}
