#pragma once
// Collision shapes: each floe as a set of convex parts (a convex floe is its
// own single part; a non-convex one is cut by core/convex_partition), in the
// body frame, stored contiguously. Built once per floe set.

#include <span>
#include <vector>

#include "core/floes.hpp"

namespace floesim::contact {

struct CollisionShapes {
  std::vector<std::size_t> part_offsets{0};    // floe i owns parts [part_offsets[i], part_offsets[i+1])
  std::vector<std::size_t> vertex_offsets{0};  // part p owns vertices [vertex_offsets[p], vertex_offsets[p+1])
  std::vector<Vec2> vertices;                  // m, body frame, counter-clockwise per part
  std::vector<double> radius;                  // per floe: max |vertex| (bounding circle about G)

  std::span<const Vec2> part(std::size_t p) const {
    return {vertices.data() + vertex_offsets[p], vertex_offsets[p + 1] - vertex_offsets[p]};
  }
  std::size_t parts_of(std::size_t floe) const { return part_offsets[floe + 1] - part_offsets[floe]; }

  // What these arrays allocate, against the entries of the floes `held`
  // marks (core/floe_bytes.hpp; empty: every floe): their part offsets and
  // radii, their parts' vertex offsets and vertices.
  FloeBytes memory(std::span<const std::uint8_t> held) const;
};

CollisionShapes build_collision_shapes(const Floes& floes);

// Appends the shapes of floes [first, floes.size()) (after floes were added, e.g. a split).
void extend_collision_shapes(CollisionShapes& shapes, const Floes& floes, std::size_t first);

}  // namespace floesim::contact
