// Convex partition: every piece convex, pieces tile the polygon (areas sum to
// its area and a point of the polygon lies in exactly one piece), piece counts
// within the bounds that reflex vertices impose.
#include <doctest/doctest.h>

#include <cmath>
#include <numbers>
#include <random>

#include "core/convex_partition.hpp"
#include "core/error.hpp"

using namespace floesim;

namespace {

std::size_t reflex_vertices(const std::vector<Vec2>& p) {
  std::size_t r = 0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    const Vec2& a = p[(i + p.size() - 1) % p.size()];
    const Vec2& b = p[i];
    const Vec2& c = p[(i + 1) % p.size()];
    if (cross(b - a, c - b) < 0.0) ++r;
  }
  return r;
}

// Strictly inside a CCW convex polygon (all edges turn left of the point).
bool strictly_inside_convex(const std::vector<Vec2>& q, const Vec2& x) {
  for (std::size_t k = 0; k < q.size(); ++k)
    if (cross(q[(k + 1) % q.size()] - q[k], x - q[k]) <= 0.0) return false;
  return true;
}

// Checks that `pieces` is a convex partition of `poly`; returns the piece count.
std::size_t check_partition(const std::vector<Vec2>& poly, const std::vector<std::vector<Vec2>>& pieces,
                            unsigned seed = 1) {
  double total = 0.0;
  for (const auto& q : pieces) {
    REQUIRE(q.size() >= 3);
    CHECK(is_convex(q));
    CHECK(signed_area(q) > 0.0);  // counter-clockwise
    total += signed_area(q);
    // A partition adds diagonals only: every piece vertex is a polygon vertex.
    for (const Vec2& v : q) {
      bool found = false;
      for (const Vec2& p : poly) found = found || p == v;
      CHECK(found);
    }
  }
  CHECK(total == doctest::Approx(signed_area(poly)).epsilon(1e-12));
  // Random points of the bounding box: inside the polygon <=> in exactly one piece.
  Vec2 lo = poly[0], hi = poly[0];
  for (const Vec2& p : poly) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
  std::mt19937_64 g(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  int mismatches = 0;
  for (int s = 0; s < 4000; ++s) {
    const Vec2 x = lo + Vec2(u(g), u(g)).cwiseProduct(hi - lo);
    int in = 0;
    for (const auto& q : pieces) in += strictly_inside_convex(q, x);
    if (in != (point_in_polygon(poly, x) ? 1 : 0)) ++mismatches;
  }
  CHECK(mismatches == 0);
  return pieces.size();
}

std::vector<Vec2> comb(int teeth) {
  // Base [0, 2 teeth - 1] x [0, 1], teeth [2t, 2t+1] x [1, 3].
  std::vector<Vec2> p{{0, 0}, {2.0 * teeth - 1.0, 0}};
  for (int t = teeth - 1; t >= 0; --t) {
    p.emplace_back(2.0 * t + 1.0, 3.0);
    p.emplace_back(2.0 * t, 3.0);
    if (t > 0) {
      p.emplace_back(2.0 * t, 1.0);
      p.emplace_back(2.0 * t - 1.0, 1.0);
    }
  }
  return p;  // counter-clockwise: along the bottom, then right to left along the top
}

std::vector<Vec2> star(int points, double r_out, double r_in) {
  std::vector<Vec2> p;
  for (int k = 0; k < 2 * points; ++k) {
    const double a = std::numbers::pi * k / points;
    const double r = k % 2 ? r_in : r_out;
    p.emplace_back(r * std::cos(a), r * std::sin(a));
  }
  return p;
}

}  // namespace

