#include "contact/lcp/lemke_basis.hpp"

#include <Eigen/LU>
#include <cmath>
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

}  // namespace

std::unique_ptr<ReducedFactor> make_dense_factor() { return std::make_unique<DenseFactor>(); }
std::unique_ptr<ReducedFactor> make_sparse_factor() { return std::make_unique<UmfpackFactor>(); }

// ---------------------------------------------------------------------------
// The basis.

LemkeBasis::LemkeBasis(const SparseMatrix& M, const Vector& d, FactorPolicy policy,
                       int refactor_interval)
    : M_(M), d_(d), n_(M.rows()), policy_(policy), refactor_interval_(refactor_interval),
      basis_(static_cast<std::size_t>(n_)), position_(static_cast<std::size_t>(2 * n_ + 1), -1),
      scratch_(n_) {
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
  // B0^-1: reduced solve on the uncovered rows, then the covered rows.
  const Index k = static_cast<Index>(r_rows_.size());
  for (Index s = 0; s < k; ++s) reduced_(s) = x(r_rows_[s]);
  lu_->solve(reduced_.data());
  scratch_ = x;
  for (Index s = 0; s < k; ++s)
    if (reduced_(s) != 0.0) add_column(s_vars_[s], -reduced_(s), scratch_);
  for (std::size_t c = 0; c < w_rows_.size(); ++c) x(w_positions_[c]) = scratch_(w_rows_[c]);
  for (Index s = 0; s < k; ++s) x(s_positions_[s]) = reduced_(s);
  // The etas, oldest first: x <- E^-1 x with x_r / u_r at r, x_i - u_i x_r' elsewhere.
  for (const Eta& eta : etas_) {
    const double xr = x(eta.pos) / eta.u(eta.pos);
    if (xr != 0.0) {
      x.noalias() -= xr * eta.u;
      x(eta.pos) = xr;
    }
  }
}

void LemkeBasis::solve_transposed(Vector& y) {
  ++solves_;
  // The etas transposed, newest first: E^-T changes only entry r,
  // y_r <- y_r - ((u . y) - y_r) / u_r.
  for (auto eta = etas_.rbegin(); eta != etas_.rend(); ++eta) {
    const double ur = eta->u(eta->pos);
    const double yr = y(eta->pos);
    y(eta->pos) = yr - (eta->u.dot(y) - yr) / ur;
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
  etas_.push_back({pos, u});
  if (static_cast<int>(etas_.size()) >= refactor_interval_) return refactor();
  return true;
}

bool LemkeBasis::refactor() {
  ++refactorisations_;
  etas_.clear();
  s_positions_.clear();
  s_vars_.clear();
  r_rows_.clear();
  w_rows_.clear();
  w_positions_.clear();
  std::vector<Index> reduced_row(static_cast<std::size_t>(n_), -1);
  std::vector<char> covered(static_cast<std::size_t>(n_), 0);
  for (Index p = 0; p < n_; ++p) {
    const int var = basis_[p];
    if (is_w(var)) {
      covered[var] = 1;
      w_rows_.push_back(var);
      w_positions_.push_back(p);
    } else {
      s_positions_.push_back(p);
      s_vars_.push_back(var);
    }
  }
  for (Index i = 0; i < n_; ++i)
    if (!covered[i]) {
      reduced_row[i] = static_cast<Index>(r_rows_.size());
      r_rows_.push_back(i);
    }
  const Index k = static_cast<Index>(r_rows_.size());
  reduced_.resize(k);

  // C = [-M, -d](R, vars(S)), column by column.
  std::vector<Eigen::Triplet<double, int>> entries;
  for (Index s = 0; s < k; ++s) {
    const int var = s_vars_[s];
    const int col = static_cast<int>(s);
    if (var == z0_var()) {
      for (Index r = 0; r < k; ++r)
        if (d_(r_rows_[r]) != 0.0) entries.emplace_back(static_cast<int>(r), col, -d_(r_rows_[r]));
    } else {
      for (SparseMatrix::InnerIterator it(M_, var - n_); it; ++it)
        if (reduced_row[it.index()] >= 0)
          entries.emplace_back(static_cast<int>(reduced_row[it.index()]), col, -it.value());
    }
  }
  SparseMatrix C(k, k);
  C.setFromTriplets(entries.begin(), entries.end());
  const double size = static_cast<double>(k);
  const bool sparse = k >= policy_.sparse_min_size &&
                      static_cast<double>(C.nonZeros()) <= policy_.sparse_max_density * size * size;
  auto& factor = sparse ? sparse_lu_ : dense_lu_;
  if (!factor) factor = sparse ? make_sparse_factor() : make_dense_factor();
  lu_ = factor.get();
  if (sparse) ++sparse_refactorisations_;
  return lu_->factor(C);
}

}  // namespace floesim::lcp::detail
