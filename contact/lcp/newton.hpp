#pragma once
// A semismooth Newton method on the natural map of the LCP (lcp.hpp), in its
// active-set form, with sparse factorisations: it changes many unknowns per
// iteration where Lemke changes one per pivot. The fallback chain
// (fallback.hpp) can run it first on large LCPs (off by default: see "Where
// it works" below).
//
// Mathematics. z solves LCP(M, q) exactly when the natural map
//
//     F(z) = min(z, M z + q)          (componentwise)
//
// is zero (lcp.hpp: the residual is ||F|| / (1 + ||q||)). F is piecewise
// linear; at z its generalised Jacobian picks, row by row, the row of M where
// w_i = (M z + q)_i < z_i (the set A, "active": z_i is to be determined by
// w_i = 0) and the row of the identity elsewhere (the set I: z_i = 0). The
// Newton step from z therefore lands, whatever z, on the point
//
//     z_I = 0,    M_AA z_A = -q_A,                                       (1)
//
// the complementary point of the basis "z_A basic" (the primal-dual
// active-set method of Hintermüller, Ito and Kunisch 2002 is this iteration
// without damping). The next A is read off F at the new point, and so on: an
// active set that is right gives F = 0 at once; the active set of a
// previous, similar LCP can be given as the first one (a warm start:
// `start`).
//
// Globalisation. The step to (1) is damped by backtracking on the merit
// phi(z) = ||F(z)||^2 / 2 (Armijo: phi(z + t d) <= (1 - 2 sigma t) phi(z),
// t = 1, 1/2, ..., at most `max_backtracks` halvings; w moves linearly with
// z, so a trial costs a vector update). When no step length decreases phi,
// the full step is taken (the active-set method's own step). There is no
// convergence guarantee for the matrices of frictional contact (not P, not
// monotone): a run that does not reach `tolerance` ends with pivot_limit (or
// failed on a breakdown), and the caller goes on with Lemke.
//
// Singular systems. With more contacts than a pack has degrees of freedom
// (jams: redundant contacts), M_AA is singular even where (1) has solutions.
// (1) is then solved by proximal-point iterations on one factorisation of
// M_AA + delta I, delta = regularisation * max(1, max_i |M_ii|):
//
//     x_{k+1} = x_k + (M_AA + delta I)^-1 (-q_A - M_AA x_k),
//
// started from the present z_A. For a consistent system this converges to a
// solution (on the range of M_AA the error shrinks by delta / (sigma + delta)
// per iteration for an eigenvalue sigma; on its null space x keeps the
// start's component, so the impulses change no more than they must); it
// stops when ||M_AA x + q_A||_inf <= refine_tolerance (1 + ||q||_2), when
// the defect no longer halves (an inconsistent (1), where x would only
// drift), or after `max_refinements`. An inconsistent (1) leaves w_A != 0,
// which the next active set sees; an active set that gives back the same
// point after a full step ends the run (Status::failed).
//
// Where it works (measured, docs/contact.md "Jam solver"): the frictionless
// Delassus LCPs and the Siconos problems of data/lcp, in 1 to 18 iterations
// (lcp_CPS_3, where Lemke ends on a ray, included). On the Stewart–Trinkle
// LCPs of frictional contact of 100 contacts and more it rarely converges,
// and on those of jams mostly only when its warm start is already right (one
// iteration): their active sets, read row by row, give inconsistent or
// nearly singular systems (a friction row alpha without its beta, redundant
// contacts of a jam), and the damped steps stall.
//
// Answer. z is returned with its negative entries (rounding, at most of the
// size of the residual) set to 0, and judged by the one residual of lcp.hpp:
// Status::solved when it is at most `tolerance`. z_basic is the final A (a
// guess for a later warm start; it need not be a nonsingular Lemke basis).
// Deterministic: the same input gives the same iterations.

#include <cstdint>
#include <vector>

#include "contact/lcp/lcp.hpp"

namespace floesim::lcp {

struct NewtonOptions {
  // Newton iterations (factorisations); pivot_limit after them.
  int max_iterations = 30;
  // On the residual of lcp.hpp.
  double tolerance = 1e-9;
  // delta of the proximal solves, relative to max(1, max_i |M_ii|): small
  // against the Delassus eigenvalues that matter (the collision LCPs are
  // scaled to a unit normal diagonal), large against rounding.
  double regularisation = 1e-10;
  int max_refinements = 30;
  double refine_tolerance = 1e-13;  // relative to 1 + ||q||_2
  // Armijo's sigma and the number of step halvings tried (0: the undamped
  // active-set method).
  double armijo = 1e-4;
  int max_backtracks = 6;
  // Warm start (null: none): the unknowns to start active, n flags
  // (Result::z_basic of an earlier, similar LCP, from this method or from
  // Lemke). None: the first active set is read off F at z = 0 (the rows
  // where q_i < 0).
  const std::vector<std::uint8_t>* start = nullptr;
  // A point to start from (empty: z = 0), e.g. a Gauss–Seidel approximation;
  // with no `start`, the first active set is read off F there, and the
  // proximal solves start from it.
  Vector start_point;
};

// What the method did, for benchmarks and diagnostics.
struct NewtonStats {
  long factorisations = 0;  // one per iteration
  long refinements = 0;     // proximal solves with those factorisations
  long backtracks = 0;      // step halvings
  long full_steps = 0;      // iterations where no damped step decreased the merit
  long changed = 0;         // unknowns that changed set, summed over iterations
};

// Result::iterations counts the Newton iterations; pivots is 0.
Result solve_newton(const Lcp& lcp, const NewtonOptions& options = {}, NewtonStats* stats = nullptr);

}  // namespace floesim::lcp
