// Convex partition through CGAL's Partition_2 (Greene's optimal dynamic
// programme, Hertel–Mehlhorn). CGAL types stay in this file.
#include "core/convex_partition.hpp"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Partition_traits_2.h>
#include <CGAL/partition_2.h>

#include <cmath>
#include <iterator>
#include <list>
#include <string>

#include "core/error.hpp"

namespace floesim {

namespace {

// Exact predicates on double coordinates: the pieces' vertices are input
// vertices (a partition adds only diagonals, never new points), so no
// construction is ever rounded and exact predicates make the result exact.
using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Traits = CGAL::Partition_traits_2<Kernel>;
using Point = Traits::Point_2;
using Polygon = Traits::Polygon_2;

Point to_cgal(const Vec2& p) { return {p.x(), p.y()}; }

CGAL::Orientation turn(const Vec2& a, const Vec2& b, const Vec2& c) {
  return CGAL::orientation(to_cgal(a), to_cgal(b), to_cgal(c));
}

void require_ccw_polygon(std::span<const Vec2> v) {
  if (v.size() < 3)
    throw InputError("convex_partition: a polygon needs at least 3 vertices, got " + std::to_string(v.size()));
  for (const Vec2& p : v)
    if (!std::isfinite(p.x()) || !std::isfinite(p.y()))
      throw InputError("convex_partition: non-finite vertex coordinate");
  if (!(signed_area(v) > 0.0))
    throw InputError("convex_partition: the polygon must be counter-clockwise with a positive area");
}

}  // namespace

bool is_convex(std::span<const Vec2> polygon) {
  const std::size_t n = polygon.size();
  for (std::size_t i = 0; i < n; ++i)
    if (turn(polygon[i], polygon[(i + 1) % n], polygon[(i + 2) % n]) == CGAL::RIGHT_TURN) return false;
  return true;
}

std::vector<std::vector<Vec2>> convex_partition(std::span<const Vec2> polygon,
                                                const ConvexPartitionOptions& options) {
  require_ccw_polygon(polygon);
  if (is_convex(polygon)) return {std::vector<Vec2>(polygon.begin(), polygon.end())};
  FLOESIM_ASSERT(!find_self_intersection(polygon));

  // Drop collinear vertices: a straight angle is neither a reflex vertex nor a
  // useful diagonal end, and CGAL's partitions expect none. Repeated until
  // stable, since a removal can make a neighbour straight (a spike folded flat).
  std::vector<Point> pts;
  pts.reserve(polygon.size());
  for (const Vec2& p : polygon) pts.push_back(to_cgal(p));
  for (bool removed = true; removed && pts.size() > 3;) {
    removed = false;
    for (std::size_t i = 0; i < pts.size() && pts.size() > 3;) {
      const std::size_t n = pts.size();
      if (CGAL::collinear(pts[(i + n - 1) % n], pts[i], pts[(i + 1) % n])) {
        pts.erase(pts.begin() + static_cast<std::ptrdiff_t>(i));
        removed = true;
      } else {
        ++i;
      }
    }
  }

  const bool optimal = options.method == PartitionMethod::optimal ||
                       (options.method == PartitionMethod::automatic &&
                        pts.size() <= options.optimal_max_vertices);
  std::list<Polygon> pieces;
  const Traits traits;
  if (optimal)
    CGAL::optimal_convex_partition_2(pts.begin(), pts.end(), std::back_inserter(pieces), traits);
  else
    CGAL::approx_convex_partition_2(pts.begin(), pts.end(), std::back_inserter(pieces), traits);

  std::vector<std::vector<Vec2>> out;
  out.reserve(pieces.size());
  for (const Polygon& piece : pieces) {
    std::vector<Vec2>& v = out.emplace_back();
    v.reserve(piece.size());
    for (auto it = piece.vertices_begin(); it != piece.vertices_end(); ++it) v.emplace_back(it->x(), it->y());
  }
  return out;
}

}  // namespace floesim
