#include "coupling/footprint.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>

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

// Gauss–Legendre with 3 points on [0, 1]: exact for polynomials of degree 5.
constexpr double kGaussT[3] = {0.5 - 0.3872983346207417, 0.5, 0.5 + 0.3872983346207417};
constexpr double kGaussW[3] = {5.0 / 18.0, 8.0 / 18.0, 5.0 / 18.0};
constexpr double kUnit[3] = {1.0, 1.0, 1.0};

// The integrals along a floe's outline that go with one node (or cell): its
// edge piece, summed over the sub-segments in the cells around it.
struct EdgeSum {
  double length = 0.0, twist = 0.0;
  Vec2 normal = Vec2::Zero(), swept = Vec2::Zero();
  Eigen::Matrix2d first = Eigen::Matrix2d::Zero();
  bool any = false;
};

// Adds the sub-segment A -> B (relative to G) weighted by a kernel B that is
// linear in each coordinate along it, given by its values at the three Gauss
// points (1 for the cell kernel). The integrands are at most of degree 4
// along the segment, so the rule is exact. With n ds = (e_y, -e_x) dt and
// r x n ds = -(r . e) dt:
//     length = ∫ B |e| dt,  N = ∫ B n ds,  T = ∫ B (r x n) ds,
//     Q = ∫ B r n^T ds,     S = ∫ B r (r x n) ds.
// The sub-segment's Gauss points: positions r_g and r_g x n ds / dt.
struct SegmentPoints {
  Vec2 n, r[3];
  double rxn[3], length;
  SegmentPoints(const Vec2& a, const Vec2& b) {
    const Vec2 e = b - a;
    n = {e.y(), -e.x()};
    length = e.norm();
    for (int g = 0; g < 3; ++g) {
      r[g] = a + kGaussT[g] * e;
      rxn[g] = -r[g].dot(e);
    }
  }
};

void add_edge(EdgeSum& sum, const SegmentPoints& p, const double (&weight)[3]) {
  double twist = 0.0, wsum = 0.0;
  Vec2 first = Vec2::Zero(), swept = Vec2::Zero();
  for (int g = 0; g < 3; ++g) {
    const double w = kGaussW[g] * weight[g];
    wsum += w;
    first += w * p.r[g];
    twist += w * p.rxn[g];
    swept += (w * p.rxn[g]) * p.r[g];
  }
  sum.length += wsum * p.length;
  sum.normal += wsum * p.n;
  sum.twist += twist;
  sum.first += first * p.n.transpose();
  sum.swept += swept;
  sum.any = true;
}

void push_edge_piece(Footprints& out, std::uint32_t cell, std::ptrdiff_t piece, const EdgeSum& sum) {
  out.edge_cell.push_back(cell);
  out.edge_piece.push_back(piece);
  out.edge_length.push_back(sum.length);
  out.edge_normal.push_back(sum.normal);
  out.edge_twist.push_back(sum.twist);
  out.edge_first.push_back(sum.first);
  out.edge_swept.push_back(sum.swept);
}

// Splits the segment a -> b (relative to G) at the grid lines x = (k + shift)
// dx (and y likewise when two_d); returns the parameters, sorted, from 0 to 1.
void split_at_lines(const Vec2& a, const Vec2& b, const Vec2& g, double dx, double dy, double shift, bool two_d,
                    std::vector<double>& ts) {
  const Vec2 e = b - a;
  ts.assign({0.0, 1.0});
  for (int axis = 0; axis < (two_d ? 2 : 1); ++axis) {
    if (e[axis] == 0.0) continue;
    const double step = axis == 0 ? dx : dy;
    const double o = axis == 0 ? g.x() : g.y();
    const double u0 = std::min(a[axis], b[axis]) + o, u1 = std::max(a[axis], b[axis]) + o;
    const double inv = 1.0 / e[axis];
    for (double line = (std::ceil(u0 / step - shift) + shift) * step; line < u1; line += step) {
      const double t = (line - o - a[axis]) * inv;
      if (t > 0.0 && t < 1.0) ts.push_back(t);
    }
  }
  std::sort(ts.begin(), ts.end());
}

