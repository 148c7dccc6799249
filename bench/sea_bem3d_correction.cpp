// The cost of the static correction of a truncated 3D BEM sea ([sea]
// bem_static_correction, fluid/static_correction.hpp): its set-up (the sparse
// factorisation of a_sf) and, per implicit step, the midpoint step and the
// midpoint response (the penalty solve's G_sea, applied a few tens of times a
// step) with and without it, the two alternating in one run. Minimum over
// `repeats` after a warm-up, microseconds. Flat basin 1 m x 0.5 m x 0.2 m,
// nx x nx/2 cells, as bench/sea_bem3d.cpp.
//
// usage: floesim_bench_sea_bem3d_correction nx modes [repeats = 50]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <vector>

#include "fluid/bem3d.hpp"

using namespace floesim;
using namespace floesim::fluid;

namespace {

template <class F>
double best_us(F&& f, int repeats) {
  f();
  double best = 1e300;
  for (int r = 0; r < repeats; ++r) {
    const auto a = std::chrono::steady_clock::now();
    f();
    best = std::min(best, std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - a).count());
  }
  return best;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: %s nx modes [repeats = 50]\n", argv[0]);
    return 2;
  }
  const int nx = std::atoi(argv[1]), modes = std::atoi(argv[2]);
  const int repeats = argc > 3 ? std::atoi(argv[3]) : 50;
  SeaParams p;
  p.model = SeaModel::bem;
  p.dims = 2;
  p.size = {1.0, 0.5};
  p.cells = {nx, nx / 2};
  p.depth = 0.2;
  p.rho = 1000.0;
  p.sigma = 0.0728;
  p.bem_modes = modes;
  Bem3dSea plain(p);
  p.bem_static_correction = true;
  Bem3dSea corrected(p);  // the same cached set-up
  const std::size_t n = plain.grid().size();
  std::vector<double> pressure(n, 0.0), eta(n);
  for (std::size_t c = 0; c < n; c += 7) pressure[c] = 100.0;  // a scattered floe-like load
  double sink = 0.0;
  double step[2], response[2];
  Bem3dSea* seas[2] = {&plain, &corrected};
  for (int round = 0; round < 3; ++round)  // alternating, the best of each kept
    for (int s = 0; s < 2; ++s) {
      Sea& sea = *seas[s];
      const double a = best_us([&] {
        sea.midpoint_step(pressure, 0.01);
        sink += sea.elevation()[0];
      }, repeats);
      const double b = best_us([&] {
        sea.midpoint_response(pressure, 0.01, eta);
        sink += eta[0];
      }, repeats);
      step[s] = round == 0 ? a : std::min(step[s], a);
      response[s] = round == 0 ? b : std::min(response[s], b);
    }
  const DenseSetup::Cost& c = plain.setup_cost();
  std::printf("nx,ny,surface_nodes,modes,setup_s,correction_setup_s,step_us,step_corrected_us,response_us,"
              "response_corrected_us\n");
  std::printf("%d,%d,%zu,%d,%.3f,%.5f,%.1f,%.1f,%.1f,%.1f\n", nx, nx / 2, n, modes, c.seconds, c.correction, step[0],
              step[1], response[0], response[1]);
  if (sink == 12345.0) std::printf("#\n");
  return 0;
}
