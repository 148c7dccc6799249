#pragma once
// Event-driven step control (MODEL.md §2): how long floes may move with their
// present velocities before a near pair could close its gap.
//
// A pair's distance is bounded below, over a time t during which both floes
// keep their velocities, by a few "features", each
//   d_f(t) >= d_f + r_f t - kappa_f t^2 / 2,
// and the step keeps every feature above keep = min(d, xi)/2 (half of a gap
// below the collision distance xi; pairs further apart may come to xi/2).
// With w_a = |omega_a|, w_b = |omega_b| and R the floes' radii about their
// centroids, no two points of the floes approach faster than
// s = |V_b - V_a| + w_a R_a + w_b R_b. The features (detection.hpp):
//  * axis: a separation along a fixed axis n (box gap or separating axis):
//    every point moves along n at n.V -+ w R at most, so
//    r = n.(V_b - V_a) - w_a R_a - w_b R_b (or -s when the axis is not
//    known), kappa = 0;
//  * far: the least distance of the vertices that are not witnesses,
//    r = -s, kappa = 0;
//  * witness (vertex v, closest point q on the other floe, N = (q - v)/|q - v|):
//    the other floe lies behind the line through q normal to N, which moves
//    with it, so v's distance to that line bounds v's distance to the other
//    floe from below. Its rate is exactly N.(v_q - v_v), the normal relative
//    velocity of the two points (rotation included; positive when
//    separating), and in the line owner's frame the other floe's centroid
//    accelerates by at most w^2 |G_b - G_a| + 2 w |V_b - V_a| while its
//    vertices turn at w_a + w_b, so
//      kappa = 2 w |V_b - V_a| + w^2 (R_a + R_b + d) + (w_a + w_b)^2 max(R_a, R_b),
//    w = max(w_a, w_b) (either floe may own the line).
// Two convex parts first touch at a vertex of one of them, so while every
// feature stays positive they do not overlap: the limit is a bound, not an
// estimate. The time loop still re-measures after moving and redoes a step
// that overlapped (round-off, a floe outrunning its reach).
// Crediting separating witnesses (r > 0) is what lets a resting contact, which
// the collision LCP has just left separating or sliding, not limit the step.

#include <cstdint>
#include <limits>
#include <span>
#include <vector>

#include "contact/detection.hpp"

namespace floesim::contact {

struct StepLimit {
  double dt = std::numeric_limits<double>::infinity();  // s
  std::uint32_t a = 0, b = 0;  // the pair that sets it (when finite)
  double distance = 0.0;       // m, that pair's distance
};

// The longest time over which the pair stays above keep (infinite if it
// never closes). `witnesses` are the pair's own.
double pair_step_limit(const Floes& floes, const CollisionShapes& shapes, const NearPair& pair,
                       std::span<const Witness> witnesses, double collision_distance);

// How far above keep the pair's distance stays at least over [0, t]
// (negative: it may close below keep within t).
double pair_room(const Floes& floes, const CollisionShapes& shapes, const NearPair& pair,
                 std::span<const Witness> witnesses, double collision_distance, double t);

// The smallest pair_step_limit over `pairs` (their witnesses in `witnesses`).
StepLimit collision_step_limit(const Floes& floes, const CollisionShapes& shapes,
                               const std::vector<NearPair>& pairs, const std::vector<Witness>& witnesses,
                               double collision_distance);

// The closing of a contact over a step of length h that its linearised gap
// misses, from the turning of the floes (m, >= 0; 0 when the turning opens
// it). The collision LCP asks for a normal velocity at the contact point, so
// it sees the gap after h as linear, g + h v_n. With the floes' velocities
// kept over h (translation, yaw at a constant rate), the contact's two
// material points, A = P - N g/2 on a and B = P + N g/2 on b, and the line of
// the edge (through the point on the edge's floe e, normal N turning with e
// by omega_e h) give the gap after h as
//   g(h) = (R(omega_e h) N) . (B(h) - A(h)),
// exact while the vertex stays in front of the edge. Its second-order part is
// what matters: an edge at distance rho from its floe's centroid, turned by
// theta, moves a point in front of it by -(rho + g) theta^2/2 against the
// linear gap, while the vertex's own turning only opens it (its path curves
// towards its centroid). A 20 m arm turned by 0.05 rad in one step closes
// 2.5 cm: the creeping 500-floe jam (docs/contact.md) turned floes at up to
// 0.005 rad/s, and its 10 s time steps overlapped at gaps of 0.01 to 9 mm.
// Returns max(0, g_lin(h) - g(h)).
double turning_closing(const Floes& floes, const ContactPoint& contact, double h);

// A pair's own contact points and witnesses, in the lists it was measured into.
inline std::span<const ContactPoint> contacts_of(const NearPair& p, const std::vector<ContactPoint>& contacts) {
  return {contacts.data() + p.first_contact, p.contact_count};
}
inline std::span<const Witness> witnesses_of(const NearPair& p, const std::vector<Witness>& witnesses) {
  return {witnesses.data() + p.first_witness, p.witness_count};
}

}  // namespace floesim::contact