struct Scratch {
  std::vector<Vec2> poly;
  std::vector<double> ts;
  // Per cell of the floe's bounding box, row-major (local column fastest):
  // direct sums, the carries to the rows below, and the piece made there.
  std::vector<double> area, mx, my, carry_area, carry_mx;
  std::vector<std::ptrdiff_t> piece;
  std::vector<EdgeSum> edges;  // per local cell or node
  std::vector<std::size_t> order;
  std::vector<std::uint32_t> cells;
  std::vector<double> areas;
  std::vector<Vec2> firsts;
  // Tent kernel: per dual cell the moments m[p][q] = ∫∫ s^p t^q ds dt of the
  // floe's part (local coordinates s, t in [0, 1]) and the carries ∫ s^p ds.
  std::vector<std::array<double, 9>> moments;
  std::vector<std::array<double, 3>> carries;
  std::vector<double> node_area, node_fx, node_fy;
  std::vector<std::uint32_t> column, row_start;  // nodes' wrapped columns, rows' first cells
  std::vector<std::uint8_t> touched;  // dual cells the outline crosses
};

// Floe f posed in world orientation relative to its centroid G (into poly),
// and the cells of its bounding box on the grid whose lines lie at
// (k + shift) dx, (k + shift) dy: columns i0..i1, rows j0..j1 (one row, 0,
// when dims = 1).
struct PosedBox {
  Vec2 g = Vec2::Zero();
  int i0 = 0, i1 = 0, j0 = 0, j1 = 0;
  int w() const { return i1 - i0 + 1; }
  int h() const { return j1 - j0 + 1; }
};
PosedBox pose(const Floes& floes, std::span<const FloePose> poses, std::size_t f, double dx, double dy, double shift,
              bool two_d, std::vector<Vec2>& poly) {
  const FloeState& st = floes.state[f];
  const FloePose at = poses.empty() ? FloePose{st.x, st.y, st.yaw} : poses[f];
  PosedBox b;
  b.g = {at.x, at.y};
  poly.clear();
  Vec2 lo = Vec2::Constant(INFINITY), hi = Vec2::Constant(-INFINITY);
  for (const Vec2& p : floes.vertices(f)) {
    poly.push_back(rotate(p, at.yaw));
    lo = lo.cwiseMin(poly.back());
    hi = hi.cwiseMax(poly.back());
  }
  b.i0 = static_cast<int>(std::floor((b.g.x() + lo.x()) / dx - shift));
  b.i1 = static_cast<int>(std::floor((b.g.x() + hi.x()) / dx - shift));
  b.j0 = two_d ? static_cast<int>(std::floor((b.g.y() + lo.y()) / dy - shift)) : 0;
  b.j1 = two_d ? static_cast<int>(std::floor((b.g.y() + hi.y()) / dy - shift)) : 0;
  return b;
}

// Calls fn(pa, pb, li, lj) for each sub-segment of the outline poly cut at
// the grid lines of pose(): its ends (relative to G) and the local column and
// row of its cell in the box.
template <class Fn>
void for_each_subsegment(const std::vector<Vec2>& poly, const PosedBox& b, double dx, double dy, double shift,
                         bool two_d, std::vector<double>& ts, Fn&& fn) {
  const double inv_dx = 1.0 / dx, inv_dy = 1.0 / dy;
  const std::size_t nv = poly.size();
  for (std::size_t k = 0; k < nv; ++k) {
    const Vec2 a = poly[k], e = poly[(k + 1) % nv] - a;
    split_at_lines(a, a + e, b.g, dx, dy, shift, two_d, ts);
    for (std::size_t m = 0; m + 1 < ts.size(); ++m) {
      if (ts[m + 1] - ts[m] <= 1e-14) continue;
      const Vec2 pa = a + ts[m] * e, pb = a + ts[m + 1] * e;
      const Vec2 mid = b.g + 0.5 * (pa + pb);
      const int ci = static_cast<int>(std::floor(mid.x() * inv_dx - shift));
      const int cj = two_d ? static_cast<int>(std::floor(mid.y() * inv_dy - shift)) : 0;
      fn(pa, pb, std::clamp(ci - b.i0, 0, b.w() - 1), std::clamp(cj - b.j0, 0, b.h() - 1));
    }
  }
}

