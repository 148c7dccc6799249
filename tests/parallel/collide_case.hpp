#pragma once
// The step-start collisions' test case, shared by test_collide_share.cpp
// (shares played on one process) and collide_share_ranks.cpp (over the
// ranks mpirun starts), and the comparisons bit for bit the parallel tests
// share (states, collision counts, warm store, impulse record).
#include <algorithm>
#include <cstring>
#include <numeric>
#include <random>
#include <vector>

#include "contact/detection.hpp"
#include "contact/impulse.hpp"
#include "contact/shapes.hpp"
#include "core/floe.hpp"
#include "core/pack_generator.hpp"

namespace floesim::test {

struct CollideCase {
  Floes floes;                       // W^-
  std::vector<FloeState> start;      // the step's start, before its smooth forces
  contact::Detection detection;
  contact::ImpulseOptions options;
  contact::Domain domain;
  double dt = 10.0;
};

// `side` x `side` rows of four 10 m squares, 100 m apart in a periodic box,
// along x or y by turns, floes numbered in a shuffled order. In a row, A
// (0.2 to 1 m/s) touches B (0.1 m/s) 5 mm ahead of it and D touches C the
// same way from the other side; B and C are 0.1 to 1.5 m apart, a witness.
// The collisions throw B and C at each other: a speculative contact joins
// the two contact components, which are solved again together from W^-, so
// each row is one step group (and two contact components). The step's start
// had 60 % of the velocities.
inline CollideCase rows_of_four(unsigned seed, int side = 8) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> fast(0.2, 1.0), gap(0.1, 1.5);
  const double spacing = 100.0;
  std::vector<FloeInput> in;
  for (int m = 0; m < side * side; ++m) {
    const bool along_x = m % 2 == 0;
    const Vec2 at{spacing * (m % side) + 20.0, spacing * (m / side) + 20.0};
    const double g = gap(rng);
    const double x[4] = {0.0, 10.005, 20.005 + g, 30.01 + g};
    const double v[4] = {fast(rng), 0.1, -0.1, -fast(rng)};
    for (int k = 0; k < 4; ++k) {
      FloeInput f;
      const Vec2 o = along_x ? Vec2{at.x() + x[k] - 20.0, at.y()} : Vec2{at.x(), at.y() + x[k] - 20.0};
      f.vertices = {{o.x(), o.y()}, {o.x() + 10.0, o.y()}, {o.x() + 10.0, o.y() + 10.0}, {o.x(), o.y() + 10.0}};
      f.velocity = along_x ? Vec2{v[k], 0.0} : Vec2{0.0, v[k]};
      in.push_back(f);
    }
  }
  std::vector<std::size_t> order(in.size());
  std::iota(order.begin(), order.end(), 0);
  std::shuffle(order.begin(), order.end(), rng);
  CollideCase c;
  for (const std::size_t i : order) c.floes.add(make_floe_shape(in[i]), in[i]);
  c.start = c.floes.state;
  for (FloeState& s : c.start) {
    s.vx *= 0.6;
    s.vy *= 0.6;
  }
  c.domain = {true, 0.0, spacing * side, 0.0, spacing * side};
  contact::DetectionOptions d;
  d.domain = c.domain;
  d.horizon = c.dt;
  d.reach.assign(c.floes.size(), 6.0);  // m: pairs within 12 m, each row's own
  c.detection = contact::detect(c.floes, contact::build_collision_shapes(c.floes), d);
  c.options.collision_distance = d.collision_distance;
  c.options.min_gap = 0.1 * d.collision_distance;
  c.options.relaxation_time = c.dt;
  return c;
}

// The same states, bit for bit.
inline bool same_states(const std::vector<FloeState>& a, const std::vector<FloeState>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(FloeState)) == 0;
}

// The same collision counts: every one contact::collision_counts names.
inline bool same_stats(const contact::CollisionStats& a, const contact::CollisionStats& b) {
  const auto x = contact::collision_counts(a);
  const auto y = contact::collision_counts(b);
  for (std::size_t k = 0; k < x.size(); ++k)
    if (*x[k].second != *y[k].second) return false;
  return true;
}

