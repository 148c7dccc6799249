// The normal targets of the collision LCP (contact/impulse.hpp) over a step
// of length h: what the floes' turning closes beyond the linear gap is asked
// back as a speed, turning / h. A gap measured at positions of size L carries
// a round-off of about 1e-16 L, and over a sliver of a step (1.8e-15 s, as
// the clock and a record time computed another way can differ) that becomes
// a speed of hundreds of m/s. The step is taken no shorter than
// ImpulseOptions::step_floor, so round-off stays round-off.
#include <doctest/doctest.h>

#include <cmath>
#include <vector>

#include "contact/detection.hpp"
#include "contact/impulse.hpp"

using namespace floesim;

TEST_SUITE_BEGIN("contact");

namespace {

FloeInput square(double x0, double vx) {
  FloeInput f;
  f.vertices = {{x0, 0.0}, {x0 + 10.0, 0.0}, {x0 + 10.0, 10.0}, {x0, 10.0}};
  f.velocity = {vx, 0.0};
  return f;
}

// Two 10 m squares 5 mm apart (in contact: within xi = 1 cm), the second
// closing on the first at 1 mm/s, their contacts carrying a turning of
// 1e-12 m (the round-off of a gap measured 5 km from the origin), solved as
// the contacts of a jam's time step of length h. Returns the speed at which
// the floes separate afterwards (m/s, > 0: apart).
double separation_after(double h, double step_floor) {
  Floes f;
  for (const FloeInput& in : {square(5000.0, 0.0), square(5010.005, -1e-3)}) f.add(make_floe_shape(in), in);
  contact::Detection det = contact::detect(f, contact::build_collision_shapes(f), {});
  REQUIRE(!det.contacts.empty());
  for (contact::ContactPoint& c : det.contacts) c.turning = 1e-12;
  contact::ImpulseOptions o;
  o.restitution = 0.0;
  o.friction = 0.0;
  o.speculative_step = h;
  o.step_floor = step_floor;
  contact::CollisionStats stats;
  contact::resolve_collisions(f, det.contacts, o, stats, std::vector<std::uint8_t>(det.contacts.size(), 1));
  REQUIRE(stats.failures == 0);
  return f.state[1].vx - f.state[0].vx;
}

}  // namespace

TEST_CASE("impulse: a sliver of a step does not turn the round-off of a gap into a speed") {
  const double floor = contact::ImpulseOptions{}.step_floor;
  // A step of 1 s: the contact stops the approach and asks 1e-12 m/s back.
  const double normal = separation_after(1.0, floor);
  CHECK(normal >= -1e-12);
  CHECK(normal < 1e-9);
  // A 1.8e-15 s sliver: at most turning / floor = 1e-7 m/s, a tenth of the
  // approach the solver notices (approach_tolerance).
  const double sliver = separation_after(1.8e-15, floor);
  CHECK(sliver >= -1e-12);
  CHECK(sliver <= 1e-12 / floor + 1e-12);
  CHECK(sliver < contact::ImpulseOptions{}.approach_tolerance);
  // Without the floor the same contact throws the floes apart at
  // 1e-12 / 1.8e-15 = 556 m/s: what the floor is there for.
  CHECK(separation_after(1.8e-15, 0.0) == doctest::Approx(1e-12 / 1.8e-15).epsilon(1e-3));
}