// Sorts the pieces of the last floe (from first_piece) by cell and merges
// pieces of one cell: a floe whose box wraps around a periodic edge, or is
// larger than the box and covers a cell twice.
void merge_wrapped(Footprints& out, std::size_t first_piece, Scratch& s) {
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


// Tent kernel (see the header): the same edge accumulation on the dual grid,
// whose lines x = (I + 1/2) dx run through the cells' centres. In dual cell
// (I, J), with s = (x - x_I) / dx and t = (y - y_J) / dy in [0, 1], the four
// tents of its corners (the nodes I, I + 1 and J, J + 1, i.e. sea cells) are
// (1 - s)(1 - t), s (1 - t), (1 - s) t and s t. Every integral of a tent times
// 1, x or y over the floe's part of the dual cell is a combination of the
// moments m_pq = ∫∫ s^p t^q ds dt, p, q <= 2 (not p = q = 2). By Green's
// theorem, as for the areas (F_q(s, t) = t^(q+1) / (q+1) the t-antiderivative),
//     m_pq(own row) = -sum over sub-segments ∫ s^p F_q(s, t(s)) ds,
//     m_pq(row below) = -sum over the sub-segments above ∫ s^p ds / (q + 1),
// integrated exactly by 3-point Gauss–Legendre (degree <= 4). With dims = 1
// there is one row and no t in the tents: t is y relative to G (dy = 1).
void build_tent(const Floes& floes, std::span<const std::uint8_t> include, std::span<const FloePose> poses,
                const fluid::SurfaceGrid& grid, Footprints& out, Scratch& s, std::size_t first, std::size_t last) {
  const bool two_d = grid.dims == 2;
  const double dx = grid.dx(), dy = two_d ? grid.dy() : 1.0, inv_dx = 1.0 / dx, inv_dy = 1.0 / dy;
  const double area_element = dx * (two_d ? dy : 1.0);
  const double tiny = 1e-12 * dx * (two_d ? grid.dy() : grid.ly);
  for (std::size_t f = first; f < last; ++f) {
    if (!include[f]) {
      out.offsets.push_back(out.cell.size());
      out.edge_offsets.push_back(out.edge_cell.size());
      continue;
    }
    // Dual cells of the bounding box, and their corner nodes ((w + 1) x (h + 1); one row with dims = 1).
    const PosedBox box = pose(floes, poses, f, dx, dy, 0.5, two_d, s.poly);
    const Vec2 g = box.g;
    const int i0 = box.i0, i1 = box.i1, j0 = box.j0, j1 = box.j1, w = box.w(), h = box.h();
    const int nw = w + 1, nh = two_d ? h + 1 : 1;
    const std::size_t nloc = static_cast<std::size_t>(w) * static_cast<std::size_t>(h);
    s.moments.assign(nloc, {});
    s.touched.assign(nloc, 0);
    s.carries.assign(nloc, {});
    // Origin of dual cell (li, lj) relative to G (dims = 1: t = y, origin 0).
    auto origin = [&](int li, int lj) {
      return Vec2{(i0 + li + 0.5) * dx - g.x(), two_d ? (j0 + lj + 0.5) * dy - g.y() : 0.0};
    };

    const std::size_t nnodes = static_cast<std::size_t>(nw) * static_cast<std::size_t>(nh);
    s.edges.assign(nnodes, {});
    // The sea cell of node (ni, nj): row_start[nj] + column[ni] (wrapped).
    s.column.resize(static_cast<std::size_t>(nw));
    s.row_start.resize(static_cast<std::size_t>(nh));
    for (int ni = 0; ni < nw; ++ni) s.column[static_cast<std::size_t>(ni)] = static_cast<std::uint32_t>(wrap(i0 + ni, grid.nx));
    for (int nj = 0; nj < nh; ++nj)
      s.row_start[static_cast<std::size_t>(nj)] = static_cast<std::uint32_t>((two_d ? wrap(j0 + nj, grid.ny) : 0) * grid.nx);
    auto cell_of_node = [&](int ni, int nj) {
      return s.row_start[static_cast<std::size_t>(nj)] + s.column[static_cast<std::size_t>(ni)];
    };
    for_each_subsegment(s.poly, box, dx, dy, 0.5, two_d, s.ts, [&](const Vec2& pa, const Vec2& pb, int li, int lj) {
        const std::size_t local = static_cast<std::size_t>(lj) * w + li;
        const Vec2 o = origin(li, lj);
        const double sa = (pa.x() - o.x()) * inv_dx, sb = (pb.x() - o.x()) * inv_dx;
        const double ta = (pa.y() - o.y()) * inv_dy, tb = (pb.y() - o.y()) * inv_dy;
        double ss[3], tt[3];
        for (int q = 0; q < 3; ++q) {
          ss[q] = sa + kGaussT[q] * (sb - sa);
          tt[q] = ta + kGaussT[q] * (tb - ta);
        }
        const double run = sb - sa;
        s.touched[local] = 1;  // vertical sub-segments too: they split the cell
        if (run != 0.0) {
          std::array<double, 9>& mom = s.moments[local];
          std::array<double, 3>& carry = s.carries[local];
          for (int q = 0; q < 3; ++q) {
            const double wq = kGaussW[q] * run;
            const double s1 = ss[q], s2 = s1 * s1, t1 = tt[q], t2 = t1 * t1, t3 = t2 * t1;
            // m_pq -= ∫ s^p t^(q+1) / (q+1) ds
            mom[0] -= wq * t1;
            mom[1] -= wq * s1 * t1;
            mom[2] -= wq * s2 * t1;
            mom[3] -= wq * t2 * 0.5;
            mom[4] -= wq * s1 * t2 * 0.5;
            mom[5] -= wq * s2 * t2 * 0.5;
            mom[6] -= wq * t3 / 3.0;
            mom[7] -= wq * s1 * t3 / 3.0;
            if (lj > 0) {
              carry[0] -= wq;
              carry[1] -= wq * s1;
              carry[2] -= wq * s2;
            }
          }
        }
        // The outline's integrals, to each corner node of the dual cell.
        const SegmentPoints points(pa, pb);
        for (int beta = 0; beta < (two_d ? 2 : 1); ++beta)
          for (int alpha = 0; alpha < 2; ++alpha) {
            double weight[3];
            for (int q = 0; q < 3; ++q)
              weight[q] = (alpha ? ss[q] : 1.0 - ss[q]) * (two_d ? (beta ? tt[q] : 1.0 - tt[q]) : 1.0);
            if (weight[0] == 0.0 && weight[1] == 0.0 && weight[2] == 0.0) continue;
            add_edge(s.edges[static_cast<std::size_t>((lj + beta) * nw + li + alpha)], points, weight);
          }
    });
    // The carries, summed down each column: a full row below has m_pq =
    // (sum of the carries above)_p / (q + 1).
    if (h > 1) {
      for (int li = 0; li < w; ++li) {
        std::array<double, 3> above{};
        for (int lj = h - 1; lj >= 0; --lj) {
          const std::size_t local = static_cast<std::size_t>(lj) * w + li;
          std::array<double, 9>& mom = s.moments[local];
          if (s.touched[local]) {
            mom[0] += above[0];  // m_pq += above_p / (q + 1)
            mom[1] += above[1];
            mom[2] += above[2];
            mom[3] += 0.5 * above[0];
            mom[4] += 0.5 * above[1];
            mom[5] += 0.5 * above[2];
            mom[6] += above[0] / 3.0;
            mom[7] += above[1] / 3.0;
            for (int p = 0; p < 3; ++p) above[static_cast<std::size_t>(p)] += s.carries[local][static_cast<std::size_t>(p)];
          } else {
            mom[0] += above[0];  // full or empty: only m00 is read (below)
          }
        }
      }
    }
    // Nodes: each dual cell adds its four tents' integrals to its corners.
    // With the tent (c0 + c1 s)(d0 + d1 t), ∫∫ tent s^i t^j = sum of c d m.
    s.node_area.assign(nnodes, 0.0);
    s.node_fx.assign(nnodes, 0.0);
    s.node_fy.assign(nnodes, 0.0);
    for (int lj = 0; lj < h; ++lj)
      for (int li = 0; li < w; ++li) {
        const std::size_t local = static_cast<std::size_t>(lj) * w + li;
        const std::array<double, 9>& mom = s.moments[local];
        const Vec2 o = origin(li, lj);
        if (two_d && !s.touched[local]) {
          // No outline here: the dual cell is empty (m00 = 0) or full
          // (m_pq = 1 / ((p + 1)(q + 1))), where each corner's tent has
          // ∫∫ tent = 1/4 and ∫∫ tent s = 1/6 at s = 1, 1/12 at s = 0.
          if (mom[0] < 0.5) continue;
          for (int beta = 0; beta < 2; ++beta)
            for (int alpha = 0; alpha < 2; ++alpha) {
              const std::size_t node = static_cast<std::size_t>((lj + beta) * nw + li + alpha);
              s.node_area[node] += 0.25 * area_element;
              s.node_fx[node] += area_element * (0.25 * o.x() + dx * (alpha ? 1.0 / 6.0 : 1.0 / 12.0));
              s.node_fy[node] += area_element * (0.25 * o.y() + dy * (beta ? 1.0 / 6.0 : 1.0 / 12.0));
            }
          continue;
        }
        auto m = [&](int p, int q) { return mom[static_cast<std::size_t>(3 * q + p)]; };
        for (int beta = 0; beta < (two_d ? 2 : 1); ++beta)
          for (int alpha = 0; alpha < 2; ++alpha) {
            const double c0 = alpha ? 0.0 : 1.0, c1 = alpha ? 1.0 : -1.0;
            const double d0 = two_d ? (beta ? 0.0 : 1.0) : 1.0, d1 = two_d ? (beta ? 1.0 : -1.0) : 0.0;
            auto I = [&](int i, int j) {
              return c0 * d0 * m(i, j) + c1 * d0 * m(i + 1, j) + c0 * d1 * m(i, j + 1) + c1 * d1 * m(i + 1, j + 1);
            };
            const double i00 = I(0, 0), i10 = I(1, 0), i01 = I(0, 1);
            const std::size_t node = static_cast<std::size_t>((lj + beta) * nw + li + alpha);
            s.node_area[node] += area_element * i00;
            s.node_fx[node] += area_element * (o.x() * i00 + dx * i10);
            s.node_fy[node] += area_element * (o.y() * i00 + dy * i01);
          }
      }
    const std::size_t first_piece = out.cell.size();
    s.piece.assign(nnodes, -1);
    for (int nj = 0; nj < nh; ++nj)
      for (int ni = 0; ni < nw; ++ni) {
        const std::size_t node = static_cast<std::size_t>(nj) * nw + ni;
        const double a = s.node_area[node];
        if (a <= tiny) continue;
        s.piece[node] = static_cast<std::ptrdiff_t>(out.cell.size());
        out.cell.push_back(cell_of_node(ni, nj));
        out.area.push_back(a);
        out.centroid.push_back(Vec2{s.node_fx[node], s.node_fy[node]} / a);
      }
    const bool wraps = i0 < 0 || i1 + 1 >= grid.nx || (two_d && (j0 < 0 || j1 + 1 >= grid.ny));
    if (wraps) merge_wrapped(out, first_piece, s);
    out.offsets.push_back(out.cell.size());
    for (int nj = 0; nj < nh; ++nj)
      for (int ni = 0; ni < nw; ++ni) {
        const std::size_t node = static_cast<std::size_t>(nj) * nw + ni;
        if (!s.edges[node].any) continue;
        const std::uint32_t c = cell_of_node(ni, nj);
        push_edge_piece(out, c, wraps ? out.find(f - first, c) : s.piece[node], s.edges[node]);
      }
    out.edge_offsets.push_back(out.edge_cell.size());
  }
}

}  // namespace