// Two warm stores hold the same pairs, each with the same clock and the
// same entries to the bit, and the same uses.
inline bool same_store(const contact::WarmStart& a, const contact::WarmStart& b) {
  if (a.pairs.size() != b.pairs.size() || a.uses != b.uses || a.clock != b.clock) return false;
  for (const auto& [key, p] : a.pairs) {
    const auto it = b.pairs.find(key);
    if (it == b.pairs.end() || it->second.stored != p.stored || it->second.entries.size() != p.entries.size())
      return false;
    for (std::size_t k = 0; k < p.entries.size(); ++k) {
      const contact::WarmStart::Entry &x = p.entries[k], &y = it->second.entries[k];
      if (std::memcmp(x.body_point.data(), y.body_point.data(), 2 * sizeof(double)) != 0 ||
          std::memcmp(x.body_normal.data(), y.body_normal.data(), 2 * sizeof(double)) != 0 || x.basic != y.basic ||
          x.vertex_of_b != y.vertex_of_b)
        return false;
    }
  }
  return true;
}

// The same record: the same loads in the same order, field for field (the
// doubles bit for bit), the same event numbers and count.
inline bool same_record(const contact::ImpulseRecord& a, const contact::ImpulseRecord& b) {
  if (a.events != b.events || a.loads.size() != b.loads.size()) return false;
  auto bits = [](const Vec2& u, const Vec2& v) { return std::memcmp(u.data(), v.data(), 2 * sizeof(double)) == 0; };
  for (std::size_t k = 0; k < a.loads.size(); ++k) {
    const contact::ImpulseRecord::Load &x = a.loads[k], &y = b.loads[k];
    if (x.floe != y.floe || x.event != y.event || x.other != y.other || x.sustained != y.sustained ||
        std::memcmp(&x.normal, &y.normal, sizeof(double)) != 0 || !bits(x.point, y.point) ||
        !bits(x.impulse, y.impulse) || !bits(x.world, y.world))
      return false;
  }
  return true;
}

// The rows of four with their serial step-start collisions recorded: as
// jams of two floes solved at the step's start (`jams`: a jam's speculative
// points, segment 1 of the places) or not, the record begun after three
// earlier events (a redone try's, say), so that a merge must number on.
struct RecordedRows {
  CollideCase c;
  contact::ImpulseRecord record;  // the serial call's
  Floes floes;                    // W^+ of the serial call
  contact::CollisionStats stats;
};
inline RecordedRows recorded_rows_of_four(bool jams, unsigned seed = 7) {
  RecordedRows r{rows_of_four(seed), {}, {}, {}};
  if (jams) {
    r.c.options.jam.floes = 2;
    r.c.options.jam.at_step_start = true;
  }
  r.record.events = 3;
  r.floes = r.c.floes;
  contact::ImpulseOptions o = r.c.options;
  o.record = &r.record;
  contact::resolve_step_collisions(r.floes, r.c.start, r.c.detection, r.c.dt, o, r.stats);
  return r;
}

// A dense 400-floe pack in a 2000 m box (seeded), its floes moving at up to
// `speed` (m/s) each way and turning at up to 1e-3 `speed` rad/s: many small
// clusters, some merging, some floes joining.
inline GeneratedPack moving_generated_pack(unsigned seed, double speed, double concentration = 0.75) {
  PackOptions o;
  o.floes = 400;
  o.concentration = concentration;
  o.min_gap = 0.05;
  o.width = o.height = 2000.0;
  o.seed = seed;
  GeneratedPack g = generate_pack(o);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-speed, speed);
  for (FloeState& s : g.floes.state) {
    s.vx = u(rng);
    s.vy = u(rng);
    s.yaw_rate = 1e-3 * u(rng);
  }
  return g;
}

}  // namespace floesim::test
