// Momentum balance of the collision impulses (contact/impulse.hpp), checked
// without the time loop: a block of floes thrown against a static wall, with
// friction and restitution, solved by resolve_collisions. Newton's laws
// (analytic, for any solution of the LCP):
//  * the floes' momentum changes by the wall's impulses alone (the impulses
//    between two floes are equal and opposite), sum_i m_i dv_i = J_wall;
//  * their angular momentum about the origin changes by the wall's moment,
//    sum_i (I_i domega_i + m_i x_i X dv_i) = sum_wall p X J;
//  * after the solve no contact approaches (Signorini, in velocities), and
//    each contact's impulse lies in its Coulomb cone, |J_t| <= mu J_n.
#include <doctest/doctest.h>

#include <cmath>
#include <vector>

#include "contact/detection.hpp"
#include "contact/impulse.hpp"

using namespace floesim;

TEST_SUITE_BEGIN("contact");

namespace {

FloeInput rectangle(Vec2 lower_left, Vec2 upper_right, Vec2 velocity, double spin, bool is_static = false) {
  FloeInput f;
  const double x0 = lower_left.x(), y0 = lower_left.y(), x1 = upper_right.x(), y1 = upper_right.y();
  f.vertices = {{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}};
  f.velocity = velocity;
  f.angular_velocity = spin;
  f.is_static = is_static;
  return f;
}

double cross2(const Vec2& a, const Vec2& b) { return a.x() * b.y() - a.y() * b.x(); }

}  // namespace

TEST_CASE("impulse: a block of floes thrown at a wall changes momentum by the wall's impulse alone") {
  // 6 x 4 squares of 10 m, 5 mm apart (within xi = 1 cm), moving towards +x
  // at 0.1 to 0.3 m/s with small spins and sideways speeds; a static wall
  // 5 mm beyond the last column.
  Floes f;
  auto add = [&f](const FloeInput& in) { f.add(make_floe_shape(in), in); };
  const double side = 10.0, pitch = 10.005;
  for (int i = 0; i < 6; ++i)
    for (int j = 0; j < 4; ++j)
      add(rectangle({pitch * i, pitch * j}, {pitch * i + side, pitch * j + side},
                    {0.1 + 0.05 * ((i + 2 * j) % 5), 0.01 * (((i + j) % 3) - 1)}, 1e-4 * (((i * 5 + j) % 7) - 3)));
  const std::size_t dynamic = f.size();
  const double wall_x = pitch * 5 + side + 0.005;
  add(rectangle({wall_x, -20.0}, {wall_x + 10.0, 60.0}, {0.0, 0.0}, 0.0, true));
  const contact::Detection det = contact::detect(f, contact::build_collision_shapes(f), {});
  REQUIRE(det.contacts.size() > 30);

  std::vector<FloeState> before = f.state;
  contact::ImpulseOptions o;
  o.restitution = 0.4;
  o.friction = 0.7;
  contact::CollisionStats stats;
  const std::vector<contact::ContactImpulse> J = contact::resolve_collisions(f, det.contacts, o, stats);
  REQUIRE(stats.failures == 0);
  REQUIRE(stats.lcps >= 1);

  Vec2 dp = Vec2::Zero(), wall = Vec2::Zero();
  double dL = 0.0, wall_moment = 0.0, scale = 0.0;
  for (std::size_t i = 0; i < dynamic; ++i) {
    const Vec2 dv{f.state[i].vx - before[i].vx, f.state[i].vy - before[i].vy};
    const Vec2 x{f.state[i].x, f.state[i].y};
    dp += f.mass[i] * dv;
    dL += f.inertia_z[i] * (f.state[i].yaw_rate - before[i].yaw_rate) + f.mass[i] * cross2(x, dv);
    scale += f.mass[i] * std::hypot(before[i].vx, before[i].vy);
  }
  bool wall_touched = false;
  for (std::size_t k = 0; k < det.contacts.size(); ++k) {
    const contact::ContactPoint& c = det.contacts[k];
    // Floe b receives J, floe a its opposite; the wall's share on the block.
    if (f.is_static[c.a]) {
      wall += J[k].vector;
      wall_moment += cross2(J[k].point, J[k].vector);
      wall_touched = true;
    } else if (f.is_static[c.b]) {
      wall -= J[k].vector;
      wall_moment -= cross2(J[k].point, J[k].vector);
      wall_touched = true;
    }
    // Coulomb's cone for every contact.
    CHECK(std::abs(J[k].tangential) <= o.friction * J[k].normal * (1.0 + 1e-9) + 1e-9 * scale);
    CHECK(J[k].normal >= 0.0);
  }
  REQUIRE(wall_touched);
  CHECK(wall.x() < -0.01 * scale);  // the wall pushes the block back
  CHECK((dp - wall).norm() <= 1e-9 * scale);
  CHECK(std::abs(dL - wall_moment) <= 1e-9 * scale * 100.0);  // arms up to 100 m
  // No contact approaches after the solve.
  for (const contact::ContactPoint& c : det.contacts) {
    auto point_velocity = [&](std::size_t g, const Vec2& p) {
      const FloeState& s = f.state[g];
      const Vec2 r = p - Vec2{s.x, s.y};
      return Vec2{s.vx - s.yaw_rate * r.y(), s.vy + s.yaw_rate * r.x()};
    };
    const double vn = c.normal.dot(point_velocity(c.b, c.point - c.shift) - point_velocity(c.a, c.point));
    CHECK(vn >= -1e-8);
  }
}

TEST_SUITE_END();
