// Footprints of floes on the sea grid (coupling/footprint.hpp): every area
// piece against an independent computation, the polygon clipped by its cell
// (Sutherland–Hodgman by the four half-planes; for a non-convex polygon the
// clipped chain may hold zero-width slivers, but its area and first moments
// by Green's theorem are exact), and the sums against the polygon's own
// integrals.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>
#include <random>
#include <stdexcept>

#include "core/floes.hpp"
#include "coupling/footprint.hpp"
#include "coupling/moving_footprint.hpp"

using namespace floesim;

TEST_SUITE_BEGIN("coupling");

namespace {

struct Piece {
  double area = 0.0;
  Vec2 first = Vec2::Zero();  // ∫∫ r dA, r relative to G
};

std::vector<Vec2> clip(const std::vector<Vec2>& in, int axis, double bound, double sign) {
  std::vector<Vec2> out;
  for (std::size_t k = 0; k < in.size(); ++k) {
    const Vec2& p = in[k];
    const Vec2& q = in[(k + 1) % in.size()];
    const double dp = sign * (p[axis] - bound), dq = sign * (q[axis] - bound);
    if (dp <= 0.0) out.push_back(p);
    if ((dp < 0.0 && dq > 0.0) || (dp > 0.0 && dq < 0.0)) out.push_back(p + dp / (dp - dq) * (q - p));
  }
  return out;
}

Piece green(const std::vector<Vec2>& v) {
  Piece m;
  for (std::size_t k = 0; k < v.size(); ++k) {
    const Vec2& p = v[k];
    const Vec2& q = v[(k + 1) % v.size()];
    const double c = cross(p, q);
    m.area += 0.5 * c;
    m.first += c * (p + q) / 6.0;
  }
  return m;
}

// Floe f's outline in world orientation relative to its centroid g, and its
// world bounding box.
struct Posed {
  Vec2 g = Vec2::Zero();
  std::vector<Vec2> poly;
  double lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY};
};
Posed pose(const Floes& floes, std::size_t f) {
  const FloeState& st = floes.state[f];
  Posed out;
  out.g = {st.x, st.y};
  for (const Vec2& p : floes.vertices(f)) out.poly.push_back(rotate(p, st.yaw));
  for (const Vec2& p : out.poly)
    for (int a = 0; a < 2; ++a) {
      out.lo[a] = std::min(out.lo[a], p[a] + out.g[a]);
      out.hi[a] = std::max(out.hi[a], p[a] + out.g[a]);
    }
  return out;
}

// Reference pieces of floe f by clipping, keyed by (wrapped) cell.
std::map<std::uint32_t, Piece> clipped_pieces(const Floes& floes, std::size_t f, const fluid::SurfaceGrid& grid) {
  const Posed posed = pose(floes, f);
  const Vec2& g = posed.g;
  const std::vector<Vec2>& poly = posed.poly;
  const double *lo = posed.lo, *hi = posed.hi;
  const bool two_d = grid.dims == 2;
  const double dx = grid.dx(), dy = grid.dy();
  std::map<std::uint32_t, Piece> out;
  for (int j = two_d ? static_cast<int>(std::floor(lo[1] / dy)) : 0;
       j <= (two_d ? static_cast<int>(std::floor(hi[1] / dy)) : 0); ++j)
    for (int i = static_cast<int>(std::floor(lo[0] / dx)); i <= static_cast<int>(std::floor(hi[0] / dx)); ++i) {
      std::vector<Vec2> piece = clip(clip(poly, 0, i * dx - g.x(), -1.0), 0, (i + 1) * dx - g.x(), 1.0);
      if (two_d) piece = clip(clip(piece, 1, j * dy - g.y(), -1.0), 1, (j + 1) * dy - g.y(), 1.0);
      if (piece.size() < 3) continue;
      const Piece m = green(piece);
      if (m.area <= 1e-12 * grid.cell_area()) continue;
      int ci = i, cj = j;
      if (grid.edge == fluid::GridEdge::periodic) {
        ci = ((i % grid.nx) + grid.nx) % grid.nx;
        cj = two_d ? ((j % grid.ny) + grid.ny) % grid.ny : 0;
      } else if (i < 0 || i >= grid.nx) {
        continue;
      }
      Piece& p = out[static_cast<std::uint32_t>(cj * grid.nx + ci)];
      p.area += m.area;
      p.first += m.first;
    }
  return out;
}

