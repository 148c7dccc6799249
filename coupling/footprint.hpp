#pragma once
// Where each floe covers the sea's surface grid (MODEL.md §4): the exact
// pieces of its footprint in every cell it touches, and the pieces of its
// boundary in every cell its edges cross.
//
//   area piece  (cell c, area a_c, centroid r_c):   omega_i ∩ cell_c
//   edge piece  (cell c, segment A -> B):           ∂omega_i ∩ cell_c
//
// Positions are relative to the floe's centroid G, in world orientation (so a
// floe far from the origin keeps full precision). Area pieces come from the
// edges alone (Green's theorem per cell, footprint.cpp): each edge is split at
// the grid lines it crosses, every sub-segment adds its exact integrals to its
// cell and, through one carry summed down the column, to the cells below it.
// Exact up to round-off for convex and non-convex polygons, in time
// proportional to the sub-segments plus the cells of the floe's bounding box.
// Pieces are sorted by cell; each edge piece knows its area piece. Forces built
// on these areas change continuously as a floe crosses cell boundaries
// (MODEL.md §4: smooth forces).
//
// Periodic grids (spectral sea) wrap cell indices; a walled basin (bem) has no
// water outside [0, lx], so pieces there are dropped. With dims = 1 cells are
// strips in x over the whole width ly of the long-crested sea.

#include <cstdint>
#include <span>
#include <vector>

#include "core/floes.hpp"
#include "fluid/grid.hpp"

namespace floesim {

struct Footprints {
  // Area pieces of floe i: [offsets[i], offsets[i + 1]), sorted by cell.
  std::vector<std::size_t> offsets{0};
  std::vector<std::uint32_t> cell;
  std::vector<double> area;       // m^2
  std::vector<Vec2> centroid;     // m, relative to G
  // Edge pieces of floe i: [edge_offsets[i], edge_offsets[i + 1]); the polygon
  // is counter-clockwise, so the outward normal of A -> B is (e_y, -e_x) / |e|.
  std::vector<std::size_t> edge_offsets{0};
  std::vector<std::uint32_t> edge_cell;
  std::vector<Vec2> edge_a, edge_b;  // m, relative to G
  std::vector<std::ptrdiff_t> edge_piece;  // index of the area piece in the same cell, or -1

  std::size_t floes() const { return offsets.size() - 1; }
  // Index of the area piece of floe i in `cell_index`, or -1.
  std::ptrdiff_t find(std::size_t i, std::uint32_t cell_index) const;
};

// Pieces of every floe for which include[i] is true (others get none).
void build_footprints(const Floes& floes, std::span<const std::uint8_t> include,
                      const fluid::SurfaceGrid& grid, Footprints& out);

}  // namespace floesim