std::ptrdiff_t Footprints::find(std::size_t i, std::uint32_t c) const {
  const auto first = cell.begin() + static_cast<std::ptrdiff_t>(offsets[i]);
  const auto last = cell.begin() + static_cast<std::ptrdiff_t>(offsets[i + 1]);
  const auto it = std::lower_bound(first, last, c);
  return it != last && *it == c ? it - cell.begin() : -1;
}

namespace {

void clear(Footprints& out) {
  out.offsets.assign(1, 0);
  out.cell.clear();
  out.area.clear();
  out.centroid.clear();
  out.edge_offsets.assign(1, 0);
  out.edge_cell.clear();
  out.edge_piece.clear();
  out.edge_length.clear();
  out.edge_normal.clear();
  out.edge_twist.clear();
  out.edge_first.clear();
  out.edge_swept.clear();
}

// Appends the footprints of part (floes after those already in out).
void append(Footprints& out, const Footprints& part) {
  const std::size_t pieces = out.cell.size(), edges = out.edge_cell.size();
  for (std::size_t k = 1; k < part.offsets.size(); ++k) out.offsets.push_back(pieces + part.offsets[k]);
  for (std::size_t k = 1; k < part.edge_offsets.size(); ++k) out.edge_offsets.push_back(edges + part.edge_offsets[k]);
  out.cell.insert(out.cell.end(), part.cell.begin(), part.cell.end());
  out.area.insert(out.area.end(), part.area.begin(), part.area.end());
  out.centroid.insert(out.centroid.end(), part.centroid.begin(), part.centroid.end());
  out.edge_cell.insert(out.edge_cell.end(), part.edge_cell.begin(), part.edge_cell.end());
  for (std::ptrdiff_t p : part.edge_piece)
    out.edge_piece.push_back(p < 0 ? p : p + static_cast<std::ptrdiff_t>(pieces));
  out.edge_length.insert(out.edge_length.end(), part.edge_length.begin(), part.edge_length.end());
  out.edge_normal.insert(out.edge_normal.end(), part.edge_normal.begin(), part.edge_normal.end());
  out.edge_twist.insert(out.edge_twist.end(), part.edge_twist.begin(), part.edge_twist.end());
  out.edge_first.insert(out.edge_first.end(), part.edge_first.begin(), part.edge_first.end());
  out.edge_swept.insert(out.edge_swept.end(), part.edge_swept.begin(), part.edge_swept.end());
}

void build_cells(const Floes& floes, std::span<const std::uint8_t> include, std::span<const FloePose> poses,
                 const fluid::SurfaceGrid& grid, Footprints& out, Scratch& s, std::size_t first, std::size_t last);

}  // namespace

