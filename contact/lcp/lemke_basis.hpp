#pragma once
// Private to contact/lcp: the basis of Lemke's system and its factorisation
// (the "revised" method: no tableau is ever formed).
//
// Lemke's system, n equations in the 2n + 1 variables (w, z, z0):
//
//     I w - M z - d z0 = q,                                             (1)
//
// variable ids: w_i -> i, z_j -> n + j, z0 -> 2n. A basis B picks n of the
// columns of [I, -M, -d]; position p of the basis holds variable basis[p].
//
// Factorisation. Let B0 be the basis at the last refactorisation. Its unit
// columns e_i (basic w_i) need no work: with R the k rows NOT covered by a basic
// w and S the k positions holding z's or z0, B0 x = b splits into
//
//     C x_S = b_R,          C = [-M, -d](R, vars(S))   (k x k, "reduced basis")
//     x_{pos(w_i)} = b_i - sum_{s in S} a_{var(s)}(i) x_s   for the covered rows i,
//
// so only C is factorised: densely (Eigen partial-pivoting LU) or sparsely
// (UMFPACK or KLU), chosen at each refactorisation from k and the density of C (or
// fixed by the caller). k is the number of basic z's (plus z0), usually well
// below n.
//
// Updates. A pivot replaces the column at position r by a with u = B^-1 a, so
// B_new = B E with E = I + (u - e_r) e_r^T and B_new^-1 = E^-1 B^-1: the
// product form. Each pivot appends one eta vector (r, u); B^-1 b is then the
// reduced solve followed by the etas in order (and B^-T y the transposed etas
// in reverse order, then the transposed reduced solve). After `refactor_interval` etas the
// current basis is factorised afresh (bounds both the work per solve and the
// growth of rounding errors).
//
// Cost of a solve B^-1 b (n unknowns, k basic z's, E etas): the reduced solve
// (the factors of C), the covered rows (one pass over the entries of A(W, S),
// kept row by row from the last refactorisation) and the etas (E columns of n
// read, in one pass over x per group of up to four etas). In a jam u = B^-1 a is dense (a jam is one connected component, so C^-1
// spreads a column over all of it), so the etas are stored dense, in one block
// allocated once. A refactorisation of an unchanged basis (no eta since the
// last one) is skipped: it would give the same factors.
#include <cstdint>
#include <memory>
#include <vector>

#include "contact/lcp/lcp.hpp"
#include "contact/lcp/lemke.hpp"

namespace floesim::lcp::detail {

// A factorisation of the reduced basis C (k x k); k may be 0.
class ReducedFactor {
public:
  virtual ~ReducedFactor() = default;
  // Factorises C; false if C is (numerically) singular.
  virtual bool factor(const SparseMatrix& C) = 0;
  // x <- C^-1 x, x of length k.
  virtual void solve(double* x) = 0;
  // x <- C^-T x.
  virtual void solve_transposed(double* x) = 0;
};
std::unique_ptr<ReducedFactor> make_dense_factor();
std::unique_ptr<ReducedFactor> make_sparse_factor();  // UMFPACK
std::unique_ptr<ReducedFactor> make_klu_factor();     // KLU

// Which factorisation a refactorisation uses: `sparse_min_size` = 0 forces
// the sparse LU, a huge value forces dense LU; otherwise the sparse LU when k
// >= sparse_min_size and nnz(C) <= sparse_max_density k^2. The sparse LU is
// UMFPACK or KLU (`sparse_lu`).
struct FactorPolicy {
  Index sparse_min_size = 0;
  double sparse_max_density = 1.0;
  SparseLu sparse_lu = SparseLu::umfpack;
};

class LemkeBasis {
public:
  // M: the LCP matrix (columns are read), d: the covering vector; the initial
  // basis is all w (B = I).
  LemkeBasis(const SparseMatrix& M, const Vector& d, FactorPolicy policy, int refactor_interval);

