#pragma once
// Triangle meshes of floe polygons for the percussion model (MODEL.md §6).
//
// A floe's polygon is meshed once by CGAL's constrained Delaunay refinement
// (Delaunay_mesher_2, a Ruppert–Shewchuk refinement): the polygon's edges are
// constraints, every triangle has its edges no longer than `size` and its
// smallest angle no smaller than about 20.7 degrees (CGAL's shape bound
// B = sin^2(min angle) = 0.125, the largest for which refinement is
// guaranteed to end). CGAL types stay in mesh.cpp.
//
// A floe much larger than the mesh size would give millions of triangles; the
// size bound is then raised so that the mesh has about `max_triangles`
// triangles (Mesh::size says which bound was used). A floe only a few mesh
// sizes across is resolved too coarsely for its stresses (a 28 m square
// struck on a side: its peak sigma_1 is 23% low at size 10 m, 4% at 2.5 m;
// docs/fracture.md), so with `across` > 0 the size bound is at most its
// diameter / across.

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "core/geometry.hpp"

namespace floesim::fracture {

struct MeshOptions {
  double size = 2.0;                // m, upper bound on the triangles' edge length
  double shape_bound = 0.125;       // CGAL's B = sin^2(smallest angle allowed)
  std::size_t max_triangles = 12000;  // the size bound grows beyond this many (estimated)
  double across = 0.0;              // the size bound is at most the polygon's diameter / across; 0: `size` alone
};

struct Mesh {
  std::vector<Vec2> nodes;                       // m, in the polygon's frame
  std::vector<std::array<int, 3>> triangles;     // node indices, counter-clockwise
  std::vector<std::uint8_t> on_boundary;         // per node: 1 if on the polygon's outline
  double size = 0.0;                             // m, the size bound used

  std::size_t node_count() const { return nodes.size(); }
  double area(std::size_t t) const;              // m^2 (> 0)
};

// Meshes a simple counter-clockwise polygon (as make_floe_shape produces).
// Throws RunError for fewer than 3 vertices, non-finite input, size <= 0: the
// floes and [fracture] mesh_size were checked at load, so this is met only by
// a polygon made during a run.
Mesh mesh_polygon(std::span<const Vec2> polygon, const MeshOptions& options);

}  // namespace floesim::fracture