Floes make_floes(const std::vector<std::vector<Vec2>>& outlines) {
  Floes floes;
  for (const auto& v : outlines) {
    FloeInput in;
    in.vertices = v;
    floes.add(make_floe_shape(in), in);
  }
  return floes;
}

// A star-shaped non-convex outline with n points about the origin.
std::vector<Vec2> star(int n, double r_in, double r_out, double phase) {
  std::vector<Vec2> v;
  for (int k = 0; k < 2 * n; ++k) {
    const double t = phase + std::numbers::pi * k / n, r = k % 2 ? r_in : r_out;
    v.push_back({r * std::cos(t), r * std::sin(t)});
  }
  return v;
}

// The periodic test grid: 40 x 30 cells of 2 m x 1.5 m.
fluid::SurfaceGrid box_grid() {
  fluid::SurfaceGrid grid;
  grid.dims = 2;
  grid.nx = 40;
  grid.ny = 30;
  grid.lx = 80.0;
  grid.ly = 45.0;
  return grid;
}

// n floes of 3 to 15 m, in turn a non-convex star, an L and a regular
// 12-gon, and last a floe longer than the box (cells covered twice).
Floes mixed_floes(std::mt19937_64& rng, int n) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<std::vector<Vec2>> outlines;
  for (int k = 0; k < n; ++k) {
    const double r = 3.0 + 12.0 * u(rng);
    if (k % 3 == 0) outlines.push_back(star(5, 0.4 * r, r, u(rng)));
    else if (k % 3 == 1) outlines.push_back({{0, 0}, {r, 0}, {r, 0.3 * r}, {0.3 * r, 0.3 * r}, {0.3 * r, r}, {0, r}});
    else outlines.push_back(star(6, r, r, u(rng)));
  }
  outlines.push_back({{0, 0}, {100, 0}, {100, 10}, {0, 10}});
  return make_floes(outlines);
}

// Every floe at a random place and yaw in the grid's box.
void scatter(Floes& floes, const fluid::SurfaceGrid& grid, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (FloeState& s : floes.state) {
    s.x = grid.lx * u(rng);
    s.y = grid.ly * u(rng);
    s.yaw = 2.0 * std::numbers::pi * u(rng);
  }
}

void check_against_clipping(const Floes& floes, const fluid::SurfaceGrid& grid) {
  Footprints fp;
  const std::vector<std::uint8_t> include(floes.size(), 1);
  build_footprints(floes, include, grid, fp);
  REQUIRE(fp.floes() == floes.size());
  const double ca = grid.dims == 2 ? grid.cell_area() : grid.dx() * grid.ly;
  for (std::size_t f = 0; f < floes.size(); ++f) {
    const auto ref = clipped_pieces(floes, f, grid);
    CHECK(fp.offsets[f + 1] - fp.offsets[f] == ref.size());
    double area = 0.0;
    for (std::size_t k = fp.offsets[f]; k < fp.offsets[f + 1]; ++k) {
      if (k > fp.offsets[f]) CHECK(fp.cell[k] > fp.cell[k - 1]);  // sorted, one piece per cell
      const auto it = ref.find(fp.cell[k]);
      REQUIRE(it != ref.end());
      CHECK(std::abs(fp.area[k] - it->second.area) < 1e-10 * ca);
      const Vec2 centroid = it->second.first / it->second.area;
      CHECK((fp.centroid[k] - centroid).norm() < 1e-8 * std::sqrt(ca) * std::max(1.0, ca / it->second.area));
      area += fp.area[k];
    }
    // Cells outside a walled basin are dropped; otherwise the pieces tile the floe.
    if (grid.edge == fluid::GridEdge::periodic) CHECK(area == doctest::Approx(floes.area[f]).epsilon(1e-12));
    // Edge pieces: they run along the whole outline, and each names its area piece.
    double perimeter = 0.0, pieces = 0.0;
    const auto v = floes.vertices(f);
    for (std::size_t k = 0; k < v.size(); ++k) perimeter += (v[(k + 1) % v.size()] - v[k]).norm();
    for (std::size_t k = fp.edge_offsets[f]; k < fp.edge_offsets[f + 1]; ++k) {
      pieces += fp.edge_length[k];
      CHECK(fp.edge_piece[k] == fp.find(f, fp.edge_cell[k]));
    }
    if (grid.edge == fluid::GridEdge::periodic) CHECK(pieces == doctest::Approx(perimeter).epsilon(1e-12));
  }
}

}  // namespace

