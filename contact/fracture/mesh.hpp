#pragma once
// Triangle meshes of floe polygons for the percussion model (MODEL.md §6).
//
// Two meshers (MeshOptions::mesher):
//  * lattice (lattice_mesh.cpp), for convex polygons, the floes of packs (a
//    straight split of a convex floe is convex): nodes on the outline, each
//    edge divided into equal parts no longer than a = lattice_spacing x size;
//    inside, a triangular lattice of spacing a, rows along the longest edge,
//    keeping the points at least lattice_margin x a from every edge; the
//    constrained Delaunay triangulation of those points (ears clipped off the
//    outline, Lawson's flips, then Bowyer–Watson insertion of the lattice
//    with exact predicates, predicates.hpp). The triangles tile the polygon
//    and every outline segment is an edge (the outline is triangulated
//    first, and points are inserted only inside it). The mesh is accepted if
//    every edge is at most `size` and every angle at least the smaller of
//    `min_angle` and the polygon's sharpest corner (checked on each mesh);
//    otherwise CGAL meshes the polygon.
//  * CGAL's constrained Delaunay refinement (Delaunay_mesher_2, a
//    Ruppert–Shewchuk refinement): the polygon's edges are constraints, every
//    triangle has its edges no longer than `size` and its smallest angle no
//    smaller than about 20.7 degrees (CGAL's shape bound
//    B = sin^2(min angle) = 0.125, the largest for which refinement is
//    guaranteed to end), away from sharper input corners. For non-convex
//    polygons, and for any with Mesher::cgal. CGAL types stay in mesh.cpp.
// CGAL gives about one triangle per 0.2 size^2 (0.18 to 0.22 measured on
// squares and discs), the lattice one per sqrt(3)/4 a^2 = 0.156 size^2 at
// a = 0.6 size: the gap between the outline and the lattice needs a < size
// for its edges to stay within the bound. Spacing 0.6 and margin 0.45 are
// those that let most pack cells through (268 of 300 cells of a 500-floe
// pack at sizes 20, 10 and 5 m, against 264 at 0.6 and 0.5, 103 at 0.7 and
// 0.4; tests/contact/fracture/test_lattice_mesh.cpp); the others miss the
// angle bound at outline edges much shorter than a.
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
#include <optional>
#include <span>
#include <vector>

#include "core/geometry.hpp"

namespace floesim::fracture {

enum class Mesher {
  automatic,  // the lattice for convex polygons when its mesh meets the bounds, else CGAL
  cgal,       // CGAL's refinement for every polygon
  lattice,    // (Mesh::mesher only: the lattice made this mesh)
};

struct MeshOptions {
  Mesher mesher = Mesher::cgal;     // CGAL's irregular meshes unless asked (docs/fracture.md, "Mesh")
  double size = 2.0;                // m, upper bound on the triangles' edge length
  double shape_bound = 0.125;       // CGAL's B = sin^2(smallest angle allowed)
  double lattice_spacing = 0.6;     // the lattice's spacing and the outline's parts, over size
  double lattice_margin = 0.45;     // lattice points kept this many spacings from the outline
  double min_angle = 20.0;          // degrees: a lattice mesh with a smaller angle (than this
                                    // and than the polygon's corners) goes to CGAL
  std::size_t max_triangles = 12000;  // the size bound grows beyond this many (estimated)
  double across = 0.0;              // the size bound is at most the polygon's diameter / across; 0: `size` alone
};

struct Mesh {
  std::vector<Vec2> nodes;                       // m, in the polygon's frame
  std::vector<std::array<int, 3>> triangles;     // node indices, counter-clockwise
  std::vector<std::uint8_t> on_boundary;         // per node: 1 if on the polygon's outline
  double size = 0.0;                             // m, the size bound used
  Mesher mesher = Mesher::cgal;                  // which made it (cgal or lattice)

  std::size_t node_count() const { return nodes.size(); }
  double area(std::size_t t) const;              // m^2 (> 0)
};

// Meshes a simple counter-clockwise polygon (as make_floe_shape produces).
// Throws RunError for fewer than 3 vertices, non-finite input, size <= 0: the
// floes and [fracture] mesh_size were checked at load, so this is met only by
// a polygon made during a run.
Mesh mesh_polygon(std::span<const Vec2> polygon, const MeshOptions& options);

// The lattice mesh of a convex polygon at the size bound `size` (already
// capped); nullopt if the polygon is not convex or the mesh misses the bounds.
std::optional<Mesh> mesh_lattice(std::span<const Vec2> polygon, double size, const MeshOptions& options);

}  // namespace floesim::fracture