  Index size() const { return n_; }
  int w_var(Index i) const { return static_cast<int>(i); }
  int z_var(Index j) const { return static_cast<int>(n_ + j); }
  int z0_var() const { return static_cast<int>(2 * n_); }
  bool is_w(int var) const { return var < n_; }
  // The complement of w_i is z_i and vice versa (z0 has none).
  int complement(int var) const;

  int variable_at(Index pos) const { return basis_[pos]; }
  Index position_of(int var) const { return position_[var]; }

  // a <- the column of `var` in (1).
  void column(int var, Vector& a) const;
  // x <- B^-1 x  (x enters indexed by rows, leaves indexed by positions).
  void solve(Vector& x);
  // y <- B^-T y (y enters indexed by positions, leaves indexed by rows); with
  // y = e_p on entry this is row p of B^-1.
  void solve_transposed(Vector& y);
  // out <- B x  (x indexed by positions, out by rows).
  void multiply(const Vector& x, Vector& out) const;

  // The pivot: `var` enters at position `pos`, u = B^-1 a_var (u(pos) != 0).
  // Returns false if a refactorisation it triggered found B singular.
  bool replace(Index pos, int var, const Vector& u);
  // Factorises the current basis afresh, dropping the etas (nothing to do when
  // no eta was added since the last factorisation).
  bool refactor();
  // Starts over from the complementary basis with z_j at position j where
  // z_basic[j], w_j elsewhere; false if it is singular.
  bool start_from(const std::vector<std::uint8_t>& z_basic);

  long solves() const { return solves_; }
  long refactorisations() const { return refactorisations_; }
  long sparse_refactorisations() const { return sparse_refactorisations_; }

private:
  void add_column(int var, double scale, Vector& t) const;  // t += scale * a_var
  double dot_column(int var, const Vector& y) const;        // a_var . y

  const SparseMatrix& M_;
  const Vector& d_;
  Index n_;
  FactorPolicy policy_;
  std::unique_ptr<ReducedFactor> dense_lu_, sparse_lu_;  // created when first used
  ReducedFactor* lu_ = nullptr;                           // the one factorising B0
  int refactor_interval_;

  std::vector<int> basis_;       // variable at each position
  std::vector<Index> position_;  // position of each variable, -1 when non-basic

  bool factorise();

  // The factorised basis B0: its positions holding z / z0, the uncovered rows R,
  // and for each covered row the position of its w.
  std::vector<Index> s_positions_;
  std::vector<int> s_vars_;
  std::vector<Index> r_rows_;
  std::vector<Index> w_rows_;        // rows covered by a basic w in B0
  std::vector<Index> w_positions_;   // ... and their positions
  // The coupling of the covered rows to S in (1): covered row c (row
  // w_rows_[c]) holds v_(c, s) for the z's or z0 at S-index s, in increasing s
  // (v = M(i, j) for z_j, d_i for z0; the entry of -[M, d] is -v), compressed
  // by rows.
  std::vector<Index> w_start_;
  std::vector<Index> w_s_;
  std::vector<double> w_v_;
  Vector w_values_;  // the covered rows' values during a solve
  // Work of factorise(), kept to avoid allocating: C, each row's index in R
  // and in W (-1 if not there), the fill pointers of A(W, S).
  SparseMatrix C_;
  std::vector<Index> reduced_row_, covered_row_, fill_;

  // The etas since B0: eta e is (eta_pos_[e], column e of eta_u_). The block
  // holds refactor_interval columns, allocated once.
  std::vector<Index> eta_pos_;
  DenseMatrix eta_u_;
  bool factored_ = false;  // B0 is the current basis (no eta since it was factorised)
  Vector scratch_;
  Vector reduced_;
  long solves_ = 0;
  long refactorisations_ = 0;
  long sparse_refactorisations_ = 0;
};

}  // namespace floesim::lcp::detail
