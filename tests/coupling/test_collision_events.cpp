// The collisions a run records ([run] record_collisions, /events/collisions):
// checked against the impulse of a head-on impact (momentum and Poisson's
// restitution law) and against the wind's push on a floe resting on a wall
// (momentum balance over the time it rests there).
#include <doctest/doctest.h>

#include <cmath>
#include <string>
#include <vector>

#include "coupling/simulation.hpp"

using namespace floesim;

TEST_SUITE_BEGIN("coupling");

namespace {

std::vector<CollisionEventRow> run_rows(Simulation& sim, double until) {
  std::vector<CollisionEventRow> rows;
  while (sim.time() < until) {
    sim.step(until);
    for (const CollisionEventRow& r : sim.take_collision_events()) rows.push_back(r);
  }
  return rows;
}

// Two 10 m squares `gap` m apart, the second coming at the first at v m/s
// along -x, frictionless, restitution 0.4, no sea, collisions recorded, steps
// of at most dt s.
std::string head_on(double v = 1.0, double gap = 0.5, double dt = 0.05) {
  const std::string x0 = std::to_string(10.0 + gap), x1 = std::to_string(20.0 + gap);
  return R"(
[run]
t_end = 2.0
dt_max = )" + std::to_string(dt) + R"(
output_interval = 1.0
record_collisions = true
[sea]
model = "none"
[forcing]
ocean_drag = 0.0
air_drag = 0.0
[contact]
restitution = 0.4
friction = 0.0
[[floes.floe]]
vertices = [[0, 0], [10, 0], [10, 10], [0, 10]]
[[floes.floe]]
vertices = [[)" + x0 + ", 0], [" + x1 + ", 0], [" + x1 + ", 10], [" + x0 + R"(, 10]]
velocity = [)" + std::to_string(-v) + R"(, 0.0]
)";
}

}  // namespace

// Two equal squares (m each), the second coming at the first at v along -x,
// frictionless, restitution e: one impact whose normal impulse is the reduced
// mass times the change of the approach speed, (m/2)(1 + e) v, at the middle
// of the touching sides (x = 10).
TEST_CASE("collision events: a head-on impact records the impulse (m/2)(1 + e) v once, between the floes") {
  const std::string config = head_on();
  Simulation sim(build_scenario(parse_config(config, "head_on.toml", ".")));
  const double m = sim.floes().mass[0], v = 1.0, e = 0.4;
  const std::vector<CollisionEventRow> rows = run_rows(sim, 2.0);
  REQUIRE(rows.size() == 1);
  const CollisionEventRow& r = rows.front();
  CHECK(r.floe_a == 0.0);
  CHECK(r.floe_b == 1.0);
  CHECK(r.resting == 0.0);
  CHECK(r.normal == doctest::Approx(0.5 * m * (1.0 + e) * v).epsilon(1e-9));
  CHECK(r.x == doctest::Approx(10.0).epsilon(1e-3));
  CHECK(r.y == doctest::Approx(5.0).epsilon(1e-6));
  // Met 0.5 m apart at 1 m/s: the impact falls in the step ending at 0.5 s.
  CHECK(r.time == doctest::Approx(0.5));
  // The floes' momenta agree with the recorded impulse.
  CHECK(sim.floes().state[0].vx == doctest::Approx(-r.normal / m).epsilon(1e-9));  // pushed along -x
}

// A stop 1e-15 s ahead of the clock (k dt and a record time computed another
// way differ so) is round-off, not a step (Simulation::step). Taken as a
// step, its contact targets divided by its length threw the CITEPH 79% array
// apart (validation/citeph, array79_T1.40_H80 stepped by run_until: 23,287
// speculative contacts at 4 m gaps, then out of memory). Here two floes
// 5 cm apart closing at 1 m/s: the sliver changes nothing, and the impact
// that follows is the one a run without it has.
TEST_CASE("a stop within round-off of the clock is reached without a step") {
  const std::string config = head_on();
  Simulation sim(build_scenario(parse_config(config, "sliver.toml", ".")));
  Simulation plain(build_scenario(parse_config(config, "sliver.toml", ".")));
  while (sim.time() < 0.45) sim.step(0.45);
  while (plain.time() < 0.45) plain.step(0.45);
  const std::vector<FloeState> before = sim.floes().state;
  const double t = sim.time(), sliver = std::nextafter(std::nextafter(t, 1.0), 1.0);
  CHECK(sim.step(sliver) == 0.0);
  CHECK(sim.time() == sliver);
  CHECK(sim.steps() == plain.steps());
  for (std::size_t i = 0; i < before.size(); ++i) {
    CHECK(sim.floes().state[i].x == before[i].x);
    CHECK(sim.floes().state[i].vx == before[i].vx);
  }
  while (sim.time() < 1.0) sim.step(1.0);
  while (plain.time() < 1.0) plain.step(1.0);
  CHECK(sim.floes().state[0].vx == doctest::Approx(plain.floes().state[0].vx).epsilon(1e-12));
  CHECK(sim.floes().state[1].vx == doctest::Approx(plain.floes().state[1].vx).epsilon(1e-12));
  CHECK(sim.floes().state[0].vx < 0.0);  // the impact happened
}

