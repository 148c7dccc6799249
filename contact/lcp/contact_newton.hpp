#pragma once
// A nonsmooth Newton method on the contact form of 2D frictional contact
// (contact_form.hpp), for the large Stewart–Trinkle LCPs of jammed packs,
// with a proximal-point regularisation for their redundant contacts and
// sparse LU factorisations (UMFPACK). The fallback chain (fallback.hpp) can
// run it before Lemke on large friction LCPs.
//
// Mathematics. Per contact k, r_k = (lambda_k, beta_k) and u = W r + b. The
// Alart–Curnier function, with per-contact parameters c_n = 1/W_nn,k and
// c_t = 1/W_tt,k (so that c u is an impulse of the size of r),
//
//   F_n = lambda - max(0, lambda - c_n u_n),
//   F_t = beta - proj([-mu L, mu L], beta - c_t u_t),   L = max(0, lambda - c_n u_n),
//
// is zero exactly when r satisfies Signorini's and Coulomb's laws. It is
// piecewise smooth, and each piece is a whole contact's state, read off the
// augmented impulses at the present r:
//   separated  (L = 0):                            lambda = 0, beta = 0;
//   sticking   (|beta - c_t u_t| <= mu L):         u_n = 0,    u_t = 0;
//   sliding    (s = sign(beta - c_t u_t), beyond):  u_n = 0,    beta = s mu lambda.
// (Choosing states contact by contact, where the LCP's natural map chooses
// row by row, never makes a friction row active without its normal one: the
// failure of the LCP Newton method, newton.hpp.) On one piece the equations
// are linear, so the Newton step lands on the solution of that piece's
// linear system; the method alternates "choose the states at r" and "solve
// their system" (a primal-dual active-set method). A point where the states
// chosen give back the same r is a solution: each state's system together
// with the inequalities that chose it is Signorini–Coulomb for that contact.
//
// Redundant contacts: proximal points. In a jam W = J A^-1 J^T is singular
// (more contact rows than the floes have degrees of freedom), and a state's
// system may be singular or inconsistent (redundant contacts asked for
// velocities the floes cannot all have). The method therefore solves a
// sequence of regularised problems, each the contact problem with W + eps I
// and b - eps r_c around a centre r_c (the proximal-point method):
//
//   u_eps(r) = W r + b + eps (r - r_c),   Signorini–Coulomb in (r, u_eps).
//
// Its state systems are nonsingular for eps > 0 (on the sticking blocks;
// sliding columns W_n + s mu W_t could in principle spoil it, and a failed
// factorisation makes eps grow). The active-set iteration runs on the
// regularised problem (states chosen at u_eps) until the states repeat
// (then r solves it exactly) or `max_inner` solves; then the centre moves to
// r. A fixed point r = r_c solves the original problem, and for a fixed set
// of states the centres converge on the range of W by eps / (sigma + eps)
// per centre (sigma an eigenvalue of W) while the null-space part of r (how
// redundant contacts share their load) stays where it was. eps adapts: when
// the states did not settle within max_inner solves it is multiplied by
// `proximal_growth` (at most proximal_max: smaller, damped steps); when they
// settled within `shrink_after` solves it is divided by it (at least
// `proximal`: faster convergence of the centres). With the states and eps
// unchanged the factorisation is reused, so a settled state set costs one
// pair of triangular solves per centre.
//
// Answer and acceptance. r is turned into the LCP's unknowns (lambda, beta+,
// beta-, alpha = |u_t|: contact_form.hpp, lcp_point) and judged by the one
// residual of lcp.hpp; Status::solved when it is at most `tolerance`,
// pivot_limit after max_iterations, failed on a breakdown (a factorisation
// that fails at proximal_max, non-finite values). There is no global
// convergence guarantee (frictional contact is not monotone), so the caller
// never accepts an answer above the tolerance and goes on with its chain.
// z_basic is the basis the states imply (lambda basic where in contact; one
// of beta+/beta- where |beta| > 0; alpha where sliding; the w's elsewhere):
// a guess for a later warm start.
//
// Start. From `start` (Lemke basis flags of an earlier, similar LCP: the
// contact layer's warm start) the first states are read off the flags
// (lambda basic: in contact; alpha basic: sliding in the direction of the
// basic beta; otherwise sticking); from `start_point` (an LCP point) or
// z = 0 they are chosen by the Alart–Curnier rule at that point. Optionally
// `gs_sweeps` sweeps of the contact-wise Gauss–Seidel (coulomb_gs.hpp) move
// the start point first.
// Deterministic: the same input gives the same iterations.

#include <cstdint>
#include <vector>

#include "contact/lcp/contact_form.hpp"

namespace floesim::lcp {

struct ContactNewtonOptions {
  // Linear solves (each a factorisation or a reuse of one); pivot_limit after them.
  int max_iterations = 60;
  // On the residual of lcp.hpp.
  double tolerance = 1e-9;
  // eps of the proximal steps, relative to max(1, max_i W_ii) (the collision
  // LCPs are scaled to a unit normal diagonal), its floor and ceiling.
  double proximal = 1e-8;
  double proximal_max = 1.0;
  double proximal_growth = 10.0;
  // Active-set iterations per proximal centre before the centre moves anyway
  // (and eps grows: the states cycled).
  int max_inner = 8;
  // eps at the start (relative, as `proximal`), and shrunk by proximal_growth
  // after a centre whose states settled within shrink_after solves.
  double proximal_start = 1e-2;
  int shrink_after = 4;
  // Contact-wise Gauss–Seidel sweeps before the first state choice (0: none).
  long gs_sweeps = 0;
  // Warm start: Lemke basis flags, n of them (null: none).
  const std::vector<std::uint8_t>* start = nullptr;
  // A point to start from (empty: z = 0).
  Vector start_point;
};

struct ContactNewtonStats {
  long factorisations = 0;
  long solves = 0;          // linear solves (iterations), factorised or not
  long rejected = 0;        // times eps grew
  long state_changes = 0;   // contacts that changed state, summed over iterations
};

// Result::iterations counts the linear solves; pivots is 0. Throws RunError
// when the LCP does not have the layout's 4m unknowns, or a start of the wrong size.
Result solve_contact_newton(const Lcp& lcp, const FrictionLayout& layout, const ContactNewtonOptions& options = {},
                            ContactNewtonStats* stats = nullptr);

}  // namespace floesim::lcp
