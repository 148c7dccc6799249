#pragma once
// Scenario builders shared by the fluid tests and benchmarks.

#include <cmath>

#include "core/params.hpp"

namespace floesim::fluid::cases {

// The validation box: L = 1 m, H = 0.1 m, lab water with surface tension.
inline SeaParams lab_box_1d(int cells) {
  SeaParams p;
  p.model = SeaModel::spectral;
  p.dims = 1;
  p.size = {1.0, 1.0};
  p.cells = {cells, 1};
  p.depth = 0.1;
  p.rho = 1000.0;
  p.g = 9.81;
  p.sigma = 0.0728;
  return p;
}

// A rectangular BEM tank with the same water.
inline SeaParams lab_tank_bem(int surface_panels, double length = 1.0, double depth = 0.1) {
  SeaParams p = lab_box_1d(surface_panels);
  p.model = SeaModel::bem;
  p.size = {length, 1.0};
  p.depth = depth;
  return p;
}

}  // namespace floesim::fluid::cases
