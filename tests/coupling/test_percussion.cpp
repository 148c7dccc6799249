// Fracture in a run (MODEL.md §5 step 5, §6): a collision initiates a crack,
// the struck floes split, and the run carries on with the pieces: mass,
// momentum and angular momentum are conserved through the split (collisions
// conserve them too when nothing else acts), and no two floes overlap.
#include <doctest/doctest.h>

#include <cmath>

#include "coupling/simulation.hpp"

using namespace floesim;

TEST_SUITE_BEGIN("coupling");

namespace {

std::string scenario(bool split) {
  return std::string(R"(
[run]
t_end = 4.0
dt_max = 0.05
output_interval = 1.0
[sea]
model = "none"
[forcing]
ocean_drag = 0.0
air_drag = 0.0
[contact]
restitution = 0.4
friction = 0.3
[[floes.floe]]
vertices = [[0, 0], [40, 0], [40, 30], [0, 30]]
[[floes.floe]]
vertices = [[-12, 15], [-4, 11], [-0.5, 15.5], [-4, 19]]
velocity = [2.0, 0.1]
angular_velocity = 0.01
[fracture]
enabled = true
mesh_size = 1.5
split = )") + (split ? "true" : "false") + "\n";
}

struct Totals {
  double mass = 0.0, angular = 0.0;
  Vec2 momentum = Vec2::Zero();
};
Totals totals(const Floes& f) {
  Totals t;
  for (std::size_t i = 0; i < f.size(); ++i) {
    const FloeState& s = f.state[i];
    t.mass += f.mass[i];
    t.momentum += f.mass[i] * Vec2{s.vx, s.vy};
    t.angular += f.inertia_z[i] * s.yaw_rate + f.mass[i] * (s.x * s.vy - s.y * s.vx);
  }
  return t;
}

}  // namespace

TEST_CASE("percussion in a run: a collision splits floes that carry on without overlap, conserving momentum") {
  Simulation sim(build_scenario(parse_config(scenario(true), "percussion.toml", ".")));
  const Totals before = totals(sim.floes());
  std::vector<FractureEventRow> events;
  while (sim.time() < 4.0) {
    sim.step(4.0);
    for (const auto& e : sim.take_fracture_events()) events.push_back(e);
  }
  REQUIRE(!events.empty());
  const PercussionStats* stats = sim.percussion_stats();
  REQUIRE(stats != nullptr);
  CHECK(stats->splits >= 1);
  CHECK(sim.floes().size() == 2 + static_cast<std::size_t>(stats->splits));
  for (const FractureEventRow& e : events) {
    CHECK(e.stress >= 0.5e6);
    CHECK(e.piece_a >= 2.0);
    CHECK(e.piece_b == e.piece_a + 1.0);
    CHECK(e.load > 0.0);
  }
  const Totals after = totals(sim.floes());
  CHECK(after.mass == doctest::Approx(before.mass).epsilon(1e-13));
  CHECK((after.momentum - before.momentum).norm() < 1e-9 * before.momentum.norm());
  CHECK(std::abs(after.angular - before.angular) < 1e-9 * std::abs(before.angular));
  // Every pair apart at the end (the step's own check threw otherwise).
  for (const contact::NearPair& p : sim.detection().pairs) CHECK_FALSE(p.overlap);
  // The pieces moved on: the run went on for seconds after the split.
  CHECK(sim.time() == doctest::Approx(4.0));
}

TEST_CASE("percussion in a run: without split the event is recorded and the floes stay whole") {
  Simulation sim(build_scenario(parse_config(scenario(false), "percussion.toml", ".")));
  std::size_t events = 0;
  while (sim.time() < 1.0) {
    sim.step(1.0);
    events += sim.take_fracture_events().size();
  }
  CHECK(events >= 1);
  CHECK(sim.floes().size() == 2);
  CHECK(sim.percussion_stats()->splits == 0);
}

TEST_SUITE_END();