TEST_CASE("footprint pieces equal the polygon clipped by each cell, convex or not, across periodic edges") {
  const fluid::SurfaceGrid grid = box_grid();
  std::mt19937_64 rng(7);
  Floes floes = mixed_floes(rng, 12);
  for (int trial = 0; trial < 6; ++trial) {
    scatter(floes, grid, rng);  // near the edges too: pieces wrap
    if (trial == 0) {  // vertices exactly on grid lines
      floes.state[1].x = floes.state[1].y = 0.0;
      floes.state[1].yaw = 0.0;
    }
    check_against_clipping(floes, grid);
  }
}

TEST_CASE("footprint pieces on a long-crested sea and in a walled basin are strips, dropped outside the walls") {
  fluid::SurfaceGrid grid;
  grid.dims = 1;
  grid.nx = 50;
  grid.lx = 100.0;
  grid.ly = 10.0;
  Floes floes = make_floes({star(4, 3.0, 7.0, 0.3), {{0, 0}, {9, 0}, {9, 3}, {0, 3}}});
  floes.state[0].x = 50.3;
  floes.state[0].yaw = 0.7;
  floes.state[1].x = 98.0;  // over the far end
  floes.state[1].yaw = 0.2;
  SUBCASE("periodic") { check_against_clipping(floes, grid); }
  SUBCASE("walls") {
    grid.edge = fluid::GridEdge::wall;
    check_against_clipping(floes, grid);
  }
}

// ---- Tent kernel (coupling/footprint.hpp): each node's tent-weighted area
// and first moment against an independent computation, the polygon clipped by
// each dual cell (the square between four cell centres) and integrated with a
// degree-3 triangle rule over a fan (signed triangles, so non-convex clipped
// chains are fine): the tent times 1, x or y is a polynomial of degree 3 there.

