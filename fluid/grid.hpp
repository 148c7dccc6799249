#pragma once
// The surface grid that a sea exchanges fields on: pressure in, elevation,
// slope and orbital velocity out. Cells are rectangles of dx by dy; a field
// value belongs to the cell centre x_i = (i + 1/2) dx, y_j = (j + 1/2) dy, and
// a pressure value is the mean pressure over its cell (Pa). Layout is row-major
// with x contiguous: index j * nx + i.
//
// dims = 1 (long-crested sea, or a vertical-slice basin): ny = 1, and ly is the
// width over which the sea is uniform (a flume's width); energies and forces
// are integrated over that width.

#include <cstddef>
#include <span>

namespace floesim::fluid {

// How a field continues past the ends of the grid for interpolation.
enum class GridEdge {
  periodic,  // spectral box: index wraps
  wall       // basin walls at x = 0 and x = lx: even (or odd) reflection
};

struct SurfaceGrid {
  int dims = 1;
  int nx = 0, ny = 1;
  double lx = 0.0, ly = 1.0;  // m
  GridEdge edge = GridEdge::periodic;

  double dx() const { return lx / nx; }
  double dy() const { return ly / ny; }
  double cell_area() const { return dx() * dy(); }
  std::size_t size() const { return static_cast<std::size_t>(nx) * static_cast<std::size_t>(ny); }
  double x(int i) const { return (i + 0.5) * dx(); }
  double y(int j) const { return (j + 0.5) * dy(); }
};

// Parity of a field under reflection at a wall: elevation and the vertical
// velocity are even, the x-slope and x-velocity are odd. Ignored when periodic.
enum class Parity { even, odd };

// Value at (x, y) of a cell-centred field, by tensor-product cubic Lagrange
// interpolation on the 4 (x 4) nearest cell centres: error O(h^4) for smooth
// fields. In dims = 1, y is ignored. Outside a walled basin, x (and y) are
// clamped; `parity` is the field's parity at the walls x = 0 and lx,
// `parity_y` at the walls y = 0 and ly (dims = 2, walled).
double interpolate(const SurfaceGrid& grid, std::span<const double> field, double x, double y,
                   Parity parity = Parity::even, Parity parity_y = Parity::even);

}  // namespace floesim::fluid
