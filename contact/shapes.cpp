#include "contact/shapes.hpp"

#include <algorithm>

#include "core/convex_partition.hpp"

namespace floesim::contact {

void extend_collision_shapes(CollisionShapes& s, const Floes& floes, std::size_t first) {
  for (std::size_t i = first; i < floes.size(); ++i) {
    const auto v = floes.vertices(i);
    double r = 0.0;
    for (const Vec2& p : v) r = std::max(r, p.norm());
    s.radius.push_back(r);
    if (is_convex(v)) {
      s.vertices.insert(s.vertices.end(), v.begin(), v.end());
      s.vertex_offsets.push_back(s.vertices.size());
    } else {
      for (const auto& piece : convex_partition(v)) {
        s.vertices.insert(s.vertices.end(), piece.begin(), piece.end());
        s.vertex_offsets.push_back(s.vertices.size());
      }
    }
    s.part_offsets.push_back(s.vertex_offsets.size() - 1);
  }
}

FloeBytes CollisionShapes::memory(std::span<const std::uint8_t> held) const {
  const std::size_t n = radius.size();
  std::size_t floes = 0, parts = 0, points = 0;
  for (std::size_t i = 0; i < n; ++i) {
    if (!held.empty() && (i >= held.size() || !held[i])) continue;
    ++floes;
    parts += parts_of(i);
    points += vertex_offsets[part_offsets[i + 1]] - vertex_offsets[part_offsets[i]];
  }
  return {capacity_bytes(part_offsets) + capacity_bytes(vertex_offsets) + capacity_bytes(vertices) +
              capacity_bytes(radius),
          (floes + 1 + parts) * sizeof(std::size_t) + points * sizeof(Vec2) + floes * sizeof(double)};
}

CollisionShapes build_collision_shapes(const Floes& floes) {
  CollisionShapes s;
  extend_collision_shapes(s, floes, 0);
  return s;
}

}  // namespace floesim::contact
