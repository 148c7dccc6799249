// floesim_bench_sea_bem3d: 3D BEM basin set-up cost (time by part, memory)
// and step cost against the number of surface nodes, with the accuracy of
// the sloshing frequencies. Flat basin 1 m x 0.5 m x 0.2 m of lab water
// (rho 1000, sigma 0.0728), nx x nx/2 surface cells; the accuracy column is
// the worst relative error of modes (1,0), (0,1), (1,1) against
// omega^2 = (g k + sigma k^3 / rho) tanh(k H).
// Peak memory is the process's maximum resident set (sizes run in increasing
// order, so it is the largest set-up's). A step: bench/dense_sea_step.hpp.
// CSV on stdout.
//
// modes: 0 keeps all of them (the dense eigenproblem), n > 0 the n lowest
// ([sea] bem_modes, Lanczos).
//
// usage: floesim_bench_sea_bem3d [max_nx = 48] [repeats = 20] [first_nx = 8] [modes = 0] [step_nx = 8]

#include <sys/resource.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <numbers>
#include <vector>

#include "fluid/bem3d.hpp"
#include "bench/dense_sea_step.hpp"
#include "fluid/waves.hpp"
#include "tests/fluid/sea_cases.hpp"

using namespace floesim;
using namespace floesim::fluid;

namespace {

double mode_frequency(Bem3dSea& sea, int m, int n) {
  const SurfaceGrid& g = sea.grid();
  std::vector<double> eta(g.size()), zero(g.size(), 0.0);
  for (int j = 0; j < g.ny; ++j)
    for (int i = 0; i < g.nx; ++i)
      eta[static_cast<std::size_t>(j * g.nx + i)] = std::cos(m * std::numbers::pi * g.x(i) / g.lx) *
                                                    std::cos(n * std::numbers::pi * g.y(j) / g.ly);
  sea.set_surface(eta, zero);
  const auto q = sea.modes().q();
  std::size_t best = 0;
  for (std::size_t k = 0; k < q.size(); ++k)
    if (std::abs(q[k]) > std::abs(q[best])) best = k;
  return sea.frequencies()[best];
}

}  // namespace

int main(int argc, char** argv) {
  const int max_nx = argc > 1 ? std::atoi(argv[1]) : 48;
  const int repeats = argc > 2 ? std::atoi(argv[2]) : 20;
  const int first_nx = argc > 3 ? std::atoi(argv[3]) : 8;
  const int modes = argc > 4 ? std::atoi(argv[4]) : 0;
  const int step_nx = argc > 5 ? std::atoi(argv[5]) : 8;
  std::printf("nx,ny,surface_nodes,modes,panels,setup_s,assemble_s,solve_s,modes_s,matrix_mb,peak_rss_mb,step_us,"
              "worst_error_10_01_11\n");
  for (int nx = first_nx; nx <= max_nx; nx += nx < 16 ? 4 : step_nx) {
    SeaParams p = cases::lab_tank_bem(nx, 1.0, 0.2);
    p.dims = 2;
    p.size = {1.0, 0.5};
    p.cells = {nx, nx / 2};
    p.bem_modes = modes;
    Bem3dSea sea(p);  // each size is a cache miss: a fresh set-up
    const Dispersion d = Dispersion::of(p);
    double worst = 0.0;
    for (auto [m, n] : {std::pair{1, 0}, std::pair{0, 1}, std::pair{1, 1}}) {
      const double k = std::numbers::pi * std::hypot(m / 1.0, n / 0.5);
      worst = std::max(worst, std::abs(mode_frequency(sea, m, n) / d.omega(k) - 1.0));
    }
    const double best = bench::best_step_us(sea, repeats);
    rusage u{};
    getrusage(RUSAGE_SELF, &u);
    const auto& c = sea.setup_cost();
    std::printf("%d,%d,%zu,%zu,%d,%.3f,%.3f,%.3f,%.3f,%.1f,%.1f,%.1f,%.3e\n", nx, nx / 2, sea.grid().size(), sea.frequencies().size(), sea.panels(),
                c.seconds, c.assemble, c.solve, c.modes, c.bytes / 1e6, static_cast<double>(u.ru_maxrss) / 1024.0, best, worst);
    std::fflush(stdout);
  }
  return 0;
}
