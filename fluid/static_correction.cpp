#include "fluid/static_correction.hpp"

#include <Eigen/SparseCholesky>

#include <cmath>

#include "core/error.hpp"

namespace floesim::fluid {

using Eigen::VectorXd;

struct ZeroMeanStiffness::Impl {
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt;
  bool pinned = false;
};

ZeroMeanStiffness::ZeroMeanStiffness(const Eigen::SparseMatrix<double>& a_sf) : impl_(std::make_unique<Impl>()) {
  // With g = 0, a_sf = sigma L is singular on the constants: one node is
  // pinned (adding c e_0 e_0^T); for a zero-mean b the pinned solution has
  // y_0 = 0 and L y = b, and removing its mean gives the zero-mean solution.
  // With g > 0 the solution of a zero-mean b is already zero-mean
  // (1^T a_sf y = rho g A 1^T y) and the pin is not added.
  const Eigen::Index n = a_sf.rows();
  Eigen::SparseMatrix<double> k = a_sf;
  const double diag = a_sf.diagonal().cwiseAbs().maxCoeff();
  if (std::abs((a_sf * VectorXd::Ones(n)).sum()) <= 1e-12 * diag * static_cast<double>(n)) {
    k.coeffRef(0, 0) += diag;
    impl_->pinned = true;
  }
  impl_->ldlt.compute(k);
  if (impl_->ldlt.info() != Eigen::Success)
    throw RunError("fluid: the surface stiffness a_sf is not positive definite on zero-mean surfaces");
}

ZeroMeanStiffness::~ZeroMeanStiffness() = default;

void ZeroMeanStiffness::solve(const VectorXd& b, VectorXd& y) const {
  y = impl_->ldlt.solve(b);
  y.array() -= y.mean();
}

StaticCorrection::StaticCorrection(const Eigen::SparseMatrix<double>& a_sf, std::span<const double> omega)
    : stiffness_(a_sf), inverse_square_(static_cast<Eigen::Index>(omega.size())) {
  for (std::size_t j = 0; j < omega.size(); ++j) {
    if (!(omega[j] > 0.0)) throw RunError("fluid: a kept mode has no frequency; the static correction needs omega > 0");
    inverse_square_(static_cast<Eigen::Index>(j)) = 1.0 / (omega[j] * omega[j]);
  }
}

void StaticCorrection::apply(const Eigen::MatrixXd& x, const VectorXd& load, std::span<const double> modal_load,
                             VectorXd& eta, VectorXd& centred, VectorXd& modal) const {
  FLOESIM_ASSERT(static_cast<Eigen::Index>(modal_load.size()) == inverse_square_.size() && x.cols() == inverse_square_.size());
  // K^-1 P F: the full static surface ...
  centred = load.array() - load.mean();
  stiffness_.solve(centred, eta);
  // ... minus the kept modes' share, X Omega^-2 X^T F.
  const Eigen::Map<const VectorXd> s(modal_load.data(), inverse_square_.size());
  modal = inverse_square_.cwiseProduct(s);
  eta.noalias() -= x * modal;
}

}  // namespace floesim::fluid
