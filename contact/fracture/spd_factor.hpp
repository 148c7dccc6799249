#pragma once
// A sparse symmetric positive definite matrix factorised once by SuiteSparse
// CHOLMOD and reused: solves, and low-rank modifications of the factor
// (A +- W W^T through cholmod_updown, Davis & Hager 1999) instead of a new
// factorisation. The factor is kept simplicial LDL^T, the form updown works on.
// CHOLMOD's types stay in spd_factor.cpp.

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <memory>

namespace floesim::fracture {

class SpdFactor {
public:
  // Factorises A (square, symmetric; only its lower triangle is read). Throws
  // RunError when A is not positive definite or CHOLMOD fails.
  explicit SpdFactor(const Eigen::SparseMatrix<double>& a);
  ~SpdFactor();
  SpdFactor(SpdFactor&&) noexcept;
  SpdFactor& operator=(SpdFactor&&) noexcept;
  SpdFactor(const SpdFactor&) = delete;
  SpdFactor& operator=(const SpdFactor&) = delete;

  // An independent copy of the factor (to modify one and keep the other).
  SpdFactor copy() const;

  Eigen::Index size() const;
  // x = A^-1 b.
  Eigen::VectorXd solve(const Eigen::VectorXd& b) const;
  // A <- A + W W^T (update) or A - W W^T (downdate); W is n x k. Throws
  // RunError if a downdate loses positive definiteness.
  void modify(const Eigen::SparseMatrix<double>& w, bool downdate);

private:
  SpdFactor();
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace floesim::fracture
