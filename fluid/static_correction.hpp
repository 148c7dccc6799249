#pragma once
// The static correction of a truncated mode set (`[sea] bem_static_correction`;
// docs/sea.md, "Lowest modes"). Internal to fluid/.
//
// A sea whose surface keeps only its n lowest modes X (fluid/lowest_modes.hpp;
// a_sf X = m_sf X Omega^2, X^T m_sf X = I) answers a load only through them.
// The modes it drops are the short, fast ones; under a load that changes
// slowly against their periods they respond quasi-statically. This is the
// mode-acceleration method of structural dynamics (Dickens & Wilson; the
// residual flexibility of Craig & Bampton's reduction): the surface under a
// nodal load F (F = -A p for a pressure p on cells of area A) is
//     eta = X q + R F,   q'' + Omega^2 q = X^T F   (the kept modes, dynamic),
//     R = K^-1 P - X Omega^-2 X^T                   (the dropped modes, static),
// with K = a_sf = rho g A I + sigma L and K^-1 P its inverse on zero-mean
// surfaces (P the projection on them). Written over all the modes X_all,
// K^-1 P = X_all Omega_all^-2 X_all^T (since K = m_sf X_all Omega_all^2
// X_all^T m_sf), so R = X_d Omega_d^-2 X_d^T over the dropped modes X_d:
// symmetric, positive semi-definite, zero on the kept modes' loads
// (R m_sf X = 0), and a static load gives the full static surface,
// X Omega^-2 X^T F + R F = K^-1 P F, whatever n. Its energy is the dropped
// modes' potential, 1/2 F^T R F.
//
// Cost: K is sparse (the five-point Laplacian plus a diagonal), factored once
// at set-up (a sparse LDL^T); applying R is one sparse solve and, with the
// modal load X^T F that the kick or the midpoint step computes anyway, one
// thin mat-vec X (Omega^-2 X^T F).

#include <Eigen/Dense>
#include <Eigen/SparseCore>

#include <memory>
#include <span>
#include <vector>

namespace floesim::fluid {

// K^-1 on zero-mean right-hand sides, K = a_sf sparse symmetric, positive
// definite on zero-mean surfaces (with g = 0 it is singular on the constants:
// one node is pinned). Factored once.
class ZeroMeanStiffness {
public:
  explicit ZeroMeanStiffness(const Eigen::SparseMatrix<double>& a_sf);
  ~ZeroMeanStiffness();
  ZeroMeanStiffness(const ZeroMeanStiffness&) = delete;
  ZeroMeanStiffness& operator=(const ZeroMeanStiffness&) = delete;
  // y = K^-1 b for a zero-mean b; y has zero mean.
  void solve(const Eigen::VectorXd& b, Eigen::VectorXd& y) const;

private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

class StaticCorrection {
public:
  // a_sf as above; omega the kept modes' frequencies.
  StaticCorrection(const Eigen::SparseMatrix<double>& a_sf, std::span<const double> omega);
  // eta = R F, given the kept modes x (surface x n), the nodal load F and its
  // modal load s = X^T F. `centred` (surface-sized) and `modal` (mode-sized)
  // are scratch.
  void apply(const Eigen::MatrixXd& x, const Eigen::VectorXd& load, std::span<const double> modal_load,
             Eigen::VectorXd& eta, Eigen::VectorXd& centred, Eigen::VectorXd& modal) const;

private:
  ZeroMeanStiffness stiffness_;
  Eigen::VectorXd inverse_square_;  // Omega^-2 per kept mode
};

}  // namespace floesim::fluid
