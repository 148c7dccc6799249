#pragma once
// Collision impulses: the velocity–impulse LCP with Stewart–Trinkle friction
// (Rabatel et al. 2015; report 002, eq. 3.5) and Poisson restitution, solved
// per connected component of the contact graph.
//
// For contact j between floes a and b (normal N_j from a to b, tangent
// T_j = k x N_j, point P_j), the relative velocity of b with respect to a at
// P_j along a unit vector u is  u . (v_b(P_j) - v_a(P_j)) = g_u W, where the
// row g_u has (u, (P_j - G_b) x u) in b's block and -(u, (P_j - G_a) x u) in
// a's. Stack the normal rows Gn (m x 3n) and the tangent rows Gt (2m x 3n: +T_j
// then -T_j per contact). With A the block-diagonal mass matrix (static floes:
// A^-1 = 0) and W^- the velocities before the collision, the unknowns
// z = (lambda [m], beta [2m], alpha [m]) >= 0 solve the LCP
//
//       | Gn A^-1 Gn^T   Gn A^-1 Gt^T   0 |       | Gn W^- |
//   M = | Gt A^-1 Gn^T   Gt A^-1 Gt^T   E |,  q = | Gt W^- |,
//       | mu I           -E^T           0 |       | 0      |
//
// E = blockdiag((1, 1)^T). Complementarity says: the normal relative
// velocity after the impulse is >= 0 and positive only where lambda = 0
// (Signorini, in velocities); alpha is the sliding speed, beta the friction
// impulse along +-T, at most mu lambda, and acting only against sliding
// (Coulomb). This is the compression phase (restitution 0), W^c = W^- +
// A^-1 (Gn^T lambda + Gt^T beta); Poisson's law then gives
//   W^+ = (1 + e) W^c - e W^-   (decompression impulse e times the compression one).
//
// Gap stabilisation: a contact whose gap g has fallen below min_gap (round-off
// and rotation make gaps creep down over many steps) asks for the small
// separating normal velocity (min_gap - g)/tau instead of 0, i.e.
// q_j -= (min_gap - g)/tau, with a fixed relaxation time tau (not the step:
// a short step must not turn a tiny gap error into a large velocity). Contacts
// at or above min_gap keep the exact Signorini condition (and the exact
// restitution law).
//
// Components are built from dynamic floes joined by contacts; an obstacle
// (static floe) does not join components since it transmits no impulse.

#include <cstdint>
#include <vector>

#include "contact/detection.hpp"
#include "contact/lcp/fallback.hpp"

namespace floesim::contact {

struct ImpulseOptions {
  double restitution = 0.4;  // e in [0, 1]
  double friction = 0.7;     // mu >= 0
  // A component is solved only if some contact approaches faster than this (m/s).
  double approach_tolerance = 1e-12;
  double min_gap = 0.0;      // m, see "gap stabilisation" above
  double relaxation_time = 10.0;  // s, tau of the gap stabilisation
  std::size_t dense_max = 400;  // LCPs up to this size are assembled dense, larger sparse
  lcp::FallbackOptions solver;
};

// Running totals of a run (written to /diagnostics/lcp and the summary).
struct CollisionStats {
  long contacts = 0;      // contact points in solved components
  long lcps = 0;          // LCP solves
  long pivots = 0;
  long failures = 0;      // solves that ended without an accepted solution
  long fallbacks = 0;     // solves that needed a fallback step
  long flagged = 0;       // of those, answered by projected Gauss–Seidel
  long largest = 0;       // largest LCP size
  long total_size = 0;    // sum of LCP sizes
};

// Per contact: the total impulse applied (compression + decompression), N s.
// Floe b received `vector` = normal N + tangential T at `point` (the contact's,
// in a's image of a periodic domain), floe a its opposite (percussion loads).
struct ContactImpulse {
  double normal = 0.0, tangential = 0.0;
  Vec2 vector = Vec2::Zero();  // N s, world
  Vec2 point = Vec2::Zero();   // m, world
};

// Changes the velocities of the floes in contact (W^- -> W^+). Returns the
// impulses, one per contact, in the order of `contacts`.
std::vector<ContactImpulse> resolve_collisions(Floes& floes, const std::vector<ContactPoint>& contacts,
                                               const ImpulseOptions& options, CollisionStats& stats);

}  // namespace floesim::contact
