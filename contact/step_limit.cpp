#include "contact/step_limit.hpp"

#include <algorithm>
#include <cmath>

namespace floesim::contact {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// d_f(t) >= d + r t - kappa t^2 / 2 (step_limit.hpp).
struct Feature {
  double d, r, kappa;
};

// First t > 0 at which d + r t - kappa t^2/2 reaches keep (infinite if never).
double time_to(const Feature& f, double keep) {
  const double room = f.d - keep;
  if (!(room > 0.0)) return 0.0;
  if (f.kappa > 0.0) {
    const double root = std::sqrt(f.r * f.r + 2.0 * f.kappa * room);
    return f.r < 0.0 ? 2.0 * room / (root - f.r) : (f.r + root) / f.kappa;
  }
  return f.r < 0.0 ? room / -f.r : kInf;
}

// Lowest value of d + r s - kappa s^2/2 - keep over s in [0, t].
double room_over(const Feature& f, double keep, double t) {
  return f.d - keep + std::min(0.0, f.r * t - 0.5 * f.kappa * t * t);
}

// Calls f(feature) for each feature of the pair (step_limit.hpp).
template <class F>
void for_each_feature(const Floes& floes, const CollisionShapes& shapes, const NearPair& p,
                      std::span<const Witness> witnesses, F&& f) {
  const FloeState &a = floes.state[p.a], &b = floes.state[p.b];
  const Vec2 ga{a.x, a.y}, gb = Vec2{b.x, b.y} + p.shift;
  const double ra = shapes.radius[p.a], rb = shapes.radius[p.b];
  const double wa = std::abs(a.yaw_rate), wb = std::abs(b.yaw_rate);
  const Vec2 dv{b.vx - a.vx, b.vy - a.vy};
  const double spin = wa * ra + wb * rb;
  const double s = dv.norm() + spin;
  if (p.axis_distance < kInf) f(Feature{p.axis_distance, p.axis_any ? -s : p.axis_normal.dot(dv) - spin, 0.0});
  if (p.far_distance < kInf) f(Feature{p.far_distance, -s, 0.0});
  if (witnesses.empty()) return;
  const double w = std::max(wa, wb);
  const double kappa = 2.0 * w * dv.norm() + w * w * (ra + rb + p.distance) + (wa + wb) * (wa + wb) * std::max(ra, rb);
  for (const Witness& x : witnesses)
    f(Feature{x.distance, x.normal.dot(arm_velocity(b, x.pb - gb) - arm_velocity(a, x.pa - ga)), kappa});
}

}  // namespace

double pair_step_limit(const Floes& floes, const CollisionShapes& shapes, const NearPair& p,
                       std::span<const Witness> witnesses, double xi) {
  // Overlaps are the caller's to report; floes exactly touching (no normal)
  // are left to the overlap check, as no bound applies.
  if (p.overlap || !(p.distance > 0.0)) return kInf;
  const double keep = 0.5 * std::min(p.distance, xi);
  double t = kInf;
  for_each_feature(floes, shapes, p, witnesses, [&](const Feature& f) { t = std::min(t, time_to(f, keep)); });
  return t;
}

double pair_room(const Floes& floes, const CollisionShapes& shapes, const NearPair& p,
                 std::span<const Witness> witnesses, double xi, double t) {
  if (p.overlap || !(p.distance > 0.0)) return 0.0;
  const double keep = 0.5 * std::min(p.distance, xi);
  double room = kInf;
  for_each_feature(floes, shapes, p, witnesses, [&](const Feature& f) { room = std::min(room, room_over(f, keep, t)); });
  return room;
}

StepLimit collision_step_limit(const Floes& floes, const CollisionShapes& shapes, const std::vector<NearPair>& pairs,
                               const std::vector<Witness>& witnesses, double xi) {
  StepLimit limit;
  for (const NearPair& p : pairs) {
    if (p.overlap) continue;  // reported by the caller's overlap check
    const double dt = pair_step_limit(floes, shapes, p, witnesses_of(p, witnesses), xi);
    if (dt < limit.dt) limit = {dt, p.a, p.b, p.distance};
  }
  return limit;
}

double turning_closing(const Floes& floes, const ContactPoint& c, double h) {
  const FloeState& sa = floes.state[c.a];
  const FloeState& sb = floes.state[c.b];
  const Vec2 ga{sa.x, sa.y};
  const Vec2 gb = Vec2{sb.x, sb.y} + c.shift;  // b's image next to a
  const Vec2 pa = c.point - 0.5 * c.gap * c.normal;
  const Vec2 pb = c.point + 0.5 * c.gap * c.normal;
  // Straight-line and turned positions of a material point at P, arm r = P - G.
  // (Vec2 returns: an Eigen expression would outlive its temporaries.)
  auto linear = [h](const FloeState& s, const Vec2& g, const Vec2& p) -> Vec2 { return p + h * arm_velocity(s, p - g); };
  auto turned = [h](const FloeState& s, const Vec2& g, const Vec2& p) -> Vec2 {
    return g + h * Vec2{s.vx, s.vy} + rotate(p - g, h * s.yaw_rate);
  };
  const double g_linear = c.normal.dot(linear(sb, gb, pb) - linear(sa, ga, pa));
  const double edge_turn = h * (c.vertex_of_b ? sa.yaw_rate : sb.yaw_rate);
  const double g_turned = rotate(c.normal, edge_turn).dot(turned(sb, gb, pb) - turned(sa, ga, pa));
  return std::max(0.0, g_linear - g_turned);
}

}  // namespace floesim::contact
