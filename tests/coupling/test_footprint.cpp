// Footprints of floes on the sea grid (coupling/footprint.hpp): every area
// piece against an independent computation, the polygon clipped by its cell
// (Sutherland–Hodgman by the four half-planes; for a non-convex polygon the
// clipped chain may hold zero-width slivers, but its area and first moments
// by Green's theorem are exact), and the sums against the polygon's own
// integrals.
#include <doctest/doctest.h>

#include <cmath>
#include <map>
#include <numbers>
#include <random>

#include "core/floes.hpp"
#include "coupling/footprint.hpp"

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

// Reference pieces of floe f by clipping, keyed by (wrapped) cell.
std::map<std::uint32_t, Piece> clipped_pieces(const Floes& floes, std::size_t f, const fluid::SurfaceGrid& grid) {
  const FloeState& st = floes.state[f];
  const Vec2 g{st.x, st.y};
  std::vector<Vec2> poly;
  for (const Vec2& p : floes.vertices(f)) poly.push_back(rotate(p, st.yaw));
  double lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY};
  for (const Vec2& p : poly)
    for (int a = 0; a < 2; ++a) {
      lo[a] = std::min(lo[a], p[a] + g[a]);
      hi[a] = std::max(hi[a], p[a] + g[a]);
    }
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
  fluid::SurfaceGrid grid;
  grid.dims = 2;
  grid.nx = 40;
  grid.ny = 30;
  grid.lx = 80.0;
  grid.ly = 45.0;  // dx = 2, dy = 1.5
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<std::vector<Vec2>> outlines;
  for (int k = 0; k < 12; ++k) {
    const double r = 3.0 + 12.0 * u(rng);
    if (k % 3 == 0) outlines.push_back(star(5, 0.4 * r, r, u(rng)));  // non-convex
    else if (k % 3 == 1) outlines.push_back({{0, 0}, {r, 0}, {r, 0.3 * r}, {0.3 * r, 0.3 * r}, {0.3 * r, r}, {0, r}});  // L
    else outlines.push_back(star(6, r, r, u(rng)));  // a regular 12-gon
  }
  outlines.push_back({{0, 0}, {100, 0}, {100, 10}, {0, 10}});  // longer than the box: cells covered twice
  Floes floes = make_floes(outlines);
  for (int trial = 0; trial < 6; ++trial) {
    for (std::size_t f = 0; f < floes.size(); ++f) {
      FloeState& s = floes.state[f];
      s.x = grid.lx * u(rng);  // near the edges too: pieces wrap
      s.y = grid.ly * u(rng);
      s.yaw = 2.0 * std::numbers::pi * u(rng);
    }
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
