#include "core/floe.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "core/error.hpp"

namespace floesim {

namespace {
// A number as a user wrote it (shortest form: 2e+130, 1000, 0.5).
std::string number(double x) {
  std::ostringstream s;
  s << x;
  return s.str();
}
}  // namespace

FloeShape make_floe_shape(const FloeInput& in) {
  auto fail = [&](const std::string& what) {
    throw InputError(in.origin.empty() ? what : in.origin + ": " + what);
  };
  if (in.vertices.size() < 3)
    fail("a floe needs at least 3 vertices, got " + std::to_string(in.vertices.size()));
  for (std::size_t i = 0; i < in.vertices.size(); ++i)
    if (!in.vertices[i].allFinite()) fail("vertex " + std::to_string(i) + " is not a finite number");
  if (!(in.thickness >= kMinLength && in.thickness <= kMaxCoordinate))
    fail("thickness = " + number(in.thickness) + " m: expected a thickness in [" + number(kMinLength) + ", " +
         number(kMaxCoordinate) + "] m");
  if (!(in.density >= kMinDensity && in.density <= kMaxDensity))
    fail("density = " + number(in.density) + " kg/m^3: expected a density in [" + number(kMinDensity) + ", " +
         number(kMaxDensity) + "] kg/m^3");
  if (!in.velocity.allFinite() || !std::isfinite(in.angular_velocity) || !std::isfinite(in.yaw) ||
      !in.position.allFinite())
    fail("position, velocity, angular_velocity and yaw must be finite numbers");
  // Coordinates bounded before any product of them (a 1e300 m square's area
  // overflows to inf, which the area test below would misread as zero).
  auto too_far = [](const Vec2& p) { return p.cwiseAbs().maxCoeff() > kMaxCoordinate; };
  for (std::size_t i = 0; i < in.vertices.size(); ++i)
    if (too_far(in.vertices[i]))
      fail("vertex " + std::to_string(i) + " = (" + number(in.vertices[i].x()) + ", " +
           number(in.vertices[i].y()) + ") m: coordinates too large, expected |x|, |y| <= " +
           number(kMaxCoordinate) + " m");
  if (too_far(in.position))
    fail("position (" + number(in.position.x()) + ", " + number(in.position.y()) +
         ") m: coordinates too large, expected |x|, |y| <= " + number(kMaxCoordinate) + " m");
  if (in.velocity.stableNorm() > kMaxSpeed)  // (stableNorm: |(1e300, 0)| is 1e300, not inf)
    fail("speed |velocity| = " + number(in.velocity.stableNorm()) + " m/s is not physical, expected <= " +
         number(kMaxSpeed) + " m/s");
  if (std::abs(in.heave_rate) > kMaxSpeed)
    fail("heave_rate = " + number(in.heave_rate) + " m/s is not physical, expected |heave_rate| <= " +
         number(kMaxSpeed) + " m/s");

  FloeShape shape;
  std::vector<Vec2> v = in.vertices;
  // All vertices on one line (or one point): zero area, whatever the order.
  // They are collinear iff all lie on the line from v[0] to the vertex farthest from it.
  Vec2 far = v[0];
  for (const Vec2& p : v)
    if ((p - v[0]).squaredNorm() > (far - v[0]).squaredNorm()) far = p;
  const double extent = (far - v[0]).norm();
  double spread = 0.0;
  for (const Vec2& p : v) spread = std::max(spread, std::abs(cross(p - v[0], far - v[0])));
  if (!(spread > 1e-12 * extent * extent) || extent == 0.0)
    fail("the outline has zero area (all vertices on a line?)");
  if (extent < kMinLength)
    fail("the outline is " + number(extent) + " m across: expected a floe at least " + number(kMinLength) +
         " m across");
  if (auto bad = find_self_intersection(v)) {
    std::ostringstream s;
    s << "the outline intersects itself (edges " << bad->first << " and " << bad->second
      << ", counting from 0; edge i joins vertex i to vertex i+1)";
    fail(s.str());
  }
  PolygonMoments m = polygon_moments(v);
  if (!(std::abs(m.area) > 1e-12 * extent * extent))
    fail("the outline has zero area");
  if (m.area < 0.0) {
    std::reverse(v.begin(), v.end());
    m = polygon_moments(v);
    shape.reoriented = true;
  }
  const Vec2 g = m.centroid();
  double radius = 0.0;  // largest distance from the centroid to a vertex
  for (const Vec2& p : v) radius = std::max(radius, (p - g).norm());
  if (std::abs(in.angular_velocity) * radius > kMaxSpeed)
    fail("angular_velocity = " + number(in.angular_velocity) + " rad/s gives a rim speed of " +
         number(std::abs(in.angular_velocity) * radius) + " m/s (" + number(radius) +
         " m from the centroid), which is not physical, expected <= " + number(kMaxSpeed) + " m/s");
  shape.centroid = in.position + rotate(g, in.yaw);
  shape.body.reserve(v.size());
  for (const Vec2& p : v) shape.body.push_back(p - g);

  // Second moments about the centroid: ∫(x-G)² = ∫x² - A Gx², etc.
  const double jxx = m.sxx - m.area * g.x() * g.x();
  const double jyy = m.syy - m.area * g.y() * g.y();
  const double rho_h = in.density * in.thickness;
  MassProperties& p = shape.props;
  p.area = m.area;
  p.mass = rho_h * m.area;
  p.inertia_z = rho_h * (jxx + jyy);
  const double plate = p.mass * in.thickness * in.thickness / 12.0;
  p.inertia_x = rho_h * jyy + plate;
  p.inertia_y = rho_h * jxx + plate;
  return shape;
}

}  // namespace floesim