// A 20 m square at rest 5 mm from a static wall (closer than the collision
// distance xi = 10 mm, so it rests on it from the first step), pushed by a
// 20 m/s wind with no water drag: the force F = rho_a C_a U^2 A. Whatever the
// floe does, momentum gives m v_x(T) = F T - sum of the wall's normal
// impulses; the rows are resting contacts, one per step.
TEST_CASE("collision events: a floe resting on a wall records the wind's push as resting impulses") {
  const std::string config = R"(
[run]
t_end = 20.0
dt_max = 1.0
output_interval = 1.0
record_collisions = true
[sea]
model = "none"
[forcing]
wind = [20.0, 0.0]
ocean_drag = 0.0
[[floes.floe]]
vertices = [[0, 0], [20, 0], [20, 20], [0, 20]]
[[floes.floe]]
vertices = [[20.005, -5], [22, -5], [22, 25], [20.005, 25]]
static = true
)";
  Simulation sim(build_scenario(parse_config(config, "wall.toml", ".")));
  const double T = 20.0;
  const double force = 1.341 * 1.7e-3 * 20.0 * 20.0 * 400.0;  // N, [forcing] air_density and air_drag defaults
  const std::vector<CollisionEventRow> rows = run_rows(sim, T);
  REQUIRE(rows.size() >= 15);
  double sum = 0.0;
  for (const CollisionEventRow& r : rows) {
    CHECK(r.floe_a == 0.0);
    CHECK(r.floe_b == 1.0);
    CHECK(r.resting == 1.0);
    CHECK(r.x == doctest::Approx(20.0).epsilon(1e-3));
    sum += r.normal;
  }
  const double m = sim.floes().mass[0];
  MESSAGE("sum of normal impulses " << sum << " N s, F T = " << force * T << " N s, m v_x = " << m * sim.floes().state[0].vx);
  // The impulses are all the momentum the wall took (the run's own budget).
  CHECK(sum == doctest::Approx(-sim.momentum_budget().collisions.x()).epsilon(1e-9));
  CHECK(sum + m * sim.floes().state[0].vx == doctest::Approx(force * T).epsilon(1e-3));
}

// Resting contact or impact is decided by the approach speed against
// [contact] rest_speed (0.01 m/s), not by the step (contact/impulse.hpp). The
// head-on pair at 5 mm/s rests: restitution 0, the reduced mass times v,
// (m/2) v, recorded as a sustained force; at 2 cm/s it is an impact,
// (m/2)(1 + e) v. Each the same with steps of 0.05 s and of 2 s (the impact
// falls inside a step, in the sub-stepper's events, in both).
TEST_CASE("collision events: a contact rests or strikes by its approach speed, whatever the step") {
  const double e = 0.4;
  for (double dt : {0.05, 2.0}) {
    for (double v : {0.005, 0.02}) {
      CAPTURE(dt);
      CAPTURE(v);
      Simulation sim(build_scenario(parse_config(head_on(v, 0.05, dt), "rest.toml", ".")));
      const double m = sim.floes().mass[0];
      const bool slow = v <= 0.01;
      const std::vector<CollisionEventRow> rows = run_rows(sim, 0.05 / v + 3.0);
      REQUIRE(rows.size() >= 1);
      CHECK(rows.front().resting == (slow ? 1.0 : 0.0));
      double sum = 0.0;
      for (const CollisionEventRow& r : rows) sum += r.normal;
      CHECK(sum == doctest::Approx(0.5 * m * (slow ? 1.0 : 1.0 + e) * v).epsilon(1e-6));
      // Restitution 0 leaves the pair moving together at v/2; e = 0.4 parts them at e v.
      CHECK(sim.floes().state[1].vx - sim.floes().state[0].vx ==
            doctest::Approx(slow ? 0.0 : e * v).epsilon(1e-6).scale(v));
    }
  }
}
