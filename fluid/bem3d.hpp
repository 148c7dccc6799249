#pragma once
// BEM sea in 3D (dims = 2): a rectangular basin [0, lx] x [0, ly] with four
// vertical walls and a bottom z_b(x) (a polyline along x, uniform across the
// basin, or a flat bottom at -depth) or z_b(x, y) (a grid of depths, bilinear
// between its nodes), the fluid in R^3 under the free surface.
//
// Setup (once per basin, cached process-wide by geometry and physics; the
// panels and their integrals in fluid/bem3d_panels.hpp):
//  1. The fluid boundary is cut into flat constant panels (planar quadrilaterals):
//     the nx x ny grid cells on the free surface; on the bottom, columns along
//     the polyline's segments (about bem_panel_ratio times the surface cell
//     length; equal columns for a bottom grid, whose patches are split into
//     two flat triangles) times rows across; on the walls, the columns and rows of the
//     bottom carried up to z = 0 in equal fractions of the local depth. The
//     panels close the basin exactly (watertight), whatever their sizes.
//  2. Collocation BEM for Laplace at panel centroids, with the free-space Green
//     function G = 1 / (4 pi r) integrated exactly on each flat panel (the
//     single layer by its edge formula, the double layer as the solid angle the
//     panel subtends):
//         1/2 phi_i + sum_j D_ij phi_j = sum_j S_ij q_j,
//         S_ij = ∫_j G dS,  D_ij = ∫_j dG/dn_y dS = -Omega_ij / (4 pi),
//     (a panel farther than bem_near_field diameters from the point by 2 x 2
//     Gauss points instead, O((1 / bem_near_field)^4) relative error),
//     q = d phi / d n = eta' on the surface, 0 on walls and bottom. The pure-
//     Neumann system is singular (constants); it is bordered by the condition
//     that phi has zero mean on the surface, which fixes Phi, the Neumann-to-
//     Dirichlet map on the surface (MODEL.md §3). The rows of D sum to -1/2
//     (a closed polyhedron subtends 2 pi at a point of a face): exactly with
//     exact integrals; with the far-field rule the diagonal is set so they do.
//  3. m_sf -> M = rho A Phi, symmetrised (A = dx dy, the cell area);
//     a_sf -> K = rho g A I + sigma L, L the five-point finite-volume Laplacian
//     with d eta / d n = 0 at the walls (sparse). Both restricted to zero-mean
//     surfaces (reduce_to_modes, fluid/dense_modal_sea.hpp).
//  4. Modes, K x = omega^2 M x with x M-orthonormal, one real mode per
//     eigenvector in the ModalBank (mass 1, gain 1):
//     - [sea] bem_modes = 0 (the default): all nx ny - 1 of them, the dense
//       generalised eigenproblem;
//     - bem_modes = n > 0: the n lowest only, by implicitly restarted Lanczos
//       (fluid/lowest_modes.hpp). The sea is then the dense one restricted to
//       those modes: the same frequencies and shapes (to the Lanczos
//       tolerance); a surface or a pressure is projected on them and the rest
//       is dropped (its energy is not in the sea, and a floe's pressure
//       excites only the kept modes: the local, quasi-static response of the
//       short waves under a floe is missing). The cut is the user's: n modes
//       reach the wavenumber k_n with n ~ Lx Ly k_n^2 / (4 pi) (the modes of
//       a rectangle, cos(m pi x / Lx) cos(n pi y / Ly), in the quarter disc
//       k < k_n); docs/sea.md says how to choose it. With
//       `bem_static_correction` the dropped modes answer the pressure held
//       over a step quasi-statically (fluid/static_correction.hpp): the
//       sea's static part, through Sea::midpoint_step and hold_pressure.
// Cost: the dense LU of the (N + 1)^2 collocation matrix (N panels in all,
// about 3 times the surface cells for a basin as deep as a cell is long
// times its cells across) and its solve for the nx ny surface right-hand
// sides, then the modes (all: a dense eigenproblem of size nx ny, (nx ny)^3;
// n lowest: a few n mat-vecs of size (nx ny)^2). Memory: 8 (N + 1) (N + 1 +
// 2 nx ny) bytes at the peak (measured in docs/sea.md). The n lowest also make
// every step's mat-vecs nx ny x n instead of (nx ny)^2.
// Tank runs: the relaxation zones of fluid/tank.hpp along x (the generation
// zone against the wall x = 0), applied on the grid around each flow.
// Per step: a kick projects the pressure on the modes (one dense mat-vec,
// nx ny x modes); fields are dense mat-vecs too; slopes and horizontal velocities
// are centred differences of eta and of the surface potential.

#include <memory>
#include <span>

#include "fluid/dense_modal_sea.hpp"

namespace floesim::fluid {

// The modal side (kicks, set_surface, projection, frequencies, the set-up's
// cost and cache) is DenseModalSea's (fluid/dense_modal_sea.hpp).
class Bem3dSea final : public DenseModalSea {
public:
  // params must have passed validate() with model = bem, dims = 2.
  Bem3dSea(const SeaParams& params, const SeaOptions& options = {});
  ~Bem3dSea() override;

  void flow(double dt) override;
  void midpoint_step(std::span<const double> p, double h) override;

  // The relaxation zones of a tank run (options.tank), or nullptr. They act
  // on eta and eta' on the grid around each flow, as on the spectral sea.
  const TankZones* tank() const;

protected:
  void compute_field(Field f, std::span<double> out) override;

private:
  void relax_tank(double t0, double h);
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace floesim::fluid