void build_footprints(const Floes& floes, std::span<const std::uint8_t> include,
                      const fluid::SurfaceGrid& grid, Footprints& out, FootprintKernel kernel, int threads,
                      std::span<const FloePose> poses) {
  if (kernel == FootprintKernel::tent && grid.edge != fluid::GridEdge::periodic)
    throw std::invalid_argument("the tent footprint kernel needs a periodic grid");
  auto build = [&](Footprints& part, std::size_t first, std::size_t last) {
    static thread_local Scratch scratch;
    clear(part);
    if (kernel == FootprintKernel::tent) build_tent(floes, include, poses, grid, part, scratch, first, last);
    else build_cells(floes, include, poses, grid, part, scratch, first, last);
  };
  // Each floe's pieces depend on that floe alone: ranges of floes are built
  // on threads and joined in order, the same arrays whatever the thread count.
  const std::size_t n = floes.size();
  // (Fewer than 64 floes stay on one thread: not worth a parallel region.)
  const std::size_t chunks = threads > 1 && n >= 64 ? 4 * static_cast<std::size_t>(threads) : 1;
  if (chunks <= 1) return build(out, 0, n);
  // The caller's thread owns the parts (a thread_local seen from the workers
  // would be theirs).
  thread_local std::vector<Footprints> owned;
  owned.resize(chunks);
  std::vector<Footprints>& parts = owned;
  const std::ptrdiff_t count = static_cast<std::ptrdiff_t>(chunks);
#pragma omp parallel for num_threads(threads) schedule(dynamic, 1)
  for (std::ptrdiff_t c = 0; c < count; ++c) {
    const auto k = static_cast<std::size_t>(c);
    build(parts[k], n * k / chunks, n * (k + 1) / chunks);
  }
  clear(out);
  for (const Footprints& part : parts) append(out, part);
}

