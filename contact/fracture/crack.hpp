#pragma once
// Straight cracks in floe polygons: the chord of the polygon along a line
// through a point, the mesh triangles a crack segment cuts, and the split of
// a polygon along a chord into two polygons.

#include <array>
#include <optional>
#include <span>
#include <vector>

#include "contact/fracture/mesh.hpp"

namespace floesim::fracture {

// The part of the line p + s d (d a unit vector) that contains p and lies in
// the polygon: s in [s0, s1], s0 <= 0 <= s1, each end on the outline, on
// edge e0 resp. e1 (edge i joins vertex i to vertex i+1). A point on the
// outline gets the side that enters the polygon (the longer one if both do).
struct Chord {
  bool valid = false;
  double s0 = 0.0, s1 = 0.0;  // m
  std::size_t e0 = 0, e1 = 0;
  Vec2 from = Vec2::Zero(), to = Vec2::Zero();  // p + s0 d, p + s1 d
  double length() const { return s1 - s0; }
};
Chord chord_through(std::span<const Vec2> polygon, const Vec2& p, const Vec2& d);

// The two polygons (counter-clockwise) on either side of a valid chord:
// from -> vertices after e0 up to e1 -> to, and to -> vertices after e1 up to
// e0 -> from. Vertices closer than `merge` to a chord end are dropped.
// nullopt when a side would have fewer than 3 vertices.
std::optional<std::array<std::vector<Vec2>, 2>> split_polygon(std::span<const Vec2> polygon, const Chord& chord,
                                                              double merge);

// Triangles of the mesh that the segment [a, b] meets (touching a vertex or
// running along an edge counts: removing them separates the two faces).
std::vector<int> triangles_cut(const Mesh& mesh, const Vec2& a, const Vec2& b);

}  // namespace floesim::fracture
