// A jam's LCP in a step (contact/impulse.hpp "Jams", contact/substep.hpp item
// 5): the collisions at the step's start leave a jam alone, and its time step
// solves it once, from the velocities before any collision; the result is
// the one the step's start would have given. And the warm start of a large
// LCP finds a contact's basis flags by its vertex and edge after the contact
// point slid along the edge (contact/impulse.hpp, WarmStart).
#include <doctest/doctest.h>

#include <cmath>
#include <vector>

#include "contact/detection.hpp"
#include "contact/impulse.hpp"
#include "contact/substep.hpp"

using namespace floesim;

TEST_SUITE_BEGIN("contact");

namespace {

FloeInput box(double x0, double y0, double w, double h, double vx, bool is_static = false) {
  FloeInput f;
  f.vertices = {{x0, y0}, {x0 + w, y0}, {x0 + w, y0 + h}, {x0, y0 + h}};
  f.velocity = {vx, 0.0};
  f.is_static = is_static;
  return f;
}

// A row of n 10 m squares 5 mm apart (within xi = 1 cm: in contact), the
// last 5 mm from a static wall on its right, all moving right at v: a jam of
// n floes pushed against the wall. The wall is floe n.
Floes pushed_row(int n, double v) {
  Floes f;
  for (int i = 0; i < n; ++i) {
    const FloeInput in = box(10.005 * i, 0.0, 10.0, 10.0, v);
    f.add(make_floe_shape(in), in);
  }
  const FloeInput wall = box(10.005 * n, -5.0, 20.0, 20.0, 0.0, true);
  f.add(make_floe_shape(wall), wall);
  return f;
}

contact::DetectionOptions detection_options(const Floes& f, double dt) {
  contact::DetectionOptions o;
  o.reach.assign(f.size(), 0.0);
  for (std::size_t i = 0; i < f.size(); ++i)
    if (!f.is_static[i]) o.reach[i] = 1.5 * std::hypot(f.state[i].vx, f.state[i].vy) * dt + o.collision_distance;
  o.horizon = dt;
  return o;
}

}  // namespace

TEST_CASE("jam: the step's start leaves a jam to its time step, which solves it in one LCP") {
  const int n = 25;  // jam.floes = 20 by default
  const double v = 1e-3, dt = 10.0;
  for (const bool at_start : {false, true}) {
    CAPTURE(at_start);
    Floes f = pushed_row(n, v);
    const contact::CollisionShapes shapes = contact::build_collision_shapes(f);
    const contact::Detection det = contact::detect(f, shapes, detection_options(f, dt));
    REQUIRE(det.contacts.size() >= static_cast<std::size_t>(2 * n));
    contact::SubstepOptions o;
    o.impulse.restitution = 0.4;
    o.impulse.friction = 0.7;
    o.impulse.jam.at_step_start = at_start;
    contact::CollisionStats start_stats;
    const std::vector<FloeState> w_minus = f.state;
    contact::resolve_step_collisions(f, w_minus, det, dt, o.impulse, start_stats);
    if (!at_start) {
      // Nothing solved: the whole row is one jam, its velocities are W^-.
      CHECK(start_stats.lcps == 0);
      for (int i = 0; i < n; ++i) CHECK(f.state[static_cast<std::size_t>(i)].vx == v);
    } else {
      CHECK(start_stats.lcps >= 1);
    }
    contact::CollisionStats stats;
    contact::SubstepReport report;
    contact::advance_with_collisions(f, shapes, det, dt, o, stats, report);
    CHECK(stats.failures == 0);
    if (!at_start) {
      // One time step of one LCP: the row translates (no turning), and no
      // wider witness is unmet. (Solved at the start, the row is at rest and
      // needs no sub-step.)
      CHECK(report.time_steps == 1);
      CHECK(stats.lcps == 1);
    }
    // Analytic: the wall holds the row, restitution 0 for a jam's contacts:
    // every floe stops (its contacts were within xi, so nothing may close).
    for (int i = 0; i < n; ++i) {
      const FloeState& s = f.state[static_cast<std::size_t>(i)];
      CHECK(std::abs(s.vx) < 1e-9);
      CHECK(std::abs(s.vy) < 1e-9);
      CHECK(std::abs(s.yaw_rate) < 1e-9);
    }
    // No pair overlaps at the end of the step.
    const contact::Detection after = contact::detect(f, shapes, detection_options(f, dt));
    for (const contact::NearPair& p : after.pairs) CHECK(!p.overlap);
  }
}

TEST_CASE("jam: a contact's target shortfall is its target minus its normal relative velocity") {
  Floes f;
  for (const FloeInput& in : {box(0.0, 0.0, 10.0, 10.0, 0.0), box(10.5, 0.0, 10.0, 10.0, -0.02)})
    f.add(make_floe_shape(in), in);
  // A speculative contact 0.5 m apart (normal from a to b, +x), closing at 2 cm/s.
  contact::ContactPoint c{0, 1, {10.25, 5.0}, {1.0, 0.0}, 0.5, {0.0, 0.0}, true, false};
  contact::ImpulseOptions o;
  o.speculative_step = 10.0;
  // It may close 0.9 (g - xi/2) over h: target -0.9 (0.5 - 0.005) / 10.
  const double target = -0.9 * (0.5 - 0.5 * o.collision_distance) / 10.0;
  CHECK(contact::normal_target(c, o) == doctest::Approx(target));
  CHECK(contact::target_shortfall(f, c, o) == doctest::Approx(target + 0.02));
  // Its turning adds turning / h to the target.
  c.turning = 0.1;
  CHECK(contact::normal_target(c, o) == doctest::Approx(target + 0.01));
}

