#pragma once
// Projected Gauss–Seidel for the LCP (lcp.hpp): the last resort of the fallback
// chain, never a replacement for Lemke (it converges for symmetric positive
// (semi)definite M with a solution, slowly when M is ill-conditioned, and may not
// converge at all otherwise).
//
// One sweep, i = 0 .. n-1:   z_i <- max(0, z_i - w_i / M_ii),  w = M z + q
// kept current by a column update after each change. Stops when the residual
// (lcp.hpp) is at most `tolerance` (Status::solved), after `max_iterations`
// sweeps (Status::pivot_limit), or at once with Status::failed when some
// M_ii <= 0 (the projection is undefined). Result::iterations counts sweeps.

#include "contact/lcp/lcp.hpp"

namespace floesim::lcp {

struct PgsOptions {
  long max_iterations = 20000;
  double tolerance = 1e-9;   // on the scaled residual
  double relaxation = 1.0;   // over-relaxation factor omega in (0, 2)
  int check_every = 10;      // sweeps between residual evaluations
};

Result solve_pgs(const Lcp& lcp, const PgsOptions& options = {});

}  // namespace floesim::lcp