namespace {

// ∫ f over the triangle (a, b, c), signed, exact for degree 3 (Strang–Fix:
// -27/48 at the centroid, 25/48 at the three points (3/5, 1/5, 1/5)).
template <class F>
double triangle_integral(const Vec2& a, const Vec2& b, const Vec2& c, const F& f) {
  const double area = 0.5 * cross(b - a, c - a);
  const Vec2 g = (a + b + c) / 3.0;
  const double sum = -27.0 / 48.0 * f(g) + 25.0 / 48.0 * (f(0.6 * a + 0.2 * b + 0.2 * c) +
                                                           f(0.2 * a + 0.6 * b + 0.2 * c) +
                                                           f(0.2 * a + 0.2 * b + 0.6 * c));
  return area * sum;
}

std::map<std::uint32_t, Piece> tent_pieces(const Floes& floes, std::size_t f, const fluid::SurfaceGrid& grid) {
  const Posed posed = pose(floes, f);
  const Vec2& g = posed.g;
  const std::vector<Vec2>& poly = posed.poly;
  const double *lo = posed.lo, *hi = posed.hi;
  const bool two_d = grid.dims == 2;
  const double dx = grid.dx(), dy = grid.dy();
  std::map<std::uint32_t, Piece> out;
  const int j_lo = two_d ? static_cast<int>(std::floor(lo[1] / dy - 0.5)) : 0;
  const int j_hi = two_d ? static_cast<int>(std::floor(hi[1] / dy - 0.5)) : 0;
  for (int J = j_lo; J <= j_hi; ++J)
    for (int I = static_cast<int>(std::floor(lo[0] / dx - 0.5)); I <= static_cast<int>(std::floor(hi[0] / dx - 0.5)); ++I) {
      const double X0 = (I + 0.5) * dx - g.x(), Y0 = (J + 0.5) * dy - g.y();
      std::vector<Vec2> piece = clip(clip(poly, 0, X0, -1.0), 0, X0 + dx, 1.0);
      if (two_d) piece = clip(clip(piece, 1, Y0, -1.0), 1, Y0 + dy, 1.0);
      if (piece.size() < 3) continue;
      for (int beta = 0; beta < (two_d ? 2 : 1); ++beta)
        for (int alpha = 0; alpha < 2; ++alpha) {
          auto tent = [&](const Vec2& r) {
            const double s = (r.x() - X0) / dx, t = (r.y() - Y0) / dy;
            return (alpha ? s : 1.0 - s) * (two_d ? (beta ? t : 1.0 - t) : 1.0);
          };
          Piece m;
          for (std::size_t k = 1; k + 1 < piece.size(); ++k) {
            const Vec2 &a = piece[0], &b = piece[k], &c = piece[k + 1];
            m.area += triangle_integral(a, b, c, tent);
            m.first.x() += triangle_integral(a, b, c, [&](const Vec2& r) { return tent(r) * r.x(); });
            m.first.y() += triangle_integral(a, b, c, [&](const Vec2& r) { return tent(r) * r.y(); });
          }
          const int ci = ((I + alpha) % grid.nx + grid.nx) % grid.nx;
          const int cj = two_d ? ((J + beta) % grid.ny + grid.ny) % grid.ny : 0;
          Piece& p = out[static_cast<std::uint32_t>(cj * grid.nx + ci)];
          p.area += m.area;
          p.first += m.first;
        }
    }
  return out;
}

void check_tent(const Floes& floes, const fluid::SurfaceGrid& grid) {
  Footprints fp;
  const std::vector<std::uint8_t> include(floes.size(), 1);
  build_footprints(floes, include, grid, fp, FootprintKernel::tent);
  REQUIRE(fp.floes() == floes.size());
  const double ca = grid.dims == 2 ? grid.cell_area() : grid.dx() * grid.ly;
  for (std::size_t f = 0; f < floes.size(); ++f) {
    const auto ref = tent_pieces(floes, f, grid);
    double area = 0.0;
    for (std::size_t k = fp.offsets[f]; k < fp.offsets[f + 1]; ++k) {
      if (k > fp.offsets[f]) CHECK(fp.cell[k] > fp.cell[k - 1]);  // sorted, one piece per node
      const auto it = ref.find(fp.cell[k]);
      REQUIRE(it != ref.end());
      CHECK(std::abs(fp.area[k] - it->second.area) < 1e-10 * ca);
      CHECK((fp.area[k] * fp.centroid[k] - it->second.first).norm() < 1e-9 * ca * std::sqrt(ca));
      area += fp.area[k];
    }
    for (const auto& [cell, p] : ref)  // no node left out
      if (p.area > 1e-9 * ca) CHECK(fp.find(f, cell) >= 0);
    // The tents are a partition of unity: the pieces sum to the floe's area,
    // the edge pieces' lengths to its perimeter, their normals to 0.
    CHECK(area == doctest::Approx(floes.area[f]).epsilon(1e-12));
    double perimeter = 0.0, pieces = 0.0;
    Vec2 normal = Vec2::Zero();
    const auto v = floes.vertices(f);
    for (std::size_t k = 0; k < v.size(); ++k) perimeter += (v[(k + 1) % v.size()] - v[k]).norm();
    for (std::size_t k = fp.edge_offsets[f]; k < fp.edge_offsets[f + 1]; ++k) {
      pieces += fp.edge_length[k];
      normal += fp.edge_normal[k];
      CHECK(fp.edge_piece[k] == fp.find(f, fp.edge_cell[k]));
    }
    CHECK(pieces == doctest::Approx(perimeter).epsilon(1e-12));
    CHECK(normal.norm() < 1e-10 * perimeter);
  }
}

}  // namespace

TEST_CASE("tent footprint: node weights and moments equal the tents integrated over the clipped floe") {
  const fluid::SurfaceGrid grid = box_grid();
  std::mt19937_64 rng(11);
  Floes floes = mixed_floes(rng, 9);
  for (int trial = 0; trial < 4; ++trial) {
    scatter(floes, grid, rng);
    if (trial == 0) {  // vertices exactly on dual grid lines (cell centres)
      floes.state[1].x = 1.0;
      floes.state[1].y = 0.75;
      floes.state[1].yaw = 0.0;
    }
    if (trial == 1) {  // edges along the grid's axes, inside dual cells: columns of cells the outline splits
      for (std::size_t f : {1, 4, 7}) floes.state[f].yaw = 0.0;
    }
    check_tent(floes, grid);
  }
  SUBCASE("long-crested") {
    fluid::SurfaceGrid strip;
    strip.dims = 1;
    strip.nx = 50;
    strip.lx = 100.0;
    strip.ly = 10.0;
    Floes f1 = make_floes({star(4, 3.0, 7.0, 0.3), {{0, 0}, {9, 0}, {9, 3}, {0, 3}}});
    f1.state[0].x = 50.3;
    f1.state[0].yaw = 0.7;
    f1.state[1].x = 98.0;  // across the periodic end
    f1.state[1].yaw = 0.2;
    check_tent(f1, strip);
  }
}