TEST_CASE("jam: a warm start finds a contact's basis by its vertex and edge after it slid along the edge") {
  // Floe b (5 m tall) 5 mm right of floe a (10 m), closing at 1 mm/s: two
  // contacts, b's left vertices on a's right edge. Solved once (the basis is
  // stored), then b is put 1 m higher (its contact points slide 1 m along
  // a's edge, beyond match_distance) and closing again: the second LCP
  // starts from the stored basis (counted in CollisionStats::warm).
  Floes f;
  for (const FloeInput& in : {box(0.0, 0.0, 10.0, 10.0, 0.0), box(10.005, 2.0, 5.0, 5.0, -1e-3)})
    f.add(make_floe_shape(in), in);
  const contact::CollisionShapes shapes = contact::build_collision_shapes(f);
  contact::WarmStart warm;
  contact::ImpulseOptions o;
  o.restitution = 0.0;
  o.warm = &warm;
  o.warm_min = 1;
  contact::CollisionStats stats;
  const contact::Detection det = contact::detect(f, shapes, {});
  REQUIRE(det.contacts.size() == 2);
  for (const contact::ContactPoint& c : det.contacts) REQUIRE(c.vertex_of_b);
  contact::resolve_collisions(f, det.contacts, o, stats);
  CHECK(stats.lcps == 1);
  CHECK(stats.warm == 0);
  // Signorini: no contact approaches after the solve.
  for (const contact::ContactPoint& c : det.contacts) CHECK(contact::target_shortfall(f, c, o) <= 1e-12);
  f.state[1].y += 1.0;
  f.state[1].vx = -1e-3;
  f.state[0].vx = 0.0;
  const contact::Detection moved = contact::detect(f, shapes, {});
  REQUIRE(moved.contacts.size() == 2);
  for (std::size_t k = 0; k < 2; ++k) REQUIRE((moved.contacts[k].point - det.contacts[k].point).norm() > 0.9);
  contact::resolve_collisions(f, moved.contacts, o, stats);
  CHECK(stats.lcps == 2);
  CHECK(stats.warm == 1);
  CHECK(stats.failures == 0);
  for (const contact::ContactPoint& c : moved.contacts) CHECK(contact::target_shortfall(f, c, o) <= 1e-12);
}

TEST_CASE("jam: a time step whose LCP Lemke cannot finish within its pivot budget is answered by the fallback chain") {
  // The pushed row of the first test case, with Lemke's pivot limit cut to 3
  // (ImpulseOptions::solver.lemke.max_pivots; the default is
  // lemke_pivots_per_unknown n + 1000): Lemke stops at its limit on the jam's
  // LCP (200 unknowns, 51 pivots with the default), the chain goes on (the
  // contact-wise Gauss–Seidel from Lemke's end point, lcp/coulomb_gs.hpp), and
  // its answer is taken within ImpulseOptions::velocity_tolerance: no failed
  // LCP, the row stopped against the wall (x and turning) to that tolerance,
  // no overlap, and the x positions those of the default budget's answer to
  // velocity_tolerance dt. Along the wall (y) the fallback's answer is not
  // Lemke's: the row slides at about 1.2e-5 m/s (measured; each contact within
  // the velocity tolerance of Signorini and Coulomb), so y is bounded by
  // 1e-4 m/s only.
  const int n = 25;
  const double v = 1e-3, dt = 10.0;
  std::vector<FloeState> answer[2];
  for (const bool small_budget : {false, true}) {
    CAPTURE(small_budget);
    Floes f = pushed_row(n, v);
    const contact::CollisionShapes shapes = contact::build_collision_shapes(f);
    const contact::Detection det = contact::detect(f, shapes, detection_options(f, dt));
    contact::SubstepOptions o;
    o.impulse.restitution = 0.4;
    o.impulse.friction = 0.7;
    if (small_budget) o.impulse.solver.lemke.max_pivots = 3;
    const double tolerance = small_budget ? o.impulse.velocity_tolerance : 1e-9;
    contact::CollisionStats stats;
    contact::SubstepReport report;
    contact::advance_with_collisions(f, shapes, det, dt, o, stats, report);
    CHECK(report.time_steps == 1);
    CHECK(stats.lcps == 1);
    CHECK(stats.failures == 0);
    if (small_budget) {
      CHECK(stats.fallbacks == 1);
      CHECK(stats.gauss_seidel + stats.tolerated == 1);
    } else {
      CHECK(stats.fallbacks == 0);
      CHECK(stats.pivots > 3);
    }
    // Analytic, as in the first test case: the wall stops the whole row.
    for (int i = 0; i < n; ++i) {
      const FloeState& s = f.state[static_cast<std::size_t>(i)];
      CHECK(std::abs(s.vx) < tolerance);
      CHECK(std::abs(s.vy) < (small_budget ? 1e-4 : tolerance));
      CHECK(std::abs(s.yaw_rate) < tolerance);
    }
    const contact::Detection after = contact::detect(f, shapes, detection_options(f, dt));
    for (const contact::NearPair& p : after.pairs) CHECK(!p.overlap);
    answer[small_budget ? 1 : 0] = f.state;
  }
  const double apart = contact::ImpulseOptions{}.velocity_tolerance * dt;
  for (std::size_t i = 0; i < static_cast<std::size_t>(n); ++i) {
    CHECK(std::abs(answer[1][i].x - answer[0][i].x) < apart);
  }
}
