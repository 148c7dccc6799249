#pragma once
// Contact-wise Gauss–Seidel for the Stewart–Trinkle LCP of 2D frictional
// contact (the nonsmooth Gauss–Seidel of Jean and Moreau): the fallback chain's
// step after Lemke for the collision LCPs (fallback.hpp), whose friction rows have a
// zero diagonal, so that the plain projected Gauss–Seidel (pgs.hpp) cannot
// run on them.
//
// The layout is the contact layer's (contact/impulse.hpp): m contacts, the
// unknowns z = (lambda [m], beta [2m], alpha [m]), the rows of contact k being
// k (normal), m + 2k and m + 2k + 1 (the tangent +T and -T) and 3m + k
// (friction cone: mu lambda_k - beta+_k - beta-_k). In 2D the two friction
// directions are the whole Coulomb cone, so with beta_k = beta+_k - beta-_k,
// u = W r + b the normal and tangential velocities (r = (lambda, beta) per
// contact, W and b read from the rows k and m + 2k of M and q), the LCP says
// per contact:
//   0 <= lambda  _|_  u_n >= 0,
//   |beta| <= mu lambda, with u_t = 0 when |beta| < mu lambda (sticking) and
//   beta = -sign(u_t) mu lambda when u_t != 0 (sliding),
//   alpha = |u_t| (the sliding speed).
// One sweep solves each contact's 2x2 problem exactly, the others held
// (separate: r = 0 if c_n >= 0, c = u - W_kk r_k; else stick: r = -W_kk^-1 c
// if it lies in the cone; else slide: lambda = -c_n / (W_nn - s mu W_nt),
// beta = -s mu lambda for the direction s = +-1 whose u_t has the sign of s).
// u is kept current by column updates. Every `check_every` sweeps, z is
// rebuilt from (lambda, beta, |u_t|) and judged by the LCP's own residual
// (lcp.hpp); Status::solved once it is at most `tolerance`, pivot_limit after
// max_sweeps. It converges for frictionless contact (W is positive
// semidefinite); with friction it usually does, without a guarantee, so its
// answer is only ever accepted on that residual.
//
// Started from an approximate solution (the fallback chain passes the best
// Lemke attempt), it polishes it: Lemke can reach a complementary basis of a
// jam's LCP whose final factorisation is too ill-conditioned to trust (rcond
// below 1e-15, redundant contacts), or end on a ray near a solution.

#include <cstddef>

#include "contact/lcp/contact_form.hpp"

namespace floesim::lcp {

struct CoulombGsOptions {
  long max_sweeps = 20000;
  int check_every = 10;
  double tolerance = 1e-9;  // on the LCP's residual (lcp.hpp)
};

// `start` (n entries, or empty for z = 0): a point to start from. Throws
// RunError if the LCP does not have the layout's size 4m.
Result solve_coulomb_gs(const Lcp& lcp, const FrictionLayout& layout, const Vector& start,
                        const CoulombGsOptions& options = {});

}  // namespace floesim::lcp
