#pragma once
// The modes of a boundary-element sea (fluid/bem.hpp, fluid/bem3d.hpp) and
// the dense maps between them and the surface nodes, set up once per basin.
// With the surface's stiffness a_sf and added mass m_sf (both symmetric, on
// zero-mean surfaces), the modes x solve a_sf x = omega^2 m_sf x with
// x^T m_sf x = I, so that eta = x a and a = x^T m_sf eta for a zero-mean eta.
// Internal to fluid/.

#include <Eigen/Dense>

#include <span>
#include <vector>

namespace floesim::fluid {

struct DenseModes {
  int surface = 0;              // surface nodes (grid cells)
  double weight = 0.0;          // a node's area: a pressure p_i is the nodal load -weight p_i
  std::vector<double> omega;    // per mode, ascending (rad/s)
  Eigen::MatrixXd x;            // surface x modes: eta = x a (m_sf-orthonormal columns)
  Eigen::MatrixXd load;         // modes x surface: modal force per unit pressure
  Eigen::MatrixXd project;      // modes x surface: a = project eta, for zero-mean eta (x^T m_sf)
  Eigen::MatrixXd potential;    // surface x modes: phi on the surface per unit a'

  // a <- project (f - mean f): the modal coordinates of a surface field
  // (its mean is not a mode: volume is conserved). `work` is surface-sized scratch.
  void to_modes(std::span<const double> f, std::span<double> a, Eigen::VectorXd& work) const {
    const Eigen::Map<const Eigen::VectorXd> fv(f.data(), surface);
    work = fv.array() - fv.mean();
    Eigen::Map<Eigen::VectorXd>(a.data(), static_cast<Eigen::Index>(a.size())).noalias() = project * work;
  }
  // s <- load p: the modal forces of a surface pressure.
  void to_forces(std::span<const double> pressure, std::span<double> s) const {
    const Eigen::Map<const Eigen::VectorXd> p(pressure.data(), surface);
    Eigen::Map<Eigen::VectorXd>(s.data(), static_cast<Eigen::Index>(s.size())).noalias() = load * p;
  }
  // eta <- x q: the surface field of modal coordinates q.
  void to_surface(std::span<const double> q, std::span<double> eta) const {
    const Eigen::Map<const Eigen::VectorXd> a(q.data(), static_cast<Eigen::Index>(q.size()));
    Eigen::Map<Eigen::VectorXd>(eta.data(), surface).noalias() = x * a;
  }
};

}  // namespace floesim::fluid
