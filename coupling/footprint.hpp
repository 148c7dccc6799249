#pragma once
// Where each floe covers the sea's surface grid (MODEL.md §4): its pieces,
// one per cell (or node) it touches, and the integrals along its outline that
// go with them, for the cell kernel (B = the cell's indicator) or the tent
// kernel (B = a node's bilinear tent; below):
//
//   area piece  (cell c, weight a_c = ∫_omega B_c, centroid r_c = ∫_omega B_c r / a_c)
//   edge piece  (cell c, ∮ B_c over the outline: length, N, T, Q, S)
//
// Positions are relative to the floe's centroid G, in world orientation (so a
// floe far from the origin keeps full precision). Area pieces come from the
// edges alone (Green's theorem per cell, footprint.cpp): each edge is split at
// the grid lines it crosses, every sub-segment adds its exact integrals to its
// cell and, through one carry summed down the column, to the cells below it.
// Exact up to round-off for convex and non-convex polygons, in time
// proportional to the sub-segments plus the cells of the floe's bounding box.
// Pieces are sorted by cell; each edge piece knows its area piece. Forces built
// on these weights change continuously as a floe crosses cell boundaries
// (MODEL.md §4: smooth forces), and with the tent kernel their rates too.
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

// How a floe's footprint is weighed on the grid (docs/coupling.md, "Footprints"):
//   cell: the indicator of each cell, B_c = 1 on cell c: pieces are the exact
//         areas omega ∩ cell_c. A cell's load is continuous as an edge crosses
//         the cell, but its rate jumps at the cell's lines.
//   tent: the bilinear tent of each node (a cell's centre), B_c(x) = (1 -
//         |x - x_c| / dx)^+ (1 - |y - y_c| / dy)^+: pieces are w_c = ∫_omega B_c,
//         first moments ∫_omega B_c r. The tents are a partition of unity, so
//         the pieces still sum to the floe's area, and a node's load is C^1 in
//         the floe's position: its rate no longer jumps as a floe drifts.
//         Computed by the same edge accumulation on the dual grid (lines
//         through the cells' centres), where each dual cell holds four
//         bilinear tents. Periodic grids only (a tent would reach past a wall).
enum class FootprintKernel { cell, tent };

struct Footprints {
  // Area pieces of floe i: [offsets[i], offsets[i + 1]), sorted by cell.
  // With the tent kernel, "area" is the tent-weighted area w_c and "centroid"
  // the tent-weighted centroid.
  std::vector<std::size_t> offsets{0};
  std::vector<std::uint32_t> cell;
  std::vector<double> area;       // m^2
  std::vector<Vec2> centroid;     // m, relative to G
  // Edge pieces of floe i: [edge_offsets[i], edge_offsets[i + 1]), one per
  // cell (cell kernel) or node (tent kernel) whose kernel B meets the floe's
  // outline: the integrals along all of the outline there (n the outward
  // normal, r relative to G; the polygon is counter-clockwise). The contact's
  // horizontal forces are linear in them, node by node.
  std::vector<std::size_t> edge_offsets{0};
  std::vector<std::uint32_t> edge_cell;
  std::vector<std::ptrdiff_t> edge_piece;  // index of the area piece of that cell, or -1
  std::vector<double> edge_length;         // ∫ B ds (m)
  std::vector<Vec2> edge_normal;           // N = ∫ B n ds = d w_c / dG
  std::vector<double> edge_twist;          // T = ∫ B (r x n) ds = d w_c / dyaw
  std::vector<Eigen::Matrix2d> edge_first; // Q = ∫ B r n^T ds: d (∫ B r) / dG = Q - w_c I
  std::vector<Vec2> edge_swept;            // S = ∫ B r (r x n) ds = d (∫ B r) / dyaw

  std::size_t floes() const { return offsets.size() - 1; }
  // Index of the area piece of floe i in `cell_index`, or -1.
  std::ptrdiff_t find(std::size_t i, std::uint32_t cell_index) const;
};

// Where a floe is placed on the grid: its centroid (m) and yaw (rad).
struct FloePose {
  double x = 0.0, y = 0.0, yaw = 0.0;
};

// Pieces of every floe for which include[i] is true (others get none), with
// floe i at poses[i] (or, if poses is empty, where its state puts it). The
// tent kernel needs a periodic grid (a walled one gets std::invalid_argument).
// With threads > 1 ranges of floes are built on that many threads; the
// result does not depend on the thread count.
void build_footprints(const Floes& floes, std::span<const std::uint8_t> include,
                      const fluid::SurfaceGrid& grid, Footprints& out,
                      FootprintKernel kernel = FootprintKernel::cell, int threads = 1,
                      std::span<const FloePose> poses = {});

}  // namespace floesim
