#include "coupling/footprint.hpp"

#include <algorithm>
#include <cmath>

namespace floesim {

// Area pieces by edge accumulation (Green's theorem per cell).
//
// For a counter-clockwise simple polygon P (convex or not), the vertical
// section of P at abscissa x is a union of intervals whose tops lie on edges
// running in -x and whose bottoms on edges running in +x. The measure of that
// section inside the row [Y_j, Y_j + dy] is therefore
//     sum over edges crossing x of  -sign(dx_e) clamp(y_e(x) - Y_j, 0, dy),
// and integrating over the column [X_i, X_i + dx] gives the area of P ∩ cell
// (i, j) as a sum of edge integrals, signed by the edge's direction:
//     a_ij = -sum_e ∫_{e ∩ column i} clamp(y - Y_j, 0, dy) dx,
// with the first moments the same way (x clamp(...) for ∫∫ x, and
// (clamp(y, Y_j, Y_j + dy)^2 - Y_j^2) / 2 for ∫∫ y). Each edge is split where
// it crosses grid lines, so every sub-segment lies in one cell (i, k); there
// clamp(...) is y - Y_k for row j = k, dy for every row j < k (the sub-segment
// is above it) and 0 above. The rows below are reached through one "carry" per
// cell, summed down each column. The sums are exact up to round-off, for any
// polygon, with work proportional to the sub-segments plus the cells of the
// bounding box (no clipping of polygons per cell).

namespace {

int wrap(int i, int n) { return ((i % n) + n) % n; }

constexpr double kSixth = 1.0 / 6.0;

struct Scratch {
  std::vector<Vec2> poly;
  std::vector<double> ts;
  // Per cell of the floe's bounding box, row-major (local column fastest):
  // direct sums, the carries to the rows below, and the piece made there.
  std::vector<double> area, mx, my, carry_area, carry_mx;
  std::vector<std::ptrdiff_t> piece;
  std::vector<std::uint32_t> edge_local;  // local cell of each of this floe's edge pieces
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
  out.edge_piece.clear();
  const double dx = grid.dx(), dy = grid.dy(), inv_dx = 1.0 / dx, inv_dy = 1.0 / dy;
  const bool periodic = grid.edge == fluid::GridEdge::periodic;
  const bool two_d = grid.dims == 2;
  // A piece thinner than this (relative to a cell) is round-off from a vertex
  // lying on a grid line.
  const double tiny = 1e-12 * dx * (two_d ? dy : grid.ly);
  static thread_local Scratch scratch;
  Scratch& s = scratch;

