#pragma once
// BEM sea: a vertical-slice basin (dims = 1) of length lx with vertical walls
// at x = 0 and x = lx and a bottom polyline z_b(x) (or a flat bottom at -depth).
//
// Setup (once per basin, cached process-wide by geometry and physics):
//  1. The fluid boundary is cut into straight constant panels: cells[0] equal
//     panels on the free surface (they are the grid cells) and panels of about
//     bem_panel_ratio times that length on the walls and bottom.
//  2. Collocation BEM for Laplace at panel midpoints, with the free-space Green
//     function G = -ln(r) / (2 pi) integrated exactly on each panel:
//         1/2 phi_i + sum_j H_ij phi_j = sum_j G_ij q_j,
//     q = d phi / d n = eta' on the surface, 0 on walls and bottom. The pure-
//     Neumann system is singular (constants); it is bordered by the condition
//     that phi has zero mean on the surface, which fixes Phi, the Neumann-to-
//     Dirichlet map on the surface (MODEL.md §3).
//  3. m_sf -> M = rho w D Phi, symmetrised (w the width ly, D the panel lengths);
//     a_sf -> K = w (rho g D + sigma L), L the finite-volume Laplacian with
//     d eta / d x = 0 at the walls. Both restricted to zero-mean surfaces.
//  4. Modes: the generalised eigenproblem K x = omega^2 M x, x M-orthonormal:
//     the ModalBank gets one real mode per eigenvector (mass 1); all of them
//     (the slice is small: [sea] bem_modes is for the 3D basin).
// Per step: a kick projects the pressure on the modes (one dense mat-vec, n^2);
// fields are dense mat-vecs too; slope and horizontal velocity are centred
// differences of eta and of the surface potential.

#include <array>
#include <memory>
#include <span>
#include <vector>

#include "fluid/dense_modal_sea.hpp"

namespace floesim::fluid {

// The modal side (kicks, set_surface, projection, frequencies, the set-up's
// cost and cache) is DenseModalSea's (fluid/dense_modal_sea.hpp).
class BemSea final : public DenseModalSea {
public:
  // params must have passed validate() with model = bem.
  BemSea(const SeaParams& params, const SeaOptions& options = {});

  void flow(double dt) override;

protected:
  void compute_field(Field f, std::span<double> out) override;
};

// The basin's bottom (x, z) clipped to [0, size x], as the list of its
// vertices: the polyline of [sea] bottom, or the flat bottom at -depth. Shared
// by the slice and the 3D basin (fluid/bem3d.hpp).
std::vector<std::array<double, 2>> bottom_profile(const SeaParams& params);

}  // namespace floesim::fluid
