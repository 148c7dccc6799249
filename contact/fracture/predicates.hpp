#pragma once
// Exact orientation and in-circle signs for the floe mesher (lattice_mesh.*).
//
// Each predicate first evaluates its determinant in double precision and
// returns its sign when the magnitude exceeds a forward error bound of that
// evaluation (Shewchuk 1997, "Adaptive precision floating-point arithmetic
// and fast robust geometric predicates": ccwerrboundA = (3 + 16 eps) eps and
// iccerrboundA = (10 + 96 eps) eps times the permanent of the terms); only the
// rare undecided cases go to CGAL's exact predicates (predicates.cpp, the one
// place CGAL's kernel is seen). The signs are therefore exact for any double
// input, which a Delaunay insertion needs: a wrong sign can make its cavity
// not star-shaped and the mesh invalid.

#include <cmath>
#include <limits>

#include "core/geometry.hpp"

namespace floesim::fracture {

namespace detail {
int orientation_exact(const Vec2& a, const Vec2& b, const Vec2& c);
int in_circle_exact(const Vec2& a, const Vec2& b, const Vec2& c, const Vec2& d);
}  // namespace detail

// +1 if a, b, c turn counter-clockwise, -1 clockwise, 0 collinear.
inline int orientation(const Vec2& a, const Vec2& b, const Vec2& c) {
  constexpr double eps = 0.5 * std::numeric_limits<double>::epsilon();
  const double left = (a.x() - c.x()) * (b.y() - c.y());
  const double right = (a.y() - c.y()) * (b.x() - c.x());
  const double det = left - right;
  const double bound = (3.0 + 16.0 * eps) * eps * (std::abs(left) + std::abs(right));
  if (det > bound) return 1;
  if (-det > bound) return -1;
  return detail::orientation_exact(a, b, c);
}

// For a counter-clockwise triangle a, b, c: +1 if d is strictly inside its
// circumcircle, -1 strictly outside, 0 on it.
inline int in_circle(const Vec2& a, const Vec2& b, const Vec2& c, const Vec2& d) {
  constexpr double eps = 0.5 * std::numeric_limits<double>::epsilon();
  const double adx = a.x() - d.x(), ady = a.y() - d.y();
  const double bdx = b.x() - d.x(), bdy = b.y() - d.y();
  const double cdx = c.x() - d.x(), cdy = c.y() - d.y();
  const double bc = bdx * cdy - cdx * bdy, ca = cdx * ady - adx * cdy, ab = adx * bdy - bdx * ady;
  const double alift = adx * adx + ady * ady, blift = bdx * bdx + bdy * bdy, clift = cdx * cdx + cdy * cdy;
  const double det = alift * bc + blift * ca + clift * ab;
  const double permanent = (std::abs(bdx * cdy) + std::abs(cdx * bdy)) * alift +
                           (std::abs(cdx * ady) + std::abs(adx * cdy)) * blift +
                           (std::abs(adx * bdy) + std::abs(bdx * ady)) * clift;
  const double bound = (10.0 + 96.0 * eps) * eps * permanent;
  if (det > bound) return 1;
  if (-det > bound) return -1;
  return detail::in_circle_exact(a, b, c, d);
}

}  // namespace floesim::fracture
