#include "contact/lcp/lemke_basis.hpp"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <klu.h>
#include <umfpack.h>

namespace floesim::lcp::detail {

// ---------------------------------------------------------------------------
// Reduced-basis factorisations.

namespace {

// Reciprocal condition estimates below this mean "singular" for the basis: a
// lexicographic pivot never produces such a basis in exact arithmetic, so this
// only catches breakdown.
constexpr double kSingularRcond = 1e-15;

class DenseFactor final : public ReducedFactor {
public:
  bool factor(const SparseMatrix& C) override {
    k_ = C.rows();
    if (k_ == 0) return true;
    dense_ = DenseMatrix(C);
    lu_.compute(dense_);
    return lu_.rcond() > kSingularRcond;
  }
  void solve(double* x) override {
    if (k_ == 0) return;
    Eigen::Map<Vector> v(x, k_);
    v = lu_.solve(v);
  }
  void solve_transposed(double* x) override {
    if (k_ == 0) return;
    Eigen::Map<Vector> v(x, k_);
    v = lu_.transpose().solve(v);
  }

private:
  Index k_ = 0;
  DenseMatrix dense_;
  Eigen::PartialPivLU<DenseMatrix> lu_;
};

// UMFPACK without iterative refinement (the etas and the final refinement in
// the Lemke driver take care of accuracy), solving through preallocated work.
class UmfpackFactor final : public ReducedFactor {
public:
  UmfpackFactor() {
    umfpack_di_defaults(control_);
    control_[UMFPACK_IRSTEP] = 0;
  }
  ~UmfpackFactor() override { release(); }
  UmfpackFactor(const UmfpackFactor&) = delete;
  UmfpackFactor& operator=(const UmfpackFactor&) = delete;

  bool factor(const SparseMatrix& C) override {
    release();
    C_ = C;
    C_.makeCompressed();
    const int k = static_cast<int>(C_.rows());
    k_ = k;
    if (k == 0) return true;
    void* symbolic = nullptr;
    int status = umfpack_di_symbolic(k, k, C_.outerIndexPtr(), C_.innerIndexPtr(),
                                     C_.valuePtr(), &symbolic, control_, info_);
    if (status != UMFPACK_OK) {
      umfpack_di_free_symbolic(&symbolic);
      return false;
    }
    status = umfpack_di_numeric(C_.outerIndexPtr(), C_.innerIndexPtr(), C_.valuePtr(),
                                symbolic, &numeric_, control_, info_);
    umfpack_di_free_symbolic(&symbolic);
    if (status != UMFPACK_OK || !(info_[UMFPACK_RCOND] > kSingularRcond)) return false;
    wi_.resize(static_cast<std::size_t>(k));
    // UMFPACK asks for n doubles without iterative refinement and 5 n with
    // it; take the larger so a change of Control can never overrun.
    w_.resize(5 * static_cast<std::size_t>(k));
    rhs_.resize(k);
    return true;
  }
  void solve(double* x) override { solve_system(UMFPACK_A, x); }
  void solve_transposed(double* x) override { solve_system(UMFPACK_Aat, x); }

private:
  void solve_system(int system, double* x) {
    if (k_ == 0) return;
    rhs_ = Eigen::Map<Vector>(x, k_);
    umfpack_di_wsolve(system, C_.outerIndexPtr(), C_.innerIndexPtr(), C_.valuePtr(), x,
                      rhs_.data(), numeric_, control_, info_, wi_.data(), w_.data());
  }
  void release() {
    if (numeric_) umfpack_di_free_numeric(&numeric_);
    numeric_ = nullptr;
  }
  double control_[UMFPACK_CONTROL];
  double info_[UMFPACK_INFO];
  SparseMatrix C_;
  Index k_ = 0;
  void* numeric_ = nullptr;
  std::vector<int> wi_;
  std::vector<double> w_;
  Vector rhs_;
};

// KLU (SuiteSparse; Davis and Palamadai Natarajan, ACM TOMS 37(3), 2010): a
// left-looking (Gilbert–Peierls) sparse LU after a block triangular form and an
// AMD ordering of each block, with row scaling by the largest entry; no
// supernodes or frontal matrices. On the reduced bases of a jam (k ~ 1300, a
// few tens of non-zeros per column) it factorises and solves faster than
// UMFPACK (docs/contact.md, sixth and seventh rounds). Its rounding differs
// from UMFPACK's, so a degenerate LCP may walk another pivot path.
class KluFactor final : public ReducedFactor {
public:
  // Threshold partial pivoting: the diagonal is kept as the pivot while it is
  // at least this fraction of the largest entry of its column (UMFPACK's
  // default threshold too). KLU's own default, 0.001, lets the factors grow
  // enough that Lemke decides ties of its ratio test otherwise on a
  // degenerate LCP of the Siconos collection (docs/contact.md, seventh round).
  static constexpr double kPivotThreshold = 0.1;

