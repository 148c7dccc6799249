#include "contact/step_limit.hpp"

#include <cmath>

namespace floesim::contact {

StepLimit collision_step_limit(const Floes& floes, const CollisionShapes& shapes,
                               const std::vector<NearPair>& pairs, double xi) {
  StepLimit limit;
  for (const NearPair& p : pairs) {
    if (p.overlap) continue;  // reported by the caller's overlap check
    const FloeState &a = floes.state[p.a], &b = floes.state[p.b];
    const double d = p.distance;
    if (!(d > 0.0)) continue;
    const Vec2& n = p.normal;
    const double keep = 0.5 * std::min(d, xi);
    double dt;
    if (p.exact) {
      // Closest points known: d'(0) = n . (v_b(p_b) - v_a(p_a)) exactly, and the
      // second derivative is bounded by how fast rotation turns the relative
      // velocity: |d''| <= kappa = (|w_a| + |w_b|) (|V_b - V_a| + |w_a| R_a + |w_b| R_b).
      // Solve d - s1 t - kappa t^2 / 2 = keep for t.
      const Vec2 ra = p.pa - Vec2{a.x, a.y}, rb = p.pb - Vec2{b.x, b.y} - p.shift;
      const Vec2 va = Vec2{a.vx, a.vy} + a.yaw_rate * Vec2{-ra.y(), ra.x()};
      const Vec2 vb = Vec2{b.vx, b.vy} + b.yaw_rate * Vec2{-rb.y(), rb.x()};
      const double s1 = std::max(0.0, -n.dot(vb - va));
      const double kappa = (std::abs(a.yaw_rate) + std::abs(b.yaw_rate)) *
                           (Vec2{b.vx - a.vx, b.vy - a.vy}.norm() + std::abs(a.yaw_rate) * shapes.radius[p.a] +
                            std::abs(b.yaw_rate) * shapes.radius[p.b]);
      const double room = d - keep;
      if (kappa > 0.0) dt = 2.0 * room / (s1 + std::sqrt(s1 * s1 + 2.0 * kappa * room));
      else if (s1 > 0.0) dt = room / s1;
      else continue;
    } else {
      const double approach = -n.dot(Vec2{b.vx - a.vx, b.vy - a.vy});
      const double s = std::max(0.0, approach) + std::abs(a.yaw_rate) * shapes.radius[p.a] +
                       std::abs(b.yaw_rate) * shapes.radius[p.b];
      if (!(s > 0.0)) continue;
      dt = (d - keep) / s;
    }
    if (dt < limit.dt) limit = {dt, p.a, p.b, d};
  }
  return limit;
}

}  // namespace floesim::contact