TEST_CASE("tent footprint: the edge integrals are the derivatives of the node weights and moments") {
  // Reynolds' transport theorem (coupling/footprint.hpp): moving the floe by
  // dG changes w_c by N . dG and m_c = ∫ B r by (Q - w_c I) dG; turning it by
  // dyaw changes w_c by T dyaw and m_c by S dyaw. Checked against central
  // differences of the weights themselves (h = 1e-5 m, 1e-6 rad).
  fluid::SurfaceGrid grid;
  grid.dims = 2;
  grid.nx = 32;
  grid.ny = 32;
  grid.lx = 64.0;
  grid.ly = 48.0;  // dx = 2, dy = 1.5
  Floes floes = make_floes({star(5, 4.0, 9.0, 0.2)});
  floes.state[0].x = 20.37;
  floes.state[0].y = 17.81;
  floes.state[0].yaw = 0.43;
  const std::vector<std::uint8_t> include{1};
  Footprints fp;
  build_footprints(floes, include, grid, fp, FootprintKernel::tent);
  struct Sum {
    Vec2 N = Vec2::Zero();
    double T = 0.0;
    Eigen::Matrix2d Q = Eigen::Matrix2d::Zero();
    Vec2 S = Vec2::Zero();
  };
  std::map<std::uint32_t, Sum> edges;
  for (std::size_t k = 0; k < fp.edge_cell.size(); ++k) {
    Sum& e = edges[fp.edge_cell[k]];
    e.N += fp.edge_normal[k];
    e.T += fp.edge_twist[k];
    e.Q += fp.edge_first[k];
    e.S += fp.edge_swept[k];
  }
  // Weight and first moment of node c (0 when absent) for a displaced floe.
  auto moved = [&](double ddx, double ddy, double dyaw) {
    Floes f2 = floes;
    f2.state[0].x += ddx;
    f2.state[0].y += ddy;
    f2.state[0].yaw += dyaw;
    Footprints out;
    build_footprints(f2, include, grid, out, FootprintKernel::tent);
    std::map<std::uint32_t, std::pair<double, Vec2>> m;
    for (std::size_t k = 0; k < out.cell.size(); ++k) m[out.cell[k]] = {out.area[k], out.area[k] * out.centroid[k]};
    return m;
  };
  const double h = 1e-5, hr = 1e-6;
  const auto xp = moved(h, 0, 0), xm = moved(-h, 0, 0), yp = moved(0, h, 0), ym = moved(0, -h, 0);
  const auto rp = moved(0, 0, hr), rm = moved(0, 0, -hr);
  auto get = [](const auto& m, std::uint32_t c) {
    const auto it = m.find(c);
    return it == m.end() ? std::pair<double, Vec2>{0.0, Vec2::Zero()} : it->second;
  };
  REQUIRE(edges.size() > 20);
  const double scale = grid.dx() * grid.dy();
  for (const auto& [c, e] : edges) {
    const std::ptrdiff_t k = fp.find(0, c);
    const double w0 = k >= 0 ? fp.area[static_cast<std::size_t>(k)] : 0.0;
    const Vec2 dw_dG{(get(xp, c).first - get(xm, c).first) / (2 * h), (get(yp, c).first - get(ym, c).first) / (2 * h)};
    CHECK((dw_dG - e.N).norm() < 1e-5 * grid.dx());
    CHECK(std::abs((get(rp, c).first - get(rm, c).first) / (2 * hr) - e.T) < 1e-4 * scale);
    const Vec2 dm_dx = (get(xp, c).second - get(xm, c).second) / (2 * h);
    const Vec2 dm_dy = (get(yp, c).second - get(ym, c).second) / (2 * h);
    CHECK((dm_dx - (e.Q.col(0) - w0 * Vec2::UnitX())).norm() < 1e-4 * scale);
    CHECK((dm_dy - (e.Q.col(1) - w0 * Vec2::UnitY())).norm() < 1e-4 * scale);
    CHECK(((get(rp, c).second - get(rm, c).second) / (2 * hr) - e.S).norm() < 1e-3 * scale * grid.dx());
  }
}

