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

}  // namespace

// Two equal squares (m each), the second coming at the first at v along -x,
// frictionless, restitution e: one impact whose normal impulse is the reduced
// mass times the change of the approach speed, (m/2)(1 + e) v, at the middle
// of the touching sides (x = 10).
TEST_CASE("collision events: a head-on impact records the impulse (m/2)(1 + e) v once, between the floes") {
  const std::string config = R"(
[run]
t_end = 2.0
dt_max = 0.05
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
vertices = [[10.5, 0], [20.5, 0], [20.5, 10], [10.5, 10]]
velocity = [-1.0, 0.0]
)";
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