namespace {

// The cell kernel: the exact areas floe ∩ cell, for floes first..last-1.
void build_cells(const Floes& floes, std::span<const std::uint8_t> include, std::span<const FloePose> poses,
                 const fluid::SurfaceGrid& grid, Footprints& out, Scratch& s, std::size_t first, std::size_t last) {
  const double dx = grid.dx(), dy = grid.dy();
  const bool periodic = grid.edge == fluid::GridEdge::periodic;
  const bool two_d = grid.dims == 2;
  // A piece thinner than this (relative to a cell) is round-off from a vertex
  // lying on a grid line.
  const double tiny = 1e-12 * dx * (two_d ? dy : grid.ly);

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

  for (std::size_t f = first; f < last; ++f) {
    if (include[f]) {
      // The bounding box in cells (all of the width when dims = 1: one row).
      const PosedBox box = pose(floes, poses, f, dx, dy, 0.0, two_d, s.poly);
      const Vec2 g = box.g;
      const int i0 = box.i0, i1 = box.i1, j0 = box.j0, j1 = box.j1, w = box.w(), h = box.h();
      const std::size_t nloc = static_cast<std::size_t>(w) * static_cast<std::size_t>(h);
      for (auto* v : {&s.area, &s.mx, &s.my, &s.carry_area, &s.carry_mx}) v->assign(nloc, 0.0);
      // Bottom of local row lj, relative to G (dims = 1: y = 0, any base works
      // since the edges in a column have zero net dx).
      auto row_base = [&](int lj) { return two_d ? (j0 + lj) * dy - g.y() : 0.0; };

      // Edges: split at grid lines; each sub-segment is an edge piece and adds
      // its integrals to its cell (direct) and to the rows below (carry).
      s.edges.assign(nloc, {});
      for_each_subsegment(s.poly, box, dx, dy, 0.0, two_d, s.ts, [&](const Vec2& pa, const Vec2& pb, int li, int lj) {
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
          add_edge(s.edges[local], SegmentPoints(pa, pb), kUnit);
      });
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
        merge_wrapped(out, first_piece, s);
      }
      out.offsets.push_back(out.cell.size());
      // One edge piece per cell the outline crosses. Its area piece: through
      // the local map, or by search among the floe's pieces once they were
      // sorted and merged.
      for (int lj = 0; lj < h; ++lj)
        for (int li = 0; li < w; ++li) {
          const std::size_t local = static_cast<std::size_t>(lj) * w + li;
          if (!s.edges[local].any) continue;
          const std::int64_t c = cell_of(i0 + li, j0 + lj);
          if (c < 0) continue;
          const auto cell = static_cast<std::uint32_t>(c);
          push_edge_piece(out, cell, wraps ? out.find(f - first, cell) : s.piece[local], s.edges[local]);
        }
    } else {
      out.offsets.push_back(out.cell.size());
    }
    out.edge_offsets.push_back(out.edge_cell.size());
  }
}

}  // namespace

}  // namespace floesim