TEST_CASE("tent footprint needs a periodic grid") {
  fluid::SurfaceGrid grid;
  grid.dims = 1;
  grid.nx = 50;
  grid.lx = 100.0;
  grid.ly = 10.0;
  grid.edge = fluid::GridEdge::wall;
  Floes floes = make_floes({{{0, 0}, {9, 0}, {9, 3}, {0, 3}}});
  floes.state[0].x = 50.0;
  Footprints fp;
  const std::vector<std::uint8_t> include{1};
  CHECK_THROWS_AS(build_footprints(floes, include, grid, fp, FootprintKernel::tent), std::invalid_argument);
}

namespace {

// Largest |a_c| difference between moved and freshly built pieces, over
// the cells of both (a cell in one only counts its whole area), and the
// largest first-moment difference |m_c - m'_c| on shared cells.
struct PieceError {
  double area = 0.0, moment = 0.0;
};
PieceError piece_error(const Footprints& a, const Footprints& b) {
  PieceError e;
  for (std::size_t f = 0; f < a.floes(); ++f) {
    std::map<std::uint32_t, std::pair<double, Vec2>> ref;
    for (std::size_t k = b.offsets[f]; k < b.offsets[f + 1]; ++k) ref[b.cell[k]] = {b.area[k], b.area[k] * b.centroid[k]};
    for (std::size_t k = a.offsets[f]; k < a.offsets[f + 1]; ++k) {
      const auto it = ref.find(a.cell[k]);
      const double other = it == ref.end() ? 0.0 : it->second.first;
      e.area = std::max(e.area, std::abs(a.area[k] - other));
      if (it != ref.end()) {
        e.moment = std::max(e.moment, (a.area[k] * a.centroid[k] - it->second.second).norm());
        ref.erase(it);
      }
    }
    for (const auto& [cell, piece] : ref) e.area = std::max(e.area, piece.first);
  }
  return e;
}

std::vector<FloePose> poses_of(const Floes& floes) {
  std::vector<FloePose> p;
  for (const FloeState& s : floes.state) p.push_back({s.x, s.y, s.yaw});
  return p;
}

}  // namespace

TEST_CASE("moved footprints: second order in the displacement, with the floe's area and centroid exact") {
  // coupling/moving_footprint.hpp: a_c(P) = a_c(P0) + N . delta + T phi is
  // the first-order Taylor expansion of the exact piece, so against a fresh
  // build its error is O(|delta|^2 + R^2 phi^2): halving the displacement
  // divides it by about 4. The sums are exact: sum N = ∮ n ds = 0 and
  // sum (Q - a I) = ∮ r n^T ds - A I = 0 (divergence theorem), unless a
  // piece's affine area went below 0 and was cut to 0 (a node the floe left).
  const fluid::SurfaceGrid grid = box_grid();
  std::mt19937_64 rng(11);
  Floes floes = mixed_floes(rng, 9);
  scatter(floes, grid, rng);
  const std::vector<std::uint8_t> include(floes.size(), 1);
  for (FootprintKernel kernel : {FootprintKernel::tent, FootprintKernel::cell}) {
    INFO((kernel == FootprintKernel::tent ? "tent" : "cell") << " kernel");
    MovingFootprints moving(grid, kernel, {0.5});
    const std::vector<FloePose> p0 = poses_of(floes);
    CHECK(moving.place(floes, include, p0, 1));  // the first placement builds
    std::vector<double> errors;
    for (double step : {0.2, 0.1, 0.05}) {  // of a cell
      std::vector<FloePose> p = p0;
      for (std::size_t i = 0; i < p.size(); ++i) {
        double radius = 0.0;
        for (const Vec2& v : floes.vertices(i)) radius = std::max(radius, v.norm());
        p[i].x += 0.6 * step * grid.dx();
        p[i].y -= 0.5 * step * grid.dy();
        p[i].yaw += 0.3 * step * grid.dy() / radius;
      }
      REQUIRE_FALSE(moving.place(floes, include, p, 1));  // inside the window: moved
      Footprints exact;
      build_footprints(floes, include, grid, exact, kernel, 1, p);
      const PieceError e = piece_error(moving.pieces(), exact);
      errors.push_back(e.area);
      MESSAGE("displacement " << step << " cell: largest piece area error " << e.area / grid.cell_area()
                              << " of a cell, first moment " << e.moment / std::pow(grid.cell_area(), 1.5));
      const Footprints& fp = moving.pieces();
      for (std::size_t f = 0; f < floes.size(); ++f) {
        double area = 0.0;
        Vec2 moment = Vec2::Zero();
        int cut = 0;
        for (std::size_t k = fp.offsets[f]; k < fp.offsets[f + 1]; ++k) {
          area += fp.area[k];
          moment += fp.area[k] * fp.centroid[k];
          cut += fp.area[k] == 0.0;
        }
        if (cut > 0) {  // a cut piece's affine area was below 0 <= its exact one: cut by less than its error
          CHECK(std::abs(area - floes.area[f]) <= cut * e.area);
          continue;
        }
        CHECK(area == doctest::Approx(floes.area[f]).epsilon(1e-12));
        CHECK(moment.norm() < 1e-9 * floes.area[f] * std::sqrt(floes.area[f]));
      }
    }
    CHECK(errors[0] / errors[1] > 3.0);
    CHECK(errors[1] / errors[2] > 3.0);
    CHECK(errors[2] < 0.01 * grid.cell_area());
  }
}

