// Floe meshing: the choice of mesher, and CGAL's Delaunay_mesher_2. CGAL types stay in this file.
#include "contact/fracture/mesh.hpp"

#include <CGAL/Constrained_Delaunay_triangulation_2.h>
#include <CGAL/Delaunay_mesh_face_base_2.h>
#include <CGAL/Delaunay_mesh_size_criteria_2.h>
#include <CGAL/Delaunay_mesh_vertex_base_2.h>
#include <CGAL/Delaunay_mesher_2.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Triangulation_vertex_base_with_info_2.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "core/error.hpp"

namespace floesim::fracture {

namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
// Each vertex carries its node number (-1 until numbered).
using Vb = CGAL::Delaunay_mesh_vertex_base_2<Kernel, CGAL::Triangulation_vertex_base_with_info_2<int, Kernel>>;
using Fb = CGAL::Delaunay_mesh_face_base_2<Kernel>;
using Tds = CGAL::Triangulation_data_structure_2<Vb, Fb>;
using Cdt = CGAL::Constrained_Delaunay_triangulation_2<Kernel, Tds>;
using Criteria = CGAL::Delaunay_mesh_size_criteria_2<Cdt>;

}  // namespace

double Mesh::area(std::size_t t) const {
  const auto& tri = triangles[t];
  return 0.5 * cross(nodes[tri[1]] - nodes[tri[0]], nodes[tri[2]] - nodes[tri[0]]);
}

Mesh mesh_polygon(std::span<const Vec2> polygon, const MeshOptions& options) {
  if (polygon.size() < 3)
    throw RunError("fracture mesh: a polygon needs at least 3 vertices, got " + std::to_string(polygon.size()));
  for (const Vec2& p : polygon)
    if (!p.allFinite()) throw RunError("fracture mesh: non-finite vertex coordinate");
  if (!(options.size > 0.0) || !std::isfinite(options.size))
    throw RunError("fracture mesh: the mesh size must be a finite number > 0 (m)");
  const double area = signed_area(polygon);
  if (!(area > 0.0)) throw RunError("fracture mesh: the polygon must be counter-clockwise with a positive area");

  // Refinement to edges <= s gives about one triangle per 0.2 s^2 (measured
  // on squares and discs: 0.18 to 0.22 s^2); keep the count bounded.
  double size = options.size;
  if (options.across > 0.0) {
    double diameter = 0.0;
    for (std::size_t i = 0; i < polygon.size(); ++i)
      for (std::size_t j = i + 1; j < polygon.size(); ++j) diameter = std::max(diameter, (polygon[i] - polygon[j]).norm());
    size = std::min(size, diameter / options.across);
  }
  const double cap = static_cast<double>(std::max<std::size_t>(options.max_triangles, 16));
  if (area / (0.2 * size * size) > cap) size = std::sqrt(area / (0.2 * cap));

  if (options.mesher != Mesher::cgal)
    if (std::optional<Mesh> lattice = mesh_lattice(polygon, size, options)) return std::move(*lattice);

  Cdt cdt;
  std::vector<Cdt::Point> pts;
  pts.reserve(polygon.size());
  for (const Vec2& p : polygon) pts.emplace_back(p.x(), p.y());
  cdt.insert_constraint(pts.begin(), pts.end(), /*close=*/true);
  // No seeds: the domain is the bounded region enclosed by the constraints.
  CGAL::refine_Delaunay_mesh_2(cdt, Criteria(options.shape_bound, size));

  Mesh mesh;
  mesh.size = size;
  // Nodes are numbered in the order the domain's faces first meet them.
  for (Cdt::Vertex_handle v : cdt.finite_vertex_handles()) v->info() = -1;
  for (Cdt::Face_handle f : cdt.finite_face_handles()) {
    if (!f->is_in_domain()) continue;
    std::array<int, 3> tri{};
    for (int k = 0; k < 3; ++k) {
      const Cdt::Vertex_handle v = f->vertex(k);
      if (v->info() < 0) {
        v->info() = static_cast<int>(mesh.nodes.size());
        mesh.nodes.emplace_back(v->point().x(), v->point().y());
      }
      tri[static_cast<std::size_t>(k)] = v->info();
    }
    mesh.triangles.push_back(tri);
  }
  // CGAL's faces are counter-clockwise; make sure, since the elements rely on it.
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t)
    if (mesh.area(t) < 0.0) std::swap(mesh.triangles[t][1], mesh.triangles[t][2]);

  // Boundary nodes: the ends of edges that belong to one triangle of the
  // domain only (the face across is outside it, or infinite).
  mesh.on_boundary.assign(mesh.nodes.size(), 0);
  for (Cdt::Face_handle f : cdt.finite_face_handles()) {
    if (!f->is_in_domain()) continue;
    for (int k = 0; k < 3; ++k)
      if (!f->neighbor(k)->is_in_domain())
        mesh.on_boundary[static_cast<std::size_t>(f->vertex(Cdt::cw(k))->info())] =
            mesh.on_boundary[static_cast<std::size_t>(f->vertex(Cdt::ccw(k))->info())] = 1;
  }
  if (mesh.triangles.empty()) throw RunError("fracture mesh: CGAL returned no triangle for the polygon");
  return mesh;
}

}  // namespace floesim::fracture
