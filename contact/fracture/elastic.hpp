#pragma once
// The elastic floe of the percussion model (MODEL.md §6): linear (constant
// strain) triangles in plane stress over a floe mesh, thickness h, Young's
// modulus E, Poisson ratio nu, density rho; lumped masses.
//
// Why finite elements rather than a lattice of bonds: a lattice of central
// springs along the mesh edges is elastic only on regular meshes, and then
// its Poisson ratio is fixed by the lattice (1/3 in plane stress for the
// triangular lattice); on an irregular Delaunay mesh it does not reproduce a
// uniform strain (it fails the patch test), so its stresses do not converge.
// Linear triangles pass the patch test on any mesh, take any nu in (-1, 1/2),
// and with lumped masses are still "masses joined by elastic elements": the
// stiffness of triangle e is K_e = h A_e B_e^T D B_e, and the removal of an
// element (a crack) is the rank-3 downdate K <- K - W_e W_e^T with
// W_e = sqrt(h A_e) B_e^T L, D = L L^T. docs/fracture.md has the figures.
//
// Unknowns: the displacement u (m) of every node, u[2i] along x, u[2i+1]
// along y, in the frame of the mesh. Strain (exx, eyy, gxy) = B u;
// stress (sxx, syy, sxy) = D (exx, eyy, gxy) with
//   D = E / (1 - nu^2) [[1, nu, 0], [nu, 1, 0], [0, 0, (1 - nu) / 2]].
//
// Setup in two parts. The constructor builds what the loads and the stress
// bound need (lumped masses, rigid modes, outline shares); the element
// matrices B_e and K are assembled on the first call that needs them
// (stiffness, element or nodal stress, strain energy, element or crack
// factors): a floe whose load cases the stress bound clears
// (response.hpp) never pays for K. The assembly is the same whenever it
// runs, so results do not depend on it. Not for concurrent first use from
// several threads (a model belongs to one floe, checked by one thread).

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <array>
#include <span>
#include <vector>

#include "contact/fracture/mesh.hpp"

namespace floesim::fracture {

struct Material {
  double young = 6.0e9;    // Pa
  double poisson = 0.3;
  double density = 917.0;  // kg/m^3
  double thickness = 1.0;  // m
};

// Principal stress: the largest principal value and its direction.
struct Principal {
  double value = 0.0;   // Pa, sigma_1 (tension > 0)
  double angle = 0.0;   // rad, direction of sigma_1 from +x, in (-pi/2, pi/2]
};
Principal principal(const Eigen::Vector3d& stress);

class ElasticModel {
public:
  ElasticModel(Mesh mesh, const Material& material);

  const Mesh& mesh() const { return mesh_; }
  const Material& material() const { return material_; }
  Eigen::Index dofs() const { return 2 * static_cast<Eigen::Index>(mesh_.node_count()); }
  const Eigen::SparseMatrix<double>& stiffness() const;               // N/m (assembled on first use)
  const Eigen::VectorXd& lumped_mass() const { return m_; }           // kg, per dof
  const Eigen::Matrix3d& elasticity() const { return d_; }            // D, Pa
  double wave_speed() const;  // m/s, plate longitudinal speed sqrt(E / (rho (1 - nu^2)))
  double bar_speed() const;   // m/s, sqrt(E / rho)
  double diameter() const { return diameter_; }  // m, largest node-to-node distance (bound)
  const Vec2& mass_centre() const { return centre_; }

  // W (dofs x 3k): the columns W_e of the listed triangles, K_e = W_e W_e^T.
  Eigen::SparseMatrix<double> element_factors(std::span<const int> triangles) const;
  // W (dofs x 2k): what a crack along the direction `angle` (rad from +x)
  // removes from the listed triangles (a smeared crack): in the crack's frame
  // (t along it, n across it) a cracked triangle keeps only the stiffness
  // along the crack, sigma_tt = E eps_tt, sigma_nn = sigma_tn = 0, so it loses
  //   D - E e_t e_t^T = E / (1 - nu^2) (nu, 1, 0)(nu, 1, 0)^T + G (0, 0, 1)(0, 0, 1)^T
  // (rank 2, in (tt, nn, tn) Voigt components; G = E / (2 (1 + nu))), and
  // K <- K - W W^T. Opening and sliding are free, the material along the
  // crack still carries its own load.
  Eigen::SparseMatrix<double> crack_factors(std::span<const int> triangles, double angle) const;

  // Constant stress of each triangle, and the area-weighted average of the
  // triangles around each node (the recovered nodal stress).
  std::vector<Eigen::Vector3d> element_stress(const Eigen::VectorXd& u) const;
  std::vector<Eigen::Vector3d> nodal_stress(const Eigen::VectorXd& u) const;
  double strain_energy(const Eigen::VectorXd& u) const;  // J, u^T K u / 2

  // Inertia relief. With Phi the three rigid modes (translations, rotation
  // about the mass centre), the load without its rigid part:
  //   f - M Phi (Phi^T M Phi)^-1 Phi^T f   (Phi^T of it is 0: self-equilibrated),
  // and a displacement without its rigid part (M-orthogonal to Phi).
  Eigen::VectorXd relieve(const Eigen::VectorXd& f) const;
  void remove_rigid(Eigen::VectorXd& u) const;

  // Adds to f (N, per dof) the force `force` applied at `point`, spread with
  // the weights w_i (1 - (d_i/radius)^2)^2, normalised to sum to one (so the
  // resultant is exactly `force`), over
  //  * the outline's nodes within `radius`, w_i their share of outline length,
  //    when the point is on the outline (within radius / 4 of it): a contact
  //    pressure, as in a collision (a body force there would pull on the
  //    free surface behind it and make spurious tension);
  //  * otherwise the nodes within `radius`, w_i their share of area.
  // A point farther than `radius` from every such node goes to the nearest.
  void add_point_load(Eigen::VectorXd& f, const Vec2& point, const Vec2& force, double radius) const;

  // Linear interpolation of nodal values at a point of the mesh; false if outside.
  bool interpolate(const std::vector<Eigen::Vector3d>& nodal, const Vec2& point, Eigen::Vector3d& out) const;

private:
  // B_e per triangle and K (a cache: the same values whenever it is built).
  void assemble_stiffness() const;

  Mesh mesh_;
  Material material_;
  Eigen::Matrix3d d_;
  Eigen::Matrix3d d_factor_;  // L, D = L L^T
  mutable std::vector<Eigen::Matrix<double, 3, 6>> b_;  // per triangle; empty until assembled
  mutable Eigen::SparseMatrix<double> k_;
  Eigen::VectorXd m_;
  std::vector<double> node_area_;
  std::vector<double> node_outline_;                 // share of outline length per node (m)
  std::vector<std::array<int, 2>> outline_edges_;
  Eigen::MatrixXd phi_;        // dofs x 3
  Eigen::Matrix3d rigid_inv_;  // (Phi^T M Phi)^-1
  Vec2 centre_ = Vec2::Zero();
  double diameter_ = 0.0;
};

}  // namespace floesim::fracture
