#pragma once
// Convex partition of a simple polygon. The collision code treats a non-convex
// floe as the union of convex pieces (MODEL.md §2): contact detection and
// distances are then convex–convex. Done once per floe shape at set-up, not
// per step.
//
// Methods (CGAL's 2D polygon partitioning, kept out of this header):
//  * optimal: Greene's dynamic programme, the fewest pieces; O(n^4) time and
//    O(n^3) memory, so only for small polygons;
//  * approximate: Hertel–Mehlhorn (triangulate, then drop every diagonal whose
//    removal keeps both sides convex): at most 4x the optimal number of
//    pieces, O(n log n);
//  * automatic (the default): optimal up to `optimal_max_vertices` vertices,
//    approximate above. Floes have tens of vertices, so this is usually optimal.
//
// Contract: the input is a simple, counter-clockwise polygon (as make_floe_shape
// produces; not closed). Pieces are counter-clockwise, not closed, in the same
// frame as the input; their interiors are disjoint and their union is the
// polygon. A convex input (collinear vertices allowed) is returned unchanged, as
// the single piece. Collinear vertices of a non-convex input are dropped before
// partitioning (they do not change the region).

#include <cstddef>
#include <span>
#include <vector>

#include "core/geometry.hpp"

namespace floesim {

enum class PartitionMethod { automatic, optimal, approximate };

struct ConvexPartitionOptions {
  PartitionMethod method = PartitionMethod::automatic;
  std::size_t optimal_max_vertices = 32;  // automatic: optimal up to this many vertices
};

// Whether a counter-clockwise polygon is convex: no right turn at any vertex
// (exact orientation tests; collinear vertices count as convex).
bool is_convex(std::span<const Vec2> polygon);

// The convex pieces of a simple counter-clockwise polygon. Throws InputError for
// fewer than 3 vertices, non-finite coordinates or a clockwise / zero-area outline.
std::vector<std::vector<Vec2>> convex_partition(std::span<const Vec2> polygon,
                                                const ConvexPartitionOptions& options = {});

}  // namespace floesim
