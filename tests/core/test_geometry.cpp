// Polygon integrals against closed forms.
#include <doctest/doctest.h>

#include <cmath>
#include <numbers>

#include "core/geometry.hpp"

using namespace floesim;

TEST_SUITE_BEGIN("core");

TEST_CASE("rectangle moments match the closed forms") {
  // Rectangle [1, 4] x [2, 4]: A = 6, centroid (2.5, 3),
  // ∫(x-Gx)² = b³h/12 = 27*2/12 = 4.5, ∫(y-Gy)² = b h³/12 = 3*8/12 = 2.
  std::vector<Vec2> r{{1, 2}, {4, 2}, {4, 4}, {1, 4}};
  const PolygonMoments m = polygon_moments(r);
  CHECK(m.area == doctest::Approx(6.0).epsilon(1e-14));
  CHECK(m.centroid().x() == doctest::Approx(2.5).epsilon(1e-14));
  CHECK(m.centroid().y() == doctest::Approx(3.0).epsilon(1e-14));
  CHECK(m.sxx - m.area * 2.5 * 2.5 == doctest::Approx(4.5).epsilon(1e-12));
  CHECK(m.syy - m.area * 3.0 * 3.0 == doctest::Approx(2.0).epsilon(1e-12));
  CHECK(m.sxy - m.area * 2.5 * 3.0 == doctest::Approx(0.0).scale(1.0));
}

TEST_CASE("clockwise polygons have negative signed area") {
  std::vector<Vec2> r{{0, 0}, {0, 1}, {1, 1}, {1, 0}};
  CHECK(signed_area(r) == doctest::Approx(-1.0));
}

TEST_CASE("non-convex L shape: moments are sums of its two rectangles") {
  // L = [0,2]x[0,1] ∪ [0,1]x[1,2]: A = 3, ∫x = 2*1 + 0.5*1 = 2.5, ∫x² = 8/3 + 1/3 = 3.
  std::vector<Vec2> l{{0, 0}, {2, 0}, {2, 1}, {1, 1}, {1, 2}, {0, 2}};
  const PolygonMoments m = polygon_moments(l);
  CHECK(m.area == doctest::Approx(3.0));
  CHECK(m.sx == doctest::Approx(2.5));
  CHECK(m.sxx == doctest::Approx(3.0));
  CHECK(m.sxy == doctest::Approx(1.0 + 0.75));  // ∫xy: [0,2]x[0,1] -> 2*0.5=1; [0,1]x[1,2] -> 0.5*1.5
}

TEST_CASE("polar third moment of a square matches the analytic integral") {
  // Square of half-side b about its centre:
  //   ∫ r³ dA = b⁵ · 8/5 ∫_0^{π/4} sec⁵θ dθ = b⁵ · 8/5 [√2/2 + 3(√2 + ln(1+√2))/8].
  const double b = 3.0;
  std::vector<Vec2> sq{{-b, -b}, {b, -b}, {b, b}, {-b, b}};
  const double s2 = std::sqrt(2.0);
  const double exact = std::pow(b, 5) * 8.0 / 5.0 * (s2 / 2 + 3.0 * (s2 + std::log(1 + s2)) / 8.0);
  CHECK(polar_moment3(sq, Vec2::Zero()) == doctest::Approx(exact).epsilon(1e-10));
  // Disc approximated by a 2000-gon: ∫ r³ dA -> 2π R⁵/5.
  std::vector<Vec2> disc;
  const int n = 2000;
  for (int k = 0; k < n; ++k) disc.emplace_back(std::cos(2 * std::numbers::pi * k / n), std::sin(2 * std::numbers::pi * k / n));
  CHECK(polar_moment3(disc, Vec2::Zero()) == doctest::Approx(2 * std::numbers::pi / 5).epsilon(1e-5));
  // Non-convex (L shape about a point outside it): equals the sum over its two rectangles.
  std::vector<Vec2> l{{0, 0}, {2, 0}, {2, 1}, {1, 1}, {1, 2}, {0, 2}};
  std::vector<Vec2> r1{{0, 0}, {2, 0}, {2, 1}, {0, 1}}, r2{{0, 1}, {1, 1}, {1, 2}, {0, 2}};
  const Vec2 c{1.6, 1.6};
  CHECK(polar_moment3(l, c) == doctest::Approx(polar_moment3(r1, c) + polar_moment3(r2, c)).epsilon(1e-10));
}

TEST_CASE("self-intersection detection") {
  std::vector<Vec2> bow{{0, 0}, {1, 1}, {1, 0}, {0, 1}};  // bow tie
  CHECK(find_self_intersection(bow).has_value());
  std::vector<Vec2> sq{{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  CHECK_FALSE(find_self_intersection(sq).has_value());
  std::vector<Vec2> l{{0, 0}, {2, 0}, {2, 1}, {1, 1}, {1, 2}, {0, 2}};
  CHECK_FALSE(find_self_intersection(l).has_value());
  std::vector<Vec2> touching{{0, 0}, {2, 0}, {2, 2}, {1, 0}, {0, 2}};  // vertex 3 lies on edge 0
  CHECK(find_self_intersection(touching).has_value());
  std::vector<Vec2> repeated{{0, 0}, {1, 0}, {1, 0}, {0, 1}};
  CHECK(find_self_intersection(repeated).has_value());
  std::vector<Vec2> folded{{0, 0}, {2, 0}, {1, 0}, {0, 1}};  // edge 1 folds back onto edge 0
  CHECK(find_self_intersection(folded).has_value());
}

TEST_CASE("point in polygon") {
  std::vector<Vec2> l{{0, 0}, {2, 0}, {2, 1}, {1, 1}, {1, 2}, {0, 2}};
  CHECK(point_in_polygon(l, {0.5, 1.5}));
  CHECK_FALSE(point_in_polygon(l, {1.5, 1.5}));
}

TEST_SUITE_END();