TEST_CASE("moved footprints: rebuilt exactly when a floe's vertices may leave their window") {
  // The window (moving_footprint.hpp): |delta_x| + R |phi| <= reach dx and the
  // same along y; past it every floe is rebuilt, to the bits of a fresh build.
  const fluid::SurfaceGrid grid = box_grid();
  std::mt19937_64 rng(5);
  Floes floes = mixed_floes(rng, 6);
  scatter(floes, grid, rng);
  const std::vector<std::uint8_t> include(floes.size(), 1);
  MovingFootprints moving(grid, FootprintKernel::tent, {0.1});
  std::vector<FloePose> p = poses_of(floes);
  CHECK(moving.place(floes, include, p, 1));
  p[2].x += 0.09 * grid.dx();
  CHECK_FALSE(moving.place(floes, include, p, 1));
  p[2].x += 0.02 * grid.dx();  // 0.11 cell from where it was built
  CHECK(moving.place(floes, include, p, 1));
  Footprints fresh;
  build_footprints(floes, include, grid, fresh, FootprintKernel::tent, 1, p);
  CHECK(moving.pieces().area == fresh.area);
  CHECK(moving.pieces().cell == fresh.cell);
  // A turn counts with the floe's radius; the new reference is the last build.
  double radius = 0.0;
  for (const Vec2& v : floes.vertices(4)) radius = std::max(radius, v.norm());
  p[4].yaw += 0.09 * grid.dy() / radius;
  CHECK_FALSE(moving.place(floes, include, p, 1));
  p[4].yaw += 0.02 * grid.dy() / radius;
  CHECK(moving.place(floes, include, p, 1));
  CHECK(moving.rebuilds() == 3);
  CHECK(moving.placements() == 5);
  // Reach 0: every placement builds.
  MovingFootprints exact(grid, FootprintKernel::tent, {0.0});
  CHECK(exact.place(floes, include, p, 1));
  CHECK(exact.place(floes, include, p, 1));
}

TEST_CASE("moved footprints: every piece lies within reach_rows() rows of its floe's centroid at the rebuild") {
  // MovingFootprints::reach_rows() is the halo of the sea's fields that a
  // rank reads when the floes are owned by place (docs/parallel.md, stage
  // five): a piece beyond it would read a stale row. The bound is the
  // largest radius, the tent's one node and the window, in rows, plus one;
  // it must hold for every floe, including those across the grid's seam,
  // and not be loose by more than those margins (the largest floe, turned
  // across the rows, has pieces within 4 rows of it). The grid is taller
  // than box_grid's so that the 100 m floe's reach is below half of it.
  fluid::SurfaceGrid grid = box_grid();
  grid.ny = 120;
  grid.ly = 180.0;
  std::mt19937_64 rng(23);
  Floes floes = mixed_floes(rng, 12);
  const std::vector<std::uint8_t> include(floes.size(), 1);
  for (FootprintKernel kernel : {FootprintKernel::tent, FootprintKernel::cell}) {
    for (int trial = 0; trial < 4; ++trial) {
      INFO((kernel == FootprintKernel::tent ? "tent" : "cell") << " kernel, trial " << trial);
      scatter(floes, grid, rng);  // near the seam too
      floes.state.back().yaw = 0.5 * std::numbers::pi;  // the 100 m floe along y
      MovingFootprints moving(grid, kernel, {0.5});
      const std::vector<FloePose> p0 = poses_of(floes);
      REQUIRE(moving.place(floes, include, p0, 1));
      const int reach = moving.reach_rows();
      const Footprints& fp = moving.pieces();
      int farthest = 0;
      for (std::size_t i = 0; i < floes.size(); ++i) {
        const int centre = static_cast<int>(std::floor(p0[i].y / grid.dy()));
        for (std::size_t k = fp.offsets[i]; k < fp.offsets[i + 1]; ++k) {
          const int row = static_cast<int>(fp.cell[k] / static_cast<std::uint32_t>(grid.nx));
          int d = std::abs(row - ((centre % grid.ny) + grid.ny) % grid.ny);
          d = std::min(d, grid.ny - d);  // periodic
          CHECK(d <= reach);
          farthest = std::max(farthest, d);
        }
      }
      CHECK(farthest >= reach - 4);
    }
  }
}

