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
    const double approach = -n.dot(Vec2{b.vx - a.vx, b.vy - a.vy});
    const double s = std::max(0.0, approach) + std::abs(a.yaw_rate) * shapes.radius[p.a] +
                     std::abs(b.yaw_rate) * shapes.radius[p.b];
    if (!(s > 0.0)) continue;
    const double keep = 0.5 * std::min(d, xi);
    const double dt = (d - keep) / s;
    if (dt < limit.dt) limit = {dt, p.a, p.b, d};
  }
  return limit;
}

}  // namespace floesim::contact