  // Cell of column i, row j, or -1 outside a walled basin.
  auto cell_of = [&](int i, int j) -> std::int64_t {
    if (i >= 0 && i < grid.nx && j >= 0 && j < grid.ny) return static_cast<std::int64_t>(j) * grid.nx + i;
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
      // The bounding box in cells (all of the width when dims = 1: one row).
      const int i0 = static_cast<int>(std::floor((g.x() + lo.x()) / dx));
      const int i1 = static_cast<int>(std::floor((g.x() + hi.x()) / dx));
      const int j0 = two_d ? static_cast<int>(std::floor((g.y() + lo.y()) / dy)) : 0;
      const int j1 = two_d ? static_cast<int>(std::floor((g.y() + hi.y()) / dy)) : 0;
      const int w = i1 - i0 + 1, h = j1 - j0 + 1;
      const std::size_t nloc = static_cast<std::size_t>(w) * static_cast<std::size_t>(h);
      for (auto* v : {&s.area, &s.mx, &s.my, &s.carry_area, &s.carry_mx}) v->assign(nloc, 0.0);
      // Bottom of local row lj, relative to G (dims = 1: y = 0, any base works
      // since the edges in a column have zero net dx).
      auto row_base = [&](int lj) { return two_d ? (j0 + lj) * dy - g.y() : 0.0; };

      // Edges: split at grid lines; each sub-segment is an edge piece and adds
      // its integrals to its cell (direct) and to the rows below (carry).
      const std::size_t first_edge = out.edge_cell.size();
      s.edge_local.clear();
      const std::size_t nv = s.poly.size();
      for (std::size_t k = 0; k < nv; ++k) {
        const Vec2 a = s.poly[k], b = s.poly[(k + 1) % nv];
        const Vec2 e = b - a;
        s.ts.assign({0.0, 1.0});
        for (int axis = 0; axis < (two_d ? 2 : 1); ++axis) {
          if (e[axis] == 0.0) continue;
          const double step = axis == 0 ? dx : dy;
          const double o = axis == 0 ? g.x() : g.y();
          const double u0 = std::min(a[axis], b[axis]) + o, u1 = std::max(a[axis], b[axis]) + o;
          const double inv = 1.0 / e[axis];
          for (double line = std::ceil(u0 / step) * step; line < u1; line += step) {
            const double t = (line - o - a[axis]) * inv;
            if (t > 0.0 && t < 1.0) s.ts.push_back(t);
          }
        }
        std::sort(s.ts.begin(), s.ts.end());
        for (std::size_t m = 0; m + 1 < s.ts.size(); ++m) {
          if (s.ts[m + 1] - s.ts[m] <= 1e-14) continue;
          const Vec2 pa = a + s.ts[m] * e, pb = a + s.ts[m + 1] * e;
          const Vec2 mid = g + 0.5 * (pa + pb);
          const int ci = static_cast<int>(std::floor(mid.x() * inv_dx));
          const int cj = two_d ? static_cast<int>(std::floor(mid.y() * inv_dy)) : 0;
          const int li = std::clamp(ci - i0, 0, w - 1), lj = std::clamp(cj - j0, 0, h - 1);
          const std::size_t local = static_cast<std::size_t>(lj) * w + li;
          const double run = pb.x() - pa.x();
          if (run != 0.0) {
            const double base = row_base(lj);
            const double x0 = pa.x(), x1 = pb.x();
            const double y0 = pa.y() - base, y1 = pb.y() - base;  // height above the row's bottom
            s.area[local] -= run * 0.5 * (y0 + y1);
            s.mx[local] -= run * (2.0 * x0 * y0 + x0 * y1 + x1 * y0 + 2.0 * x1 * y1) * kSixth;
            s.my[local] -= run * ((y0 * y0 + y0 * y1 + y1 * y1) * kSixth + base * 0.5 * (y0 + y1));
            if (lj > 0) {
              s.carry_area[local] -= run * dy;
              s.carry_mx[local] -= run * dy * 0.5 * (x0 + x1);
            }
          }
          const std::int64_t c = cell_of(ci, cj);
          if (c < 0) continue;
          out.edge_cell.push_back(static_cast<std::uint32_t>(c));
          out.edge_a.push_back(pa);
          out.edge_b.push_back(pb);
          s.edge_local.push_back(static_cast<std::uint32_t>(local));
        }
      }
      // The carries, summed down each column: a full row j below the
      // sub-segments has area sum carry and y-moment that times its mid-height.
      if (h > 1) {
        for (int li = 0; li < w; ++li) {
          double above_area = 0.0, above_mx = 0.0;
          for (int lj = h - 1; lj >= 0; --lj) {
            const std::size_t local = static_cast<std::size_t>(lj) * w + li;
            s.area[local] += above_area;
            s.mx[local] += above_mx;
            s.my[local] += above_area * (row_base(lj) + 0.5 * dy);
            above_area += s.carry_area[local];
            above_mx += s.carry_mx[local];
          }
        }
      }
      // Area pieces in local row-major order, which is the grid's order unless
      // the box wraps around a periodic edge.
      const std::size_t first_piece = out.cell.size();
      s.piece.assign(nloc, -1);
      for (int lj = 0; lj < h; ++lj)
        for (int li = 0; li < w; ++li) {
          const std::size_t local = static_cast<std::size_t>(lj) * w + li;
          const double a = s.area[local];
          if (a <= tiny) continue;
          const std::int64_t c = cell_of(i0 + li, j0 + lj);
          if (c < 0) continue;
          s.piece[local] = static_cast<std::ptrdiff_t>(out.cell.size());
          out.cell.push_back(static_cast<std::uint32_t>(c));
          out.area.push_back(a);
          out.centroid.push_back(Vec2{s.mx[local], s.my[local]} / a);
        }
      const bool wraps = periodic && (i0 < 0 || i1 >= grid.nx || (two_d && (j0 < 0 || j1 >= grid.ny)));
      if (wraps) {
        // Sort this floe's pieces by cell (a floe larger than the periodic box
        // covers a cell twice: merge those).
        const std::size_t n = out.cell.size() - first_piece;
        std::vector<std::size_t>& order = s.order;
        order.resize(n);
        for (std::size_t k = 0; k < n; ++k) order[k] = first_piece + k;
        std::sort(order.begin(), order.end(), [&](std::size_t x, std::size_t y) { return out.cell[x] < out.cell[y]; });
        s.cells.clear();
        s.areas.clear();
        s.firsts.clear();
        for (std::size_t k : order) {
          if (!s.cells.empty() && s.cells.back() == out.cell[k]) {
            s.areas.back() += out.area[k];
            s.firsts.back() += out.area[k] * out.centroid[k];
          } else {
            s.cells.push_back(out.cell[k]);
            s.areas.push_back(out.area[k]);
            s.firsts.push_back(out.area[k] * out.centroid[k]);
          }
        }
        out.cell.resize(first_piece);
        out.area.resize(first_piece);
        out.centroid.resize(first_piece);
        for (std::size_t k = 0; k < s.cells.size(); ++k) {
          out.cell.push_back(s.cells[k]);
          out.area.push_back(s.areas[k]);
          out.centroid.push_back(s.firsts[k] / s.areas[k]);
        }
      }
      out.offsets.push_back(out.cell.size());
      // Each edge piece's area piece: through the local map, or by search
      // among the floe's pieces once they were sorted and merged.
      for (std::size_t k = 0; k < s.edge_local.size(); ++k)
        out.edge_piece.push_back(wraps ? out.find(f, out.edge_cell[first_edge + k]) : s.piece[s.edge_local[k]]);
    } else {
      out.offsets.push_back(out.cell.size());
    }
    out.edge_offsets.push_back(out.edge_cell.size());
  }
}

}  // namespace floesim
