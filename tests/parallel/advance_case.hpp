#pragma once
// The advance's test cases, shared by test_advance_share.cpp (the advance
// by cluster owner and from the parts, shares played on one process) and
// test_onerank.cpp (the same with the run's warm store): a dense moving
// pack with its detection and sub-step options, and a row of five floes
// where two clusters take one free floe.
#include <cmath>
#include <utility>
#include <vector>

#include "contact/detection.hpp"
#include "contact/shapes.hpp"
#include "contact/substep.hpp"
#include "core/floe.hpp"
#include "core/pack_generator.hpp"
#include "tests/parallel/collide_case.hpp"

namespace floesim::test {

struct AdvanceCase {
  Floes floes;
  contact::CollisionShapes shapes;
  contact::Detection detection;
  contact::DetectionOptions detect_options;  // the detection's (detect_part)
  contact::SubstepOptions options;
  contact::Domain domain;
  double dt = 10.0;
};

// The 400-floe periodic pack of moving_generated_pack, its floes moving at
// up to `speed` (m/s) towards random neighbours: many small clusters, some
// merging, some floes joining. The reaches are Simulation::set_reach's
// with `speed` for the pack's rms; the floor 1e-3 dt.
inline AdvanceCase dense_advance_pack(double speed, unsigned seed, double concentration = 0.75) {
  GeneratedPack g = moving_generated_pack(seed, speed, concentration);
  AdvanceCase c;
  c.floes = std::move(g.floes);
  c.shapes = contact::build_collision_shapes(c.floes);
  c.domain = {true, g.window[0], g.window[1], g.window[2], g.window[3]};
  contact::DetectionOptions d;
  d.domain = c.domain;
  d.horizon = c.dt;
  d.reach.assign(c.floes.size(), 0.0);
  for (std::size_t i = 0; i < c.floes.size(); ++i) {  // as Simulation::set_reach
    const FloeState& s = c.floes.state[i];
    d.reach[i] = c.dt * (1.5 * (std::hypot(s.vx, s.vy) + std::abs(s.yaw_rate) * c.shapes.radius[i]) + 0.5 * speed) +
                 d.collision_distance;
  }
  c.detection = contact::detect(c.floes, c.shapes, d);
  c.detect_options = d;
  c.options.collision_distance = d.collision_distance;
  c.options.floor = 1e-3 * c.dt;
  c.options.domain = c.domain;
  c.options.impulse.collision_distance = d.collision_distance;
  c.options.impulse.min_gap = 0.1 * d.collision_distance;
  return c;
}

// In a row along x, 10 m squares: a1 (floe 0, 1 m/s) hits a2 (floe 1, at
// rest) 0.5 m ahead of it, and b1 (floe 2, -1 m/s) hits b2 (floe 3) the
// same way from the other side; j (floe 4, at rest) lies 7 m from a2 and
// from b2: free at the step's start (no hot pair), taken by both clusters
// once a2 and b2 rebound towards it (at 0.7 m/s: half the room, 3.5 m, at
// about 5.5 s; they would reach j after the 10 s step, so j never moves
// towards the other cluster). Serially the first cluster takes j and the
// second merges with it. Reaches of 6 m: pairs within 12 m (a2-j and b2-j,
// not a2-b2); an open plane.
inline AdvanceCase row_taking_one_free_floe() {
  auto box = [](double x0, double vx) {
    FloeInput f;
    f.vertices = {{x0, 0.0}, {x0 + 10.0, 0.0}, {x0 + 10.0, 10.0}, {x0, 10.0}};
    f.velocity = {vx, 0.0};
    return f;
  };
  AdvanceCase c;
  for (const FloeInput& in : {box(0.0, 1.0), box(10.5, 0.0), box(55.0, -1.0), box(44.5, 0.0), box(27.5, 0.0)})
    c.floes.add(make_floe_shape(in), in);
  c.shapes = contact::build_collision_shapes(c.floes);
  contact::DetectionOptions d;
  d.horizon = c.dt;
  d.reach.assign(c.floes.size(), 6.0);
  c.detection = contact::detect(c.floes, c.shapes, d);
  c.detect_options = d;
  c.options.floor = 1e-3 * c.dt;
  return c;
}

}  // namespace floesim::test
