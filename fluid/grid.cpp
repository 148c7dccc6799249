#include "fluid/grid.hpp"

#include <algorithm>
#include <array>
#include <cmath>

namespace floesim::fluid {

namespace {

// Cubic Lagrange weights for the nodes -1, 0, 1, 2 at offset t in [0, 1).
std::array<double, 4> cubic_weights(double t) {
  return {-t * (t - 1.0) * (t - 2.0) / 6.0, (t + 1.0) * (t - 1.0) * (t - 2.0) / 2.0,
          -(t + 1.0) * t * (t - 2.0) / 2.0, (t + 1.0) * t * (t - 1.0) / 6.0};
}

struct Stencil {
  std::array<int, 4> index;
  std::array<double, 4> weight;  // includes the reflection sign
};

// Stencil along one axis of n cells of width h; `walls` reflects at 0 and n h.
Stencil stencil(double pos, double h, int n, bool walls, double odd_sign) {
  if (walls) pos = std::clamp(pos, 0.0, n * h);
  const double xi = pos / h - 0.5;
  const double base = std::floor(xi);
  const auto w = cubic_weights(xi - base);
  const int i0 = static_cast<int>(base) - 1;
  Stencil s{};
  for (int m = 0; m < 4; ++m) {
    int i = i0 + m;
    double sign = 1.0;
    if (walls) {
      // Cell-centred reflection: ghost -1 mirrors 0, ghost n mirrors n - 1.
      while (i < 0 || i >= n) {
        if (i < 0) i = -1 - i;
        if (i >= n) i = 2 * n - 1 - i;
        sign *= odd_sign;
      }
    } else {
      i = ((i % n) + n) % n;
    }
    s.index[m] = i;
    s.weight[m] = sign * w[m];
  }
  return s;
}

}  // namespace

double interpolate(const SurfaceGrid& grid, std::span<const double> field, double x, double y,
                   Parity parity, Parity parity_y) {
  const bool walls = grid.edge == GridEdge::wall;
  const double odd = parity == Parity::odd ? -1.0 : 1.0;
  const Stencil sx = stencil(x, grid.dx(), grid.nx, walls, odd);
  if (grid.dims == 1 || grid.ny == 1) {
    double v = 0.0;
    for (int m = 0; m < 4; ++m) v += sx.weight[m] * field[sx.index[m]];
    return v;
  }
  const Stencil sy = stencil(y, grid.dy(), grid.ny, walls, parity_y == Parity::odd ? -1.0 : 1.0);
  double v = 0.0;
  for (int a = 0; a < 4; ++a) {
    const std::size_t row = static_cast<std::size_t>(sy.index[a]) * grid.nx;
    double vx = 0.0;
    for (int m = 0; m < 4; ++m) vx += sx.weight[m] * field[row + sx.index[m]];
    v += sy.weight[a] * vx;
  }
  return v;
}

}  // namespace floesim::fluid