  KluFactor() {
    klu_defaults(&common_);
    common_.tol = kPivotThreshold;
  }
  ~KluFactor() override { release(); }
  KluFactor(const KluFactor&) = delete;
  KluFactor& operator=(const KluFactor&) = delete;

  bool factor(const SparseMatrix& C) override {
    release();
    k_ = static_cast<int>(C.rows());
    if (k_ == 0) return true;
    const SparseMatrix* A = &C;
    if (!C.isCompressed()) {
      compressed_ = C;
      compressed_.makeCompressed();
      A = &compressed_;
    }
    // KLU's arguments are not const but are only read.
    int* Ap = const_cast<int*>(A->outerIndexPtr());
    int* Ai = const_cast<int*>(A->innerIndexPtr());
    double* Ax = const_cast<double*>(A->valuePtr());
    symbolic_ = klu_analyze(k_, Ap, Ai, &common_);
    if (!symbolic_) return false;
    numeric_ = klu_factor(Ap, Ai, Ax, symbolic_, &common_);  // null when singular
    if (!numeric_ || common_.status != KLU_OK) return false;
    // min |U_ii| / max |U_ii|, the estimate UMFPACK's RCOND also is.
    klu_rcond(symbolic_, numeric_, &common_);
    return common_.rcond > kSingularRcond;
  }
  void solve(double* x) override {
    if (k_ > 0) klu_solve(symbolic_, numeric_, k_, 1, x, &common_);
  }
  void solve_transposed(double* x) override {
    if (k_ > 0) klu_tsolve(symbolic_, numeric_, k_, 1, x, &common_);
  }

private:
  void release() {
    if (numeric_) klu_free_numeric(&numeric_, &common_);
    if (symbolic_) klu_free_symbolic(&symbolic_, &common_);
    numeric_ = nullptr;
    symbolic_ = nullptr;
  }
  klu_common common_;
  klu_symbolic* symbolic_ = nullptr;
  klu_numeric* numeric_ = nullptr;
  SparseMatrix compressed_;
  int k_ = 0;
};

}  // namespace

std::unique_ptr<ReducedFactor> make_dense_factor() { return std::make_unique<DenseFactor>(); }
std::unique_ptr<ReducedFactor> make_sparse_factor() { return std::make_unique<UmfpackFactor>(); }
std::unique_ptr<ReducedFactor> make_klu_factor() { return std::make_unique<KluFactor>(); }

// ---------------------------------------------------------------------------
// The basis.

LemkeBasis::LemkeBasis(const SparseMatrix& M, const Vector& d, FactorPolicy policy,
                       int refactor_interval)
    : M_(M), d_(d), n_(M.rows()), policy_(policy), refactor_interval_(refactor_interval),
      basis_(static_cast<std::size_t>(n_)), position_(static_cast<std::size_t>(2 * n_ + 1), -1),
      eta_u_(n_ + (n_ & 1), std::max(1, refactor_interval)), scratch_(n_) {
  // The eta block's leading dimension is even, so every column starts on a
  // 16-byte boundary, as a vector of its own would: the dot products of the
  // transposed etas then add in the same order.
  eta_pos_.reserve(static_cast<std::size_t>(std::max(1, refactor_interval)));
  for (Index i = 0; i < n_; ++i) {
    basis_[i] = w_var(i);
    position_[w_var(i)] = i;
  }
  refactor();  // B = I: nothing to factorise, but it sets up the bookkeeping
}

bool LemkeBasis::start_from(const std::vector<std::uint8_t>& z_basic) {
  std::fill(position_.begin(), position_.end(), -1);
  for (Index i = 0; i < n_; ++i) {
    basis_[i] = z_basic[static_cast<std::size_t>(i)] ? z_var(i) : w_var(i);
    position_[basis_[i]] = i;
  }
  factored_ = false;
  return refactor();
}

int LemkeBasis::complement(int var) const {
  if (var == z0_var()) return -1;
  return is_w(var) ? var + static_cast<int>(n_) : var - static_cast<int>(n_);
}

void LemkeBasis::add_column(int var, double scale, Vector& t) const {
  if (is_w(var)) {
    t(var) += scale;
  } else if (var == z0_var()) {
    t.noalias() -= scale * d_;
  } else {
    for (SparseMatrix::InnerIterator it(M_, var - n_); it; ++it)
      t(it.index()) -= scale * it.value();
  }
}

double LemkeBasis::dot_column(int var, const Vector& y) const {
  if (is_w(var)) return y(var);
  if (var == z0_var()) return -d_.dot(y);
  double sum = 0.0;
  for (SparseMatrix::InnerIterator it(M_, var - n_); it; ++it) sum -= it.value() * y(it.index());
  return sum;
}

void LemkeBasis::column(int var, Vector& a) const {
  a.setZero(n_);
  add_column(var, 1.0, a);
}

void LemkeBasis::multiply(const Vector& x, Vector& out) const {
  out.setZero(n_);
  for (Index p = 0; p < n_; ++p)
    if (x(p) != 0.0) add_column(basis_[p], x(p), out);
}

void LemkeBasis::solve(Vector& x) {
  ++solves_;
  // B0^-1: reduced solve on the uncovered rows, then the covered rows
  // x_W = b_W - A(W, S) x_S, with A = -[M, d] (so each entry adds x_s v).
  const Index k = static_cast<Index>(r_rows_.size());
  for (Index s = 0; s < k; ++s) reduced_(s) = x(r_rows_[s]);
  lu_->solve(reduced_.data());
  const Index covered = static_cast<Index>(w_rows_.size());
  for (Index c = 0; c < covered; ++c) {
    double t = x(w_rows_[c]);
    for (Index e = w_start_[c]; e < w_start_[c + 1]; ++e) {
      const double xs = reduced_(w_s_[e]);
      if (xs != 0.0) t -= (-xs) * w_v_[e];
    }
    w_values_(c) = t;
  }
  for (Index c = 0; c < covered; ++c) x(w_positions_[c]) = w_values_(c);
  for (Index s = 0; s < k; ++s) x(s_positions_[s]) = reduced_(s);
  // The etas, oldest first: x <- E^-1 x with x_r / u_r at r, x_i - u_i x_r' elsewhere.
  // Up to four at a time: each one's x_r' is found from the entry x_r as the
  // etas before it in the group left it (an eta with x_r' = 0 does nothing
  // and is dropped), then one pass over x does x_i <- ((x_i - x_r1' u1_i) -
  // x_r2' u2_i) - ..., and the group's entries r are set to what the etas in
  // turn leave there: the same operations in the same order as one pass per
  // eta, with a quarter of the passes over x.
  constexpr int kGroup = 4;
  const std::size_t etas = eta_pos_.size();
  std::size_t e = 0;
  while (e < etas) {
    Index r[kGroup], col[kGroup];
    double xr[kGroup], at_r[kGroup];
    int m = 0;
    for (; m < kGroup && e < etas; ++e) {
      const Index re = eta_pos_[e];
      const auto u = eta_u_.col(static_cast<Index>(e));
      double v = x(re);
      for (int i = 0; i < m; ++i) v = re == r[i] ? xr[i] : v - xr[i] * eta_u_(re, col[i]);
      const double xe = v / u(re);
      if (xe == 0.0) continue;
      r[m] = re;
      col[m] = static_cast<Index>(e);
      xr[m] = xe;
      ++m;
    }
    for (int j = 0; j < m; ++j) {
      double v = x(r[j]);
      for (int i = 0; i < m; ++i) v = r[j] == r[i] ? xr[i] : v - xr[i] * eta_u_(r[j], col[i]);
      at_r[j] = v;
    }
    auto u = [&](int i) { return eta_u_.col(col[i]).head(n_); };
    switch (m) {
      case 0: break;
      case 1: x.noalias() -= xr[0] * u(0); break;
      case 2: x.noalias() = (x - xr[0] * u(0)) - xr[1] * u(1); break;
      case 3: x.noalias() = ((x - xr[0] * u(0)) - xr[1] * u(1)) - xr[2] * u(2); break;
      default: x.noalias() = (((x - xr[0] * u(0)) - xr[1] * u(1)) - xr[2] * u(2)) - xr[3] * u(3); break;
    }
    for (int j = 0; j < m; ++j) x(r[j]) = at_r[j];
  }
}

void LemkeBasis::solve_transposed(Vector& y) {
  ++solves_;
  // The etas transposed, newest first: E^-T changes only entry r,
  // y_r <- y_r - ((u . y) - y_r) / u_r.
  for (std::size_t e = eta_pos_.size(); e-- > 0;) {
    const Index r = eta_pos_[e];
    const auto u = eta_u_.col(static_cast<Index>(e)).head(n_);
    const double ur = u(r);
    const double yr = y(r);
    y(r) = yr - (u.dot(y) - yr) / ur;
  }
  // B0^T t = y: a covered row i (w_i at position p) has t_i = y_p; the uncovered
  // rows solve C^T t_R = y_S - A(W, S)^T t_W.
  scratch_.setZero();
  for (std::size_t c = 0; c < w_rows_.size(); ++c) scratch_(w_rows_[c]) = y(w_positions_[c]);
  const Index k = static_cast<Index>(r_rows_.size());
  for (Index s = 0; s < k; ++s)  // rows R of scratch_ are still 0: the dot sees W only
    reduced_(s) = y(s_positions_[s]) - dot_column(s_vars_[s], scratch_);
  lu_->solve_transposed(reduced_.data());
  for (Index s = 0; s < k; ++s) scratch_(r_rows_[s]) = reduced_(s);
  y = scratch_;
}

bool LemkeBasis::replace(Index pos, int var, const Vector& u) {
  position_[basis_[pos]] = -1;
  basis_[pos] = var;
  position_[var] = pos;
  factored_ = false;
  eta_u_.col(static_cast<Index>(eta_pos_.size())).head(n_) = u;
  eta_pos_.push_back(pos);
  if (static_cast<int>(eta_pos_.size()) >= refactor_interval_) return refactor();
  return true;
}

bool LemkeBasis::refactor() {
  if (factored_) return true;
  factored_ = factorise();
  return factored_;
}

bool LemkeBasis::factorise() {
  ++refactorisations_;
  eta_pos_.clear();
  s_positions_.clear();
  s_vars_.clear();
  r_rows_.clear();
  w_rows_.clear();
  w_positions_.clear();
  reduced_row_.assign(static_cast<std::size_t>(n_), -1);
  covered_row_.assign(static_cast<std::size_t>(n_), -1);
  for (Index p = 0; p < n_; ++p) {
    const int var = basis_[p];
    if (is_w(var)) {
      covered_row_[var] = static_cast<Index>(w_rows_.size());
      w_rows_.push_back(var);
      w_positions_.push_back(p);
    } else {
      s_positions_.push_back(p);
      s_vars_.push_back(var);
    }
  }
  for (Index i = 0; i < n_; ++i)
    if (covered_row_[i] < 0) {
      reduced_row_[i] = static_cast<Index>(r_rows_.size());
      r_rows_.push_back(i);
    }
  const Index k = static_cast<Index>(r_rows_.size());
  const Index covered = static_cast<Index>(w_rows_.size());
  reduced_.resize(k);
  w_values_.resize(covered);

  // C = [-M, -d](R, vars(S)), column by column, its rows increasing (M's
  // columns are stored with increasing rows, and R is increasing); and the
  // covered rows' entries A(W, S), counted per row then filled in increasing s.
  C_.resize(k, k);
  C_.setZero();
  w_start_.assign(static_cast<std::size_t>(covered) + 1, 0);
  for (Index s = 0; s < k; ++s) {
    const int var = s_vars_[s];
    if (var == z0_var()) {
      for (Index c = 0; c < covered; ++c) ++w_start_[c + 1];
    } else {
      for (SparseMatrix::InnerIterator it(M_, var - n_); it; ++it)
        if (covered_row_[it.index()] >= 0) ++w_start_[covered_row_[it.index()] + 1];
    }
  }
  for (Index c = 0; c < covered; ++c) w_start_[c + 1] += w_start_[c];
  w_s_.resize(static_cast<std::size_t>(w_start_[covered]));
  w_v_.resize(static_cast<std::size_t>(w_start_[covered]));
  fill_.assign(w_start_.begin(), w_start_.end() - 1);
  for (Index s = 0; s < k; ++s) {
    const int var = s_vars_[s];
    C_.startVec(s);
    if (var == z0_var()) {
      for (Index r = 0; r < k; ++r)
        if (d_(r_rows_[r]) != 0.0) C_.insertBack(r, s) = -d_(r_rows_[r]);
      for (Index c = 0; c < covered; ++c) {
        w_s_[fill_[c]] = s;
        w_v_[fill_[c]++] = d_(w_rows_[c]);
      }
    } else {
      for (SparseMatrix::InnerIterator it(M_, var - n_); it; ++it) {
        const Index i = it.index();
        if (reduced_row_[i] >= 0) {
          C_.insertBack(reduced_row_[i], s) = -it.value();
        } else {
          const Index c = covered_row_[i];
          w_s_[fill_[c]] = s;
          w_v_[fill_[c]++] = it.value();
        }
      }
    }
  }
  C_.finalize();
  const double size = static_cast<double>(k);
  const bool sparse = k >= policy_.sparse_min_size &&
                      static_cast<double>(C_.nonZeros()) <= policy_.sparse_max_density * size * size;
  auto& factor = sparse ? sparse_lu_ : dense_lu_;
  if (!factor)
    factor = !sparse ? make_dense_factor()
                     : policy_.sparse_lu == SparseLu::klu ? make_klu_factor() : make_sparse_factor();
  lu_ = factor.get();
  if (sparse) ++sparse_refactorisations_;
  return lu_->factor(C_);
}

}  // namespace floesim::lcp::detail
