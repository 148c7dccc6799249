#pragma once
// The lowest modes of a sea's surface without the full eigenproblem: the n
// lowest eigenpairs of
//     a_sf x = omega^2 m_sf x   on zero-mean surfaces (x^T 1 = 0),
// a_sf sparse symmetric (rho g A I + sigma L, positive definite on zero-mean
// surfaces), m_sf dense symmetric positive definite on zero-mean surfaces (the
// added mass). Written as  P m_sf P x = mu a_sf x  with mu = 1 / omega^2 and
// P = I - 1 1^T / n the projection on zero-mean surfaces, the lowest omega are
// the largest mu: implicitly restarted Lanczos (ARPACK's dsaupd, mode 2: the
// operator a_sf^-1 P m_sf P, self-adjoint in the a_sf inner product, one sparse
// solve and one dense mat-vec per iteration). The constants are in P's kernel
// (mu = 0) and never among the largest. Internal to fluid/.

#include <Eigen/Dense>
#include <Eigen/SparseCore>

#include <vector>

namespace floesim::fluid {

struct LowestModesOptions {
  int count = 0;              // n: modes wanted, 1 <= n <= size - 2
  // Relative accuracy of each Ritz value mu (ARPACK's tol; 0: machine
  // precision). The frequencies' relative error is about half of it.
  double tolerance = 1e-12;
  int max_restarts = 500;     // ARPACK's iparam(3)
};

struct LowestModes {
  std::vector<double> omega;  // ascending (rad/s)
  Eigen::MatrixXd x;          // size x n, columns m_sf-orthonormal and zero-mean
  int operator_applications = 0;
};

// Throws RunError when ARPACK fails or does not converge in max_restarts.
LowestModes lowest_modes(const Eigen::MatrixXd& m_sf, const Eigen::SparseMatrix<double>& a_sf,
                         const LowestModesOptions& options);

}  // namespace floesim::fluid
