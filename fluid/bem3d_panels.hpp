#pragma once
// The boundary of a 3D BEM basin (fluid/bem3d.hpp) as flat panels, and the
// integrals of the Laplace Green function G = 1 / (4 pi r) over them.
// Private to fluid/.

#include <array>
#include <span>
#include <vector>

#include "core/params.hpp"

namespace floesim::fluid {

using P3 = std::array<double, 3>;

// A flat panel: a quadrilateral, or a triangle (size 3), counter-clockwise
// about the fluid's outward normal.
struct Panel {
  std::array<P3, 4> v;
  std::size_t size = 4;
  std::span<const P3> vertices() const { return {v.data(), size}; }
};

P3 centroid(const Panel& q);

// The watertight boundary of the basin of `params` (model = bem, dims = 2): the
// surface cells first (panel j nx + i is grid cell (i, j)), then the bottom and
// the four walls; wall and bottom panels about `ratio` times a cell long.
std::vector<Panel> basin_panels(const SeaParams& params, double ratio);

// Exact integrals over a flat polygon (vertices counter-clockwise about its
// normal n = the outward normal of the fluid), seen from a point p:
//   single = ∫ 1 / (4 pi r) dS,   double_ = ∫ d/dn_y (1 / (4 pi r)) dS.
struct PanelIntegrals {
  double single = 0.0;
  double double_ = 0.0;
};
PanelIntegrals panel_integrals(std::span<const P3> polygon, const P3& p);

// A panel's far-field rule: 2 x 2 Gauss points of a quadrilateral's bilinear
// map from the unit square, with weights times the area element, or a
// triangle's three-point rule at (2/3, 1/6, 1/6) and its permutations.
struct FarRule {
  std::array<P3, 4> point;
  std::array<double, 4> weight;
  P3 normal, centre;
  double diameter = 0.0;
};
FarRule far_rule(const Panel& panel);

// The integrals of a panel at p: exact within `near` diameters of its
// centroid, by its far rule beyond (relative error O((1 / near)^4)).
PanelIntegrals integrals_at(const Panel& panel, const FarRule& rule, const P3& p, double near);

}  // namespace floesim::fluid
