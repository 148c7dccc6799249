#pragma once
// Random packs of non-overlapping polygonal floes in a box, for `floesim pack`,
// tests, benchmarks and examples. The problem is data (PackOptions); one
// function builds the pack.
//
// Method: an area-constrained, Lloyd-relaxed power diagram, shrunk.
//  1. Floe sizes. The size of a floe is its equivalent diameter d = 2 sqrt(A/pi).
//     Sizes d_i are drawn from the requested distribution on [min_size, max_size]
//     (uniform: d ~ U[a, b]; power law: density p(d) ∝ d^-alpha), then all are
//     scaled by one factor so that the floes cover exactly C W H. Both laws keep
//     their shape under scaling (a power law keeps its exponent), so only the
//     ratio max_size / min_size matters: the absolute sizes follow from N, C and
//     the box. GeneratedPack reports the range after scaling.
//  2. Cells. Each floe i gets a cell of area a_i = A_i / C (so that Σ a_i = W H)
//     in a power (Laguerre) diagram of sites p_i with weights w_i, clipped to the
//     box: cell_i = {x in box : |x - p_i|² - w_i <= |x - p_j|² - w_j for all j}.
//     Sites start uniform in the box; the weights that give every cell its area
//     a_i are found by Newton's method on the areas (semi-discrete optimal
//     transport: the Jacobian ∂area_i/∂w_j = -l_ij / (2 |p_i - p_j|), l_ij the
//     shared edge length, is a graph Laplacian, solved sparse), damped so no
//     cell empties (Kitagawa, Mérigot, Thibert 2019). Between solves, sites move
//     to their cell centroids (Lloyd) `relax_iterations` times, which removes
//     slivers and long thin cells while keeping the areas prescribed.
//     Why a power diagram rather than sampling sizes and placing discs or
//     polygons: placement (random sequential addition) jams near 50% cover and
//     cannot reach 70–90%, while a diagram tiles the box at any concentration
//     and any size ratio, and its weights make cell areas follow the sampled
//     sizes exactly instead of the nearly equal areas of a plain Voronoi diagram.
//  3. Floes. Each (convex) cell is shrunk about its centroid by s = sqrt(C), so
//     floe i has area C a_i exactly. A convex cell contains its shrunk copy, so
//     floes never overlap; the gap between the shrunk copy and its cell boundary
//     is (1 - s) h_i, h_i the distance from the centroid to the nearest edge
//     line. Where (1 - s) h_i < min_gap / 2 the cell is shrunk more (and the
//     achieved concentration, reported, drops a little); so every two floes are
//     at least min_gap apart, and every floe at least min_gap / 2 from the box.
//  4. Optional walls: four static rectangular floes (obstacles) outside the
//     box, min_gap / 2 beyond its sides, their corners min_gap apart.
//  5. Numbering: the floes are numbered along a Z-order (Morton) curve of
//     their centroids, walls last, so floes near each other in the box are
//     near each other in the floe arrays. Detection and the multirate advance
//     read floes neighbour by neighbour: the bench's 10^4-floe pack, run
//     renumbered and not, alternating, took 1.66, 1.36, 1.38 s against 1.66,
//     1.48, 1.51 s (docs/contact.md).
//
// Determinism: the random numbers come from std::mt19937_64 (whose sequence the
// C++ standard fixes) through our own uniform-double mapping (53 high bits), not
// std::uniform_real_distribution (implementation-defined). The same options give
// the same pack bit for bit with the same compiler, flags and libm; across
// platforms they may differ in the last bits (pow, log, sqrt in libm).
//
// Floes are written in their body frame (centroid at the origin, CCW) with yaw
// 0 and zero velocity; the window is the box [0, W] x [0, H] (walls lie outside).

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>

#include "core/floes.hpp"

namespace floesim {

struct SizeDistribution {
  enum class Kind { uniform, power_law };
  Kind kind = Kind::uniform;
  double exponent = 2.0;  // alpha of p(d) ∝ d^-alpha (power_law), > 0
  // Range of the equivalent diameter before scaling (m; only the ratio is
  // used). Both <= 0: uniform gives equal sizes, power_law a ratio of 10.
  double min_size = 0.0;
  double max_size = 0.0;
};

struct PackOptions {
  std::size_t floes = 100;        // N, >= 1 (walls not counted)
  double concentration = 0.5;     // C in (0, 0.95]: floe area over box area
  double width = 1000.0;          // m, the box is [0, W] x [0, H]
  double height = 1000.0;         // m
  std::uint64_t seed = 1;
  SizeDistribution sizes;
  double thickness_min = 1.0;     // m; thickness ~ U[min, max] (equal: constant)
  double thickness_max = 1.0;     // m
  double density = 917.0;         // kg/m^3
  double min_gap = -1.0;          // m; < 0: 1e-3 of the mean floe size
  int relax_iterations = 3;       // Lloyd steps (0: none)
  double wall_width = 0.0;        // m; > 0 adds four static walls around the box
};

struct GeneratedPack {
  Floes floes;                      // N floes, then the 4 walls if asked for
  std::array<double, 4> window{};   // xmin, xmax, ymin, ymax: the box
  std::size_t walls = 0;            // static floes at the end of `floes`
  double concentration = 0.0;       // achieved: floe area (walls excluded) / W H
  double min_gap = 0.0;             // m, smallest distance between two floes (exact;
                                    // wall–wall pairs excluded; inf for a lone floe)
  double required_gap = 0.0;        // m, the min_gap that was enforced
  double mean_size = 0.0;           // m, mean equivalent diameter
  std::array<double, 2> size_range{};  // m, [a, b] of the size law after scaling
  double max_area_error = 0.0;      // max_i |cell area - a_i| / a_i after the last solve
  std::size_t newton_iterations = 0;   // total over all solves
};

// Checks the options; throws InputError naming the option and what is expected.
void validate(const PackOptions& options);

// Builds the pack (validates first). Throws InputError for options that cannot
// be met (e.g. a concentration too high for the requested gap and size ratio).
GeneratedPack generate_pack(const PackOptions& options);

// Equivalent diameter of a floe of the given area: 2 sqrt(A / pi).
double equivalent_diameter(double area);

}  // namespace floesim