TEST_CASE("moved footprints: the fit's thresholds change the pieces' arrays' capacity, not the pieces") {
  // FootprintMotionOptions::fit_slack, fit_spare: the arrays' layout after a
  // rebuild. With slack 0 and spare 1 an array with any spare capacity is
  // copied into one twice its size; with the defaults an array keeps at
  // most a quarter of its size spare. The pieces are the same bits either
  // way, built and moved.
  const fluid::SurfaceGrid grid = box_grid();
  std::mt19937_64 rng(5);
  Floes floes = mixed_floes(rng, 6);
  scatter(floes, grid, rng);
  const std::vector<std::uint8_t> include(floes.size(), 1);
  FootprintMotionOptions roomy{0.5};
  roomy.fit_slack = 0.0;
  roomy.fit_spare = 1.0;
  MovingFootprints fitted(grid, FootprintKernel::tent, {0.5}), spare(grid, FootprintKernel::tent, roomy);
  std::vector<FloePose> p = poses_of(floes);
  const auto same_pieces = [&] {
    const Footprints &a = fitted.pieces(), &b = spare.pieces();
    CHECK(a.offsets == b.offsets);
    CHECK(a.cell == b.cell);
    CHECK(a.area == b.area);
    CHECK(a.centroid == b.centroid);
    CHECK(a.edge_offsets == b.edge_offsets);
    CHECK(a.edge_cell == b.edge_cell);
    CHECK(a.edge_normal == b.edge_normal);
    CHECK(a.edge_twist == b.edge_twist);
    CHECK(std::equal(fitted.reference_area().begin(), fitted.reference_area().end(),
                     spare.reference_area().begin(), spare.reference_area().end()));
  };
  // After a rebuild each array's spare capacity is within the slack, or the
  // spare of a copy (`copied` counts those, of the arrays with entries,
  // whose spare is beyond the slack).
  const auto layout = [](const Footprints& f, const FootprintMotionOptions& o, int& copied) {
    copied = 0;
    bool rule = true;
    const auto check = [&](const auto& v) {
      const auto share = [&](double fraction) {
        return static_cast<std::size_t>(fraction * static_cast<double>(v.size()));
      };
      const std::size_t room = v.capacity() - v.size();
      rule = rule && (room <= share(o.fit_slack) || room == share(o.fit_spare));
      copied += !v.empty() && room > share(o.fit_slack);
    };
    check(f.offsets), check(f.cell), check(f.area), check(f.centroid), check(f.edge_offsets), check(f.edge_cell);
    check(f.edge_piece), check(f.edge_length), check(f.edge_normal), check(f.edge_twist), check(f.edge_first);
    check(f.edge_swept);
    return rule;
  };
  for (int rebuild = 0; rebuild < 2; ++rebuild) {
    CAPTURE(rebuild);
    REQUIRE(fitted.place(floes, include, p, 1));
    REQUIRE(spare.place(floes, include, p, 1));
    same_pieces();
    int copied_fitted = 0, copied_spare = 0;
    CHECK(layout(fitted.pieces(), FootprintMotionOptions{}, copied_fitted));
    CHECK(layout(spare.pieces(), roomy, copied_spare));
    CHECK(copied_fitted == 0);  // none more than a quarter spare
    // The options are read: arrays twice their size, which the defaults
    // never leave.
    MESSAGE("arrays copied twice their size: " << copied_spare << " of 12");
    CHECK(copied_spare > 0);
    // A move inside the window (the same on both), then a rebuild elsewhere.
    for (FloePose& q : p) q.x += 0.2 * grid.dx();
    REQUIRE_FALSE(fitted.place(floes, include, p, 1));
    REQUIRE_FALSE(spare.place(floes, include, p, 1));
    same_pieces();
    for (FloePose& q : p) q.y += 3.0 * grid.dy();
  }
}
