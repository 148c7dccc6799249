#pragma once
// Lemke's complementary pivoting method with the lexicographic minimum-ratio
// rule, applied within relative tolerances; revised (factorised basis) form.
//
// Contract. Given an LCP(M, q) (lcp.hpp) with M n x n, solve_lemke returns:
//   * Status::solved      z >= 0 with w = M z + q; the residual says how well
//                         (residual() in lcp.hpp; typically 1e-15 .. 1e-12);
//   * Status::ray         the method ended on a secondary ray: no entering column
//                         has a positive pivot (unless the point reached, z0
//                         dropped, solves the LCP within ray_accept_residual: a
//                         degenerate end where z0 sat at ~0 without leaving;
//                         that is reported solved). For a copositive-plus M (PSD, P,
//                         non-negative, ...) this proves the LCP infeasible;
//                         otherwise Lemke simply could not reach a solution;
//   * Status::pivot_limit more than options.max_pivots pivots;
//   * Status::failed      a basis became numerically singular.
// It never throws on numerical trouble; it throws floesim::RunError when the
// LCP itself is malformed (check_lcp). Deterministic: same input, same pivots.
//
// Mathematics. With a covering vector d > 0 and the artificial variable z0,
//
//     w = M z + q + d z0,   z, w, z0 >= 0,   z . w = 0.                  (1)
//
// If q >= 0, z = 0 solves the LCP (0 pivots). Otherwise z0 enters at the value
// max_i (-q_i / d_i), making w >= 0; the w_r that reached zero leaves, and from
// then on the entering variable is always the complement of the one that left
// (w_i <-> z_i). The leaving variable is chosen by the minimum-ratio test over
// the rows where the entering column u = B^-1 a is positive. The solution is
// found when z0 leaves; a column without positive entry is a secondary ray.
// Pivots are counted including the first (z0 entering) and the last (z0 leaving).
//
// Degeneracy. Ties in the ratio test are broken lexicographically: among the
// tied rows i, the one whose row of [x_B, B^-1] / u_i is lexicographically
// smallest leaves (equivalent to perturbing q by (eps, eps^2, ..., eps^n)); this
// rules out cycling. If z0 is among the tied rows it leaves at once.
// The revised form has no tableau: column j of B^-1 is e_p when w_j is basic at
// position p (so that column only disqualifies the tied row p), and otherwise is
// one solve B y = e_j, done only while ties remain.
// Tolerances are relative, never exact equality:
//   * a pivot u_i is eligible only if u_i > pivot_tolerance * ||u||_inf;
//   * basic values x_i <= zero_tolerance * ||x_B||_inf count as exactly zero
//     (degenerate rows), likewise entries of B^-1 columns relative to the column;
//   * two ratios t_i, t_k tie when they differ by at most
//     tie_tolerance * max(|t_i|, |t_k|).
// Without these, rounding turns a degenerate tie (0 versus 1e-17) into a
// "strict" choice of the wrong row, which ends on false rays or cycles on the
// Stewart–Trinkle friction LCPs.
//
// Cost per pivot: one solve with the factorised basis (lemke_basis.hpp) plus
// one per lexicographic tie-break column, instead of a dense tableau update.

#include "contact/lcp/basis_repair.hpp"
#include "contact/lcp/lcp.hpp"

namespace floesim::lcp {

// How the reduced basis is factorised: dense LU or sparse LU.
enum class Factorization { automatic, dense, sparse };

// Which sparse LU factorises a sparse reduced basis (lemke_basis.cpp):
//   * umfpack: UMFPACK (multifrontal, its automatic ordering strategy);
//   * klu:     KLU (left-looking Gilbert–Peierls after a block triangular
//              form and AMD; no supernodes: faster on the reduced bases of a
//              jam, a few tens of non-zeros per column).
// Both give the same answers up to rounding, but a jam's LCP is so
// degenerate that a different rounding may decide a tie otherwise and walk
// another pivot path (to another, equally valid, answer).
enum class SparseLu { umfpack, klu };

struct LemkeOptions {
  // d > 0, n entries; empty means all ones.
  Vector covering;
  // Pivot limit; 0 means 50 (n + 1) + 1000 (Murty's 2^n examples need more).
  long max_pivots = 0;
  double pivot_tolerance = 1e-9;   // relative to ||u||_inf
  double zero_tolerance = 1e-12;   // relative to ||x_B||_inf (and ||B^-1 e_j||_inf)
  double tie_tolerance = 1e-9;     // relative difference of tied ratios
  // At a secondary ray, the point reached with z0 dropped is reported solved
  // if its residual is at most this (a degenerate end: z0 at ~0 did not
  // leave); 0: never.
  double ray_accept_residual = 1e-9;
  Factorization factorization = Factorization::automatic;
  // automatic: at each refactorisation, the reduced basis C (k x k, k = number
  // of basic z's) goes to the sparse LU when k >= sparse_min_size and C has at most
  // sparse_max_density k^2 non-zeros, to dense LU otherwise (measured, see
  // docs/lcp.md).
  Index sparse_min_size = 120;
  double sparse_max_density = 0.1;
  // The sparse LU (above). KLU is there because a Lemke pivot in a creeping
  // jam spends about half its time refactorising C every refactor_interval
  // pivots and solving with its factors, both of which KLU does faster than
  // UMFPACK on a jam's C's (measured: docs/contact.md, sixth and seventh
  // rounds).
  SparseLu sparse_lu = SparseLu::klu;
  // Etas (pivots) between refactorisations of the basis.
  int refactor_interval = 100;
  // Warm start (null: none): the complementary basis to start from, z_j
  // basic where (*start)[j] (Result::z_basic of an earlier, similar LCP).
  // The covering vector is then d = B 1, so that z0 entering at
  // -min(B^-1 q) makes the start feasible; if B^-1 q >= 0 the start solves
  // the LCP with no pivot. d need not be positive, so Lemke's guarantees do
  // not hold: a warm start that ends on a ray or a singular basis is for the
  // caller to redo from scratch. `covering` is ignored.
  const std::vector<std::uint8_t>* start = nullptr;
  // A start basis that is singular (redundant contacts in a jam) is repaired
  // (basis_repair.hpp: its dependent z's turned to w's) and Lemke starts
  // again from the repair; rounds = 0: not repaired (the run ends failed).
  BasisRepairOptions repair_start{.tolerance = 1e-10, .rounds = 0};
};

// What the revised method did, for benchmarks and diagnostics.
struct LemkeStats {
  long sparse_refactorisations = 0;  // of `refactorisations`, how many used the sparse LU
  long solves = 0;            // solves with the basis (entering columns + tie-breaks)
  long tie_breaks = 0;        // pivots whose ratio test needed the lexicographic rule
  long refactorisations = 0;
};

Result solve_lemke(const Lcp& lcp, const LemkeOptions& options = {},
                   LemkeStats* stats = nullptr);

}  // namespace floesim::lcp
