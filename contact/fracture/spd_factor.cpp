#include "contact/fracture/spd_factor.hpp"

#include <cholmod.h>

#include <algorithm>
#include <string>
#include <vector>

#include "core/error.hpp"

namespace floesim::fracture {

struct SpdFactor::Impl {
  cholmod_common cm{};
  cholmod_factor* factor = nullptr;
  int n = 0;
  Impl() {
    cholmod_start(&cm);
    cm.print = 0;
    cm.error_handler = nullptr;
    cm.supernodal = CHOLMOD_SIMPLICIAL;  // LDL^T: the form cholmod_updown modifies
    cm.final_ll = 0;
  }
  ~Impl() {
    if (factor) cholmod_free_factor(&factor, &cm);
    cholmod_finish(&cm);
  }
  Impl(const Impl&) = delete;
  Impl& operator=(const Impl&) = delete;
};

namespace {

void check(const cholmod_common& cm, const char* what) {
  if (cm.status == CHOLMOD_NOT_POSDEF)
    throw RunError(std::string("CHOLMOD ") + what + ": the matrix is not positive definite");
  if (cm.status < CHOLMOD_OK) throw RunError(std::string("CHOLMOD ") + what + " failed (status " +
                                             std::to_string(cm.status) + ")");
}

// The lower triangle of a into a CHOLMOD matrix (stype -1).
cholmod_sparse* lower_to_cholmod(const Eigen::SparseMatrix<double>& a, cholmod_common& cm) {
  const int n = static_cast<int>(a.rows());
  std::size_t nnz = 0;
  for (int j = 0; j < n; ++j)
    for (Eigen::SparseMatrix<double>::InnerIterator it(a, j); it; ++it)
      if (it.row() >= j) ++nnz;
  cholmod_sparse* s = cholmod_allocate_sparse(n, n, nnz, 1, 1, -1, CHOLMOD_REAL, &cm);
  check(cm, "allocate");
  auto* p = static_cast<int*>(s->p);
  auto* i = static_cast<int*>(s->i);
  auto* x = static_cast<double*>(s->x);
  int k = 0;
  for (int j = 0; j < n; ++j) {
    p[j] = k;
    for (Eigen::SparseMatrix<double>::InnerIterator it(a, j); it; ++it)
      if (it.row() >= j) {
        i[k] = static_cast<int>(it.row());
        x[k] = it.value();
        ++k;
      }
  }
  p[n] = k;
  return s;
}

}  // namespace

SpdFactor::SpdFactor() : impl_(std::make_unique<Impl>()) {}

SpdFactor::SpdFactor(const Eigen::SparseMatrix<double>& a) : SpdFactor() {
  if (a.rows() != a.cols()) throw RunError("SpdFactor: the matrix is not square");
  Eigen::SparseMatrix<double> c = a;
  c.makeCompressed();
  Impl& m = *impl_;
  m.n = static_cast<int>(a.rows());
  cholmod_sparse* s = lower_to_cholmod(c, m.cm);
  m.factor = cholmod_analyze(s, &m.cm);
  if (m.factor) cholmod_factorize(s, m.factor, &m.cm);
  cholmod_free_sparse(&s, &m.cm);
  check(m.cm, "factorisation");
  if (!m.factor || m.factor->minor < m.factor->n)
    throw RunError("CHOLMOD factorisation: the matrix is not positive definite");
}

SpdFactor::~SpdFactor() = default;
SpdFactor::SpdFactor(SpdFactor&&) noexcept = default;
SpdFactor& SpdFactor::operator=(SpdFactor&&) noexcept = default;

SpdFactor SpdFactor::copy() const {
  SpdFactor out;
  out.impl_->n = impl_->n;
  out.impl_->factor = cholmod_copy_factor(impl_->factor, &out.impl_->cm);
  check(out.impl_->cm, "copy");
  return out;
}

Eigen::Index SpdFactor::size() const { return impl_->n; }

Eigen::VectorXd SpdFactor::solve(const Eigen::VectorXd& b) const {
  Impl& m = *impl_;
  if (b.size() != m.n) throw RunError("SpdFactor::solve: wrong right-hand side size");
  cholmod_dense rhs{};
  rhs.nrow = rhs.d = static_cast<std::size_t>(m.n);
  rhs.ncol = 1;
  rhs.nzmax = static_cast<std::size_t>(m.n);
  rhs.x = const_cast<double*>(b.data());
  rhs.xtype = CHOLMOD_REAL;
  rhs.dtype = CHOLMOD_DOUBLE;
  cholmod_dense* x = cholmod_solve(CHOLMOD_A, m.factor, &rhs, &m.cm);
  check(m.cm, "solve");
  Eigen::VectorXd out = Eigen::Map<const Eigen::VectorXd>(static_cast<double*>(x->x), m.n);
  cholmod_free_dense(&x, &m.cm);
  return out;
}

void SpdFactor::modify(const Eigen::SparseMatrix<double>& w, bool downdate) {
  Impl& m = *impl_;
  if (w.rows() != m.n) throw RunError("SpdFactor::modify: W has the wrong number of rows");
  if (w.cols() == 0) return;
  // cholmod_updown wants the rows of W in the factor's (fill-reducing) order.
  const int* perm = static_cast<const int*>(m.factor->Perm);
  std::vector<int> inverse(static_cast<std::size_t>(m.n));
  for (int k = 0; k < m.n; ++k) inverse[static_cast<std::size_t>(perm[k])] = k;
  Eigen::SparseMatrix<double> wc = w;
  wc.makeCompressed();
  cholmod_sparse* c = cholmod_allocate_sparse(static_cast<std::size_t>(m.n), static_cast<std::size_t>(w.cols()),
                                              static_cast<std::size_t>(wc.nonZeros()), 1, 1, 0, CHOLMOD_REAL, &m.cm);
  check(m.cm, "allocate");
  auto* p = static_cast<int*>(c->p);
  auto* i = static_cast<int*>(c->i);
  auto* x = static_cast<double*>(c->x);
  int k = 0;
  std::vector<std::pair<int, double>> column;
  for (int j = 0; j < wc.cols(); ++j) {
    p[j] = k;
    column.clear();
    for (Eigen::SparseMatrix<double>::InnerIterator it(wc, j); it; ++it)
      column.emplace_back(inverse[static_cast<std::size_t>(it.row())], it.value());
    std::sort(column.begin(), column.end());
    for (const auto& [row, value] : column) {
      i[k] = row;
      x[k] = value;
      ++k;
    }
  }
  p[wc.cols()] = k;
  const int ok = cholmod_updown(downdate ? 0 : 1, c, m.factor, &m.cm);
  cholmod_free_sparse(&c, &m.cm);
  check(m.cm, "update/downdate");
  if (!ok || m.factor->minor < m.factor->n)
    throw RunError("CHOLMOD downdate: the matrix lost positive definiteness");
}

}  // namespace floesim::fracture
