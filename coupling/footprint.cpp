#include "coupling/footprint.hpp"

#include <algorithm>
#include <cmath>

namespace floesim {

namespace {

// Keeps the part of polygon `in` where sign * p[axis] <= sign * bound
// (sign = +1: below the line, -1: above it).
void clip(const std::vector<Vec2>& in, int axis, double bound, double sign, std::vector<Vec2>& out) {
  out.clear();
  const std::size_t n = in.size();
  if (n == 0) return;
  for (std::size_t k = 0; k < n; ++k) {
    const Vec2& p = in[k];
    const Vec2& q = in[(k + 1) % n];
    const double dp = sign * (p[axis] - bound), dq = sign * (q[axis] - bound);
    if (dp <= 0.0) out.push_back(p);
    if ((dp < 0.0 && dq > 0.0) || (dp > 0.0 && dq < 0.0)) {
      const double t = dp / (dp - dq);
      Vec2 x = p + t * (q - p);
      x[axis] = bound;  // exactly on the line
      out.push_back(x);
    }
  }
  if (out.size() < 3) out.clear();
}

// Area and first moments of a closed chain (Green's theorem).
void moments(const std::vector<Vec2>& v, double& area, Vec2& first) {
  area = 0.0;
  first = Vec2::Zero();
  for (std::size_t k = 0; k < v.size(); ++k) {
    const Vec2& p = v[k];
    const Vec2& q = v[(k + 1) % v.size()];
    const double c = p.x() * q.y() - q.x() * p.y();
    area += c;
    first += c * (p + q);
  }
  area *= 0.5;
  first /= 6.0;
}

int wrap(int i, int n) { return ((i % n) + n) % n; }

struct Scratch {
  std::vector<Vec2> poly, a, row, b, piece;
  std::vector<double> ts;
  std::vector<std::size_t> order;
  std::vector<std::uint32_t> cells;
  std::vector<double> areas;
  std::vector<Vec2> firsts;
};

}  // namespace

std::ptrdiff_t Footprints::find(std::size_t i, std::uint32_t c) const {
  const auto first = cell.begin() + static_cast<std::ptrdiff_t>(offsets[i]);
  const auto last = cell.begin() + static_cast<std::ptrdiff_t>(offsets[i + 1]);
  const auto it = std::lower_bound(first, last, c);
  return it != last && *it == c ? it - cell.begin() : -1;
}

void build_footprints(const Floes& floes, std::span<const std::uint8_t> include,
                      const fluid::SurfaceGrid& grid, Footprints& out) {
  out.offsets.assign(1, 0);
  out.cell.clear();
  out.area.clear();
  out.centroid.clear();
  out.edge_offsets.assign(1, 0);
  out.edge_cell.clear();
  out.edge_a.clear();
  out.edge_b.clear();
  const double dx = grid.dx(), dy = grid.dy();
  const bool periodic = grid.edge == fluid::GridEdge::periodic;
  const bool two_d = grid.dims == 2;
  // A piece thinner than this (relative to a cell) is round-off from a vertex
  // lying on a grid line.
  const double tiny = 1e-12 * dx * (two_d ? dy : grid.ly);
  static thread_local Scratch s;

  // Cell of column i, row j, or -1 outside a walled basin.
  auto cell_of = [&](int i, int j) -> std::int64_t {
    if (periodic) {
      i = wrap(i, grid.nx);
      j = two_d ? wrap(j, grid.ny) : 0;
    } else if (i < 0 || i >= grid.nx || (two_d && (j < 0 || j >= grid.ny))) {
      return -1;
    }
    return static_cast<std::int64_t>(j) * grid.nx + i;
  };

  for (std::size_t f = 0; f < floes.size(); ++f) {
    if (include[f]) {
      const FloeState& st = floes.state[f];
      const Vec2 g{st.x, st.y};
      s.poly.clear();
      Vec2 lo = Vec2::Constant(INFINITY), hi = Vec2::Constant(-INFINITY);
      for (const Vec2& p : floes.vertices(f)) {
        s.poly.push_back(rotate(p, st.yaw));
        lo = lo.cwiseMin(s.poly.back());
        hi = hi.cwiseMax(s.poly.back());
      }
      const std::size_t first_piece = out.cell.size();
      // Area pieces: rows (all of the width when dims = 1), then columns.
      const int i0 = static_cast<int>(std::floor((g.x() + lo.x()) / dx));
      const int i1 = static_cast<int>(std::floor((g.x() + hi.x()) / dx));
      const int j0 = two_d ? static_cast<int>(std::floor((g.y() + lo.y()) / dy)) : 0;
      const int j1 = two_d ? static_cast<int>(std::floor((g.y() + hi.y()) / dy)) : 0;
      for (int j = j0; j <= j1; ++j) {
        const std::vector<Vec2>* row = &s.poly;
        if (two_d) {
          clip(s.poly, 1, j * dy - g.y(), -1.0, s.a);
          clip(s.a, 1, (j + 1) * dy - g.y(), 1.0, s.row);
          if (s.row.empty()) continue;
          row = &s.row;
        }
        for (int i = i0; i <= i1; ++i) {
          clip(*row, 0, i * dx - g.x(), -1.0, s.b);
          clip(s.b, 0, (i + 1) * dx - g.x(), 1.0, s.piece);
          if (s.piece.empty()) continue;
          double a;
          Vec2 m;
          moments(s.piece, a, m);
          const std::int64_t c = cell_of(i, j);
          if (a <= tiny || c < 0) continue;
          out.cell.push_back(static_cast<std::uint32_t>(c));
          out.area.push_back(a);
          out.centroid.push_back(m / a);
        }
      }
      // Sort this floe's pieces by cell (a floe larger than the periodic box
      // would cover a cell twice: merge those).
      const std::size_t n = out.cell.size() - first_piece;
      std::vector<std::size_t>& order = s.order;
      order.resize(n);
      for (std::size_t k = 0; k < n; ++k) order[k] = first_piece + k;
      std::sort(order.begin(), order.end(), [&](std::size_t x, std::size_t y) { return out.cell[x] < out.cell[y]; });
      std::vector<std::uint32_t>& cells = s.cells;
      std::vector<double>& areas = s.areas;
      std::vector<Vec2>& firsts = s.firsts;
      cells.clear();
      areas.clear();
      firsts.clear();
      for (std::size_t k : order) {
        if (!cells.empty() && cells.back() == out.cell[k]) {
          areas.back() += out.area[k];
          firsts.back() += out.area[k] * out.centroid[k];
        } else {
          cells.push_back(out.cell[k]);
          areas.push_back(out.area[k]);
          firsts.push_back(out.area[k] * out.centroid[k]);
        }
      }
      out.cell.resize(first_piece);
      out.area.resize(first_piece);
      out.centroid.resize(first_piece);
      for (std::size_t k = 0; k < cells.size(); ++k) {
        out.cell.push_back(cells[k]);
        out.area.push_back(areas[k]);
        out.centroid.push_back(firsts[k] / areas[k]);
      }
      // Edge pieces: split each edge where it crosses a grid line.
      const std::size_t nv = s.poly.size();
      for (std::size_t k = 0; k < nv; ++k) {
        const Vec2 a = s.poly[k], b = s.poly[(k + 1) % nv];
        const Vec2 e = b - a;
        s.ts.assign({0.0, 1.0});
        for (int axis = 0; axis < (two_d ? 2 : 1); ++axis) {
          if (e[axis] == 0.0) continue;
          const double h = axis == 0 ? dx : dy;
          const double o = axis == 0 ? g.x() : g.y();
          const double u0 = std::min(a[axis], b[axis]) + o, u1 = std::max(a[axis], b[axis]) + o;
          for (double line = std::ceil(u0 / h) * h; line < u1; line += h) {
            const double t = (line - o - a[axis]) / e[axis];
            if (t > 0.0 && t < 1.0) s.ts.push_back(t);
          }
        }
        std::sort(s.ts.begin(), s.ts.end());
        for (std::size_t m = 0; m + 1 < s.ts.size(); ++m) {
          if (s.ts[m + 1] - s.ts[m] <= 1e-14) continue;
          const Vec2 pa = a + s.ts[m] * e, pb = a + s.ts[m + 1] * e;
          const Vec2 mid = g + 0.5 * (pa + pb);
          const std::int64_t c = cell_of(static_cast<int>(std::floor(mid.x() / dx)),
                                         two_d ? static_cast<int>(std::floor(mid.y() / dy)) : 0);
          if (c < 0) continue;
          out.edge_cell.push_back(static_cast<std::uint32_t>(c));
          out.edge_a.push_back(pa);
          out.edge_b.push_back(pb);
        }
      }
    }
    out.offsets.push_back(out.cell.size());
    out.edge_offsets.push_back(out.edge_cell.size());
  }
}

}  // namespace floesim
