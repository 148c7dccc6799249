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

CollisionShapes build_collision_shapes(const Floes& floes) {
  CollisionShapes s;
  extend_collision_shapes(s, floes, 0);
  return s;
}

}  // namespace floesim::contact
