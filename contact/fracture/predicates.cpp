// The exact fallback of predicates.hpp: CGAL's exact-predicates kernel.
#include "contact/fracture/predicates.hpp"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

namespace floesim::fracture::detail {

namespace {
using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
Kernel::Point_2 point(const Vec2& p) { return {p.x(), p.y()}; }
}  // namespace

int orientation_exact(const Vec2& a, const Vec2& b, const Vec2& c) {
  return static_cast<int>(CGAL::orientation(point(a), point(b), point(c)));
}

int in_circle_exact(const Vec2& a, const Vec2& b, const Vec2& c, const Vec2& d) {
  return static_cast<int>(CGAL::side_of_oriented_circle(point(a), point(b), point(c), point(d)));
}

}  // namespace floesim::fracture::detail