TEST_CASE("convex input is returned unchanged") {
  const std::vector<Vec2> sq{{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  CHECK(is_convex(sq));
  auto pieces = convex_partition(sq);
  REQUIRE(pieces.size() == 1);
  CHECK(pieces[0] == sq);
  // Collinear vertices allowed in convex input, kept as given.
  const std::vector<Vec2> sq5{{0, 0}, {0.5, 0}, {1, 0}, {1, 1}, {0, 1}};
  pieces = convex_partition(sq5);
  REQUIRE(pieces.size() == 1);
  CHECK(pieces[0] == sq5);
}

TEST_CASE("L shape: two convex pieces") {
  const std::vector<Vec2> l{{0, 0}, {2, 0}, {2, 1}, {1, 1}, {1, 2}, {0, 2}};
  CHECK_FALSE(is_convex(l));
  CHECK(check_partition(l, convex_partition(l)) == 2);
  ConvexPartitionOptions approx;
  approx.method = PartitionMethod::approximate;
  CHECK(check_partition(l, convex_partition(l, approx)) == 2);
  // The same L with collinear midpoints on its edges: same region, same count.
  const std::vector<Vec2> l2{{0, 0}, {1, 0}, {2, 0}, {2, 1}, {1, 1}, {1, 2}, {0, 2}, {0, 1}};
  CHECK(check_partition(l2, convex_partition(l2)) == 2);
}

TEST_CASE("comb: one piece per tooth at best, reflex bound respected") {
  for (int teeth : {2, 3, 5, 8}) {
    CAPTURE(teeth);
    const auto c = comb(teeth);
    REQUIRE(signed_area(c) > 0.0);
    const std::size_t r = reflex_vertices(c);
    CHECK(r == static_cast<std::size_t>(2 * (teeth - 1)));
    // Each diagonal removes at most two reflex vertices: >= r/2 + 1 pieces.
    // One diagonal per reflex vertex suffices: <= r + 1.
    const std::size_t opt = check_partition(c, convex_partition(c));
    CHECK(opt >= r / 2 + 1);
    CHECK(opt <= r + 1);
    ConvexPartitionOptions approx;
    approx.method = PartitionMethod::approximate;
    const std::size_t hm = check_partition(c, convex_partition(c, approx));
    CHECK(hm >= opt);
    CHECK(hm <= 4 * opt);  // Hertel–Mehlhorn's guarantee
  }
}

TEST_CASE("star: pieces convex and tiling, counts within bounds") {
  const auto s = star(5, 1.0, 0.4);
  const std::size_t r = reflex_vertices(s);
  CHECK(r == 5);
  const std::size_t opt = check_partition(s, convex_partition(s));
  CHECK(opt >= 4);  // ceil(5/2) + 1
  CHECK(opt <= 6);
  ConvexPartitionOptions approx;
  approx.method = PartitionMethod::approximate;
  check_partition(s, convex_partition(s, approx));
  // Many-pointed star: above the automatic threshold (approximate path).
  const auto big = star(24, 2.0, 1.5);
  CHECK(big.size() > ConvexPartitionOptions{}.optimal_max_vertices);
  CHECK(check_partition(big, convex_partition(big)) <= 4 * (24 / 2 + 1));
}

TEST_CASE("random star-shaped polygons partition into convex tiles") {
  std::mt19937_64 g(42);
  std::uniform_real_distribution<double> u(0.3, 1.0);
  for (int trial = 0; trial < 20; ++trial) {
    const int n = trial % 2 ? 14 : 40;
    std::vector<Vec2> p;
    for (int k = 0; k < n; ++k) {
      const double a = 2.0 * std::numbers::pi * k / n;
      const double r = u(g);
      p.emplace_back(r * std::cos(a), r * std::sin(a));
    }
    CAPTURE(trial);
    check_partition(p, convex_partition(p), static_cast<unsigned>(trial));
  }
}

TEST_CASE("bad input is refused") {
  CHECK_THROWS_AS(convex_partition(std::vector<Vec2>{{0, 0}, {1, 0}}), InputError);
  const std::vector<Vec2> cw{{0, 0}, {0, 1}, {1, 1}, {1, 0}};
  CHECK_THROWS_AS(convex_partition(cw), InputError);
  const std::vector<Vec2> nan{{0, 0}, {1, 0}, {std::nan(""), 1}};
  CHECK_THROWS_AS(convex_partition(nan), InputError);
}
