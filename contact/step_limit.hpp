#pragma once
// Event-driven step control (MODEL.md §2): how long floes may move with their
// present velocities before a near pair could close its gap.
//
// For two floes translating with constant velocities, the distance d(t)
// between them is a convex function of t (the distance from a point moving on
// a line to a fixed convex set — their Minkowski difference — is convex), so
// d(t) >= d(0) + t n.(V_b - V_a), n the unit vector between the closest points.
// The same bound holds for the separation of the two floes along any fixed axis
// n, which is how pairs far apart are handled (their box gap, detection.hpp).
// Rotation moves a point at radius r from its centroid by at most |omega| r t.
// Hence, with R_a, R_b the floes' radii,
//   d(t) >= d(0) - t s,   s = max(0, -n.(V_b - V_a)) + |omega_a| R_a + |omega_b| R_b,
// and a pair keeps at least `keep` of its gap over dt <= (d - keep)/s. We keep
// half of the gap below the collision distance xi and let pairs further away
// come to xi/2:  keep = min(d, xi)/2. That bound is rigorous but pessimistic
// for floes in contact that turn slowly; for pairs whose closest points are
// known, the step uses d'(0) = n.(v_b(p_b) - v_a(p_a)) (exact, rotation
// included) and a bound kappa on d'' from the rotation rates (step_limit.cpp).
// The step itself re-detects after moving and redoes a step that overlapped,
// so no estimate here can let floes overlap.

#include <cstdint>
#include <limits>
#include <vector>

#include "contact/detection.hpp"

namespace floesim::contact {

struct StepLimit {
  double dt = std::numeric_limits<double>::infinity();  // s
  std::uint32_t a = 0, b = 0;  // the pair that sets it (when finite)
  double distance = 0.0;       // m, that pair's distance
};

StepLimit collision_step_limit(const Floes& floes, const CollisionShapes& shapes,
                               const std::vector<NearPair>& pairs, double collision_distance);

}  // namespace floesim::contact
