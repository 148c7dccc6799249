#pragma once
// Plane polygon geometry: exact integrals over simple polygons (area, first and
// second moments), simplicity (no self-intersection) and point location.
//
// Polygons are vertex lists, counter-clockwise unless stated, not closed (the
// last vertex connects to the first). Integrals use Green's theorem on the
// edges, so they are exact for any simple polygon, convex or not.

#include <Eigen/Core>
#include <optional>
#include <span>
#include <vector>

namespace floesim {

using Vec2 = Eigen::Vector2d;

// Integrals over the polygon's interior of 1, x, y, x^2, x*y, y^2
// (signed: negative for a clockwise vertex order).
struct PolygonMoments {
  double area = 0.0;
  double sx = 0.0, sy = 0.0;               // ∫x, ∫y
  double sxx = 0.0, sxy = 0.0, syy = 0.0;  // ∫x², ∫xy, ∫y²
  Vec2 centroid() const { return {sx / area, sy / area}; }
};

// Green's theorem, edge by edge: with c_i = x_i y_{i+1} - x_{i+1} y_i,
//   A    = 1/2  Σ c_i
//   ∫x   = 1/6  Σ c_i (x_i + x_{i+1})
//   ∫x²  = 1/12 Σ c_i (x_i² + x_i x_{i+1} + x_{i+1}²)
//   ∫xy  = 1/24 Σ c_i (x_i y_{i+1} + 2 x_i y_i + 2 x_{i+1} y_{i+1} + x_{i+1} y_i)
PolygonMoments polygon_moments(std::span<const Vec2> v);

double signed_area(std::span<const Vec2> v);

// ∫ |x - c|^3 dA over the polygon (the drag torque integral of a spinning floe),
// computed by quadrature on the fan triangles (c, v_i, v_{i+1}) in polar form:
// on each fan triangle r runs from 0 to the edge, so ∫ r^3 dA = ∫ r_edge(θ)^5/5 dθ,
// integrated with Gauss–Legendre in θ. Accurate to ~1e-12 relative.
double polar_moment3(std::span<const Vec2> v, const Vec2& c);

// First pair of edges (i, j) that intersect although they are not neighbours
// (or neighbours that overlap beyond their common vertex); nullopt if simple.
// O(n^2) on the edges: floes have tens of vertices.
std::optional<std::pair<std::size_t, std::size_t>> find_self_intersection(std::span<const Vec2> v);

// Whether p lies inside the polygon (even–odd rule; boundary points ambiguous).
bool point_in_polygon(std::span<const Vec2> v, const Vec2& p);

// z-component of the cross product.
inline double cross(const Vec2& a, const Vec2& b) { return a.x() * b.y() - a.y() * b.x(); }

// Rotation of a body-frame vector by the yaw angle theta.
inline Vec2 rotate(const Vec2& v, double theta) {
  const double c = std::cos(theta), s = std::sin(theta);
  return {c * v.x() - s * v.y(), s * v.x() + c * v.y()};
}

}  // namespace floesim
