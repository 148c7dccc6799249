#pragma once
// The robust LCP solve used by the contact layer: Lemke, and when Lemke does not
// deliver a solution, a fixed chain of fallbacks, every step recorded.
//
//   0. for LCPs of at least newton_min_size unknowns (0, the default: never):
//      the semismooth Newton method (newton.hpp), from options.newton.start
//      when given. It solves the frictionless (Delassus) LCPs of data/lcp in
//      a few iterations but not the Stewart–Trinkle LCPs of jams
//      (docs/contact.md, "Jam solver"), so the contact layer leaves it off;
//   0b. for Stewart–Trinkle LCPs (`friction` set) of at least
//      contact_newton_min_size unknowns (0, the default: never): the contact
//      Newton method (contact_newton.hpp), its first states read off
//      options.lemke.start when given. It solves the friction LCPs of
//      data/lcp/contact from z = 0 but is slower than Lemke's warm start on
//      the LCPs of jams, and often does not converge there (docs/contact.md,
//      "Jam solver, third round"), so the contact layer leaves it off;
//   1. Lemke from options.lemke.start when given (a warm start: Method::lemke_warm);
//      for Stewart–Trinkle LCPs (`friction` set), if that is not accepted
//      and warm_normal_retry (off by default), Lemke from the start's normal flags alone
//      (Method::lemke_warm_normal: each contact's lambda basic or not as in
//      the start, its beta+, beta-, alpha turned to their w's, a pattern
//      whose block is regular); then Lemke from scratch, covering vector of
//      ones (the options' own covering if given). On a jam, a warm start
//      that ends on a ray does so within a few pivots, and its normal flags
//      still hold most of the answer: on 9 such LCPs of jam_500 (252 to 2936
//      unknowns) Lemke from them took 130 to 2202 pivots against 150 to 4983
//      from scratch, 1.3 to 3.4 times fewer (docs/contact.md, fifth round);
//   2. for the Stewart–Trinkle LCPs of frictional contact (`friction` set):
//      contact-wise Gauss–Seidel (coulomb_gs.hpp) from the point where Lemke
//      ended, accepted on the same residual as Lemke's answers. It comes
//      before the other Lemke steps, which start again from scratch: on the
//      LCPs of a 500-floe jam (about 930 contacts) each of them took about
//      13,000 pivots and 6 s (docs/contact.md);
//   3. Lemke with another covering vector, d_i = 1 + (i mod 7) / 7, which
//      changes the path of the method (not its lexicographic safety);
//   4. Lemke on the regularised LCP(M + delta I, q), delta = regularisation *
//      max(1, max_i |M_ii|); accepted if its z solves the ORIGINAL LCP within
//      `accept_residual` (the residual is always computed with the original M);
//   5. projected Gauss–Seidel (pgs.hpp), flagged: its answer is approximate.
//
// A step succeeds when its status is solved and its residual (on the original
// LCP) is at most accept_residual; a "solved" above that counts as failed. The
// chain stops at the first success. If no step succeeds, the result is the
// attempt with the smallest residual, with that attempt's status (never
// solved); `attempts` says how each step ended.

#include <string>
#include <vector>

#include "contact/lcp/contact_newton.hpp"
#include "contact/lcp/coulomb_gs.hpp"
#include "contact/lcp/lemke.hpp"
#include "contact/lcp/newton.hpp"
#include "contact/lcp/pgs.hpp"

namespace floesim::lcp {

enum class Method { newton, contact_newton, lemke_warm, lemke_warm_normal, lemke, lemke_other_covering, lemke_regularised, coulomb_gs, pgs };
std::string_view to_string(Method method);

struct FallbackOptions {
  NewtonOptions newton;
  // Step 0 runs for LCPs of at least this many unknowns (0: never).
  Index newton_min_size = 0;
  ContactNewtonOptions contact_newton;
  // Step 0b runs for friction LCPs of at least this many unknowns (0: never).
  Index contact_newton_min_size = 0;
  LemkeOptions lemke;
  PgsOptions pgs;
  FrictionLayout friction;  // contacts = 0: not a Stewart–Trinkle LCP (no step 4)
  CoulombGsOptions coulomb_gs;
  double accept_residual = 1e-9;
  double regularisation = 1e-10;  // relative diagonal shift of step 3
  bool allow_pgs = true;
  // Step 1's second warm start, from the start's normal flags (above). Off
  // by default: with it the suite's 500-floe wall jam took 209,533 pivots
  // instead of 360,628 but was not at rest at 3000 s (a floe at 5.7e-4 m/s;
  // docs/contact.md, fifth round).
  bool warm_normal_retry = false;
};

struct Attempt {
  Method method;
  Status status;
  long pivots;      // or sweeps (PGS, Gauss–Seidel), or iterations (Newton)
  double residual;  // on the original LCP
};

struct FallbackResult {
  Result result;                  // the accepted (or best) attempt
  Method method = Method::lemke;  // which step produced it
  std::vector<Attempt> attempts;  // every step tried, in order
  bool flagged = false;           // the answer came from PGS (approximate)
  bool solved() const { return result.status == Status::solved; }
};

FallbackResult solve_with_fallbacks(const Lcp& lcp, const FallbackOptions& options = {});

}  // namespace floesim::lcp
