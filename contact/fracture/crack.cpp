#include "contact/fracture/crack.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace floesim::fracture {

Chord chord_through(std::span<const Vec2> v, const Vec2& p, const Vec2& d) {
  const std::size_t n = v.size();
  double scale = 0.0;
  for (const Vec2& q : v) scale = std::max(scale, (q - p).norm());
  const double tol = 1e-12 * std::max(scale, 1.0);
  // Intersections of the line with every edge: p + s d = a + t (b - a).
  std::vector<std::pair<double, std::size_t>> hits;
  for (std::size_t i = 0; i < n; ++i) {
    const Vec2& a = v[i];
    const Vec2 e = v[(i + 1) % n] - a;
    const double den = cross(d, e);
    if (std::abs(den) <= 1e-14 * e.norm()) continue;  // parallel: the ends of the neighbours count
    const Vec2 w = a - p;
    const double s = cross(w, e) / den;
    const double t = cross(w, d) / den;
    if (t < -1e-12 || t > 1.0 + 1e-12) continue;
    hits.emplace_back(s, i);
  }
  std::sort(hits.begin(), hits.end());
  Chord best;
  for (std::size_t k = 0; k + 1 < hits.size(); ++k) {
    const double s0 = hits[k].first, s1 = hits[k + 1].first;
    if (s1 - s0 <= tol || s0 > tol || s1 < -tol) continue;
    if (!point_in_polygon(v, p + 0.5 * (s0 + s1) * d)) continue;
    if (best.valid && best.length() >= s1 - s0) continue;
    best.valid = true;
    best.s0 = std::min(s0, 0.0);
    best.s1 = std::max(s1, 0.0);
    best.e0 = hits[k].second;
    best.e1 = hits[k + 1].second;
  }
  if (best.valid) {
    best.from = p + best.s0 * d;
    best.to = p + best.s1 * d;
  }
  return best;
}

std::optional<std::array<std::vector<Vec2>, 2>> split_polygon(std::span<const Vec2> v, const Chord& c, double merge) {
  if (!c.valid || c.e0 == c.e1) return std::nullopt;
  const std::size_t n = v.size();
  auto side = [&](const Vec2& start, std::size_t e_start, const Vec2& end, std::size_t e_end) {
    std::vector<Vec2> out{start};
    for (std::size_t i = (e_start + 1) % n;; i = (i + 1) % n) {
      if ((v[i] - start).norm() > merge && (v[i] - end).norm() > merge) out.push_back(v[i]);
      if (i == e_end) break;
    }
    out.push_back(end);
    return out;
  };
  std::array<std::vector<Vec2>, 2> pieces{side(c.from, c.e0, c.to, c.e1), side(c.to, c.e1, c.from, c.e0)};
  for (const auto& piece : pieces)
    if (piece.size() < 3) return std::nullopt;
  return pieces;
}

std::vector<int> triangles_cut(const Mesh& mesh, const Vec2& a, const Vec2& b) {
  std::vector<int> out;
  const Vec2 ab = b - a;
  const double len = ab.norm();
  if (!(len > 0.0)) return out;
  const Vec2 nab{-ab.y() / len, ab.x() / len};
  const double tol = 1e-9 * mesh.size;
  // Separating axes of a segment and a triangle: the segment's normal, the
  // segment's direction and the triangle's edge normals. Touching counts as a
  // cut (projections that meet within tol): a node on the crack line would
  // otherwise still join the two faces.
  auto range = [](const Vec2& axis, const std::array<Vec2, 3>& t) {
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (const Vec2& q : t) {
      lo = std::min(lo, axis.dot(q));
      hi = std::max(hi, axis.dot(q));
    }
    return std::pair{lo, hi};
  };
  auto separated = [&](const Vec2& axis, const std::array<Vec2, 3>& t) {
    const auto [lo, hi] = range(axis, t);
    const double pa = axis.dot(a), pb = axis.dot(b);
    return std::min(hi, std::max(pa, pb)) - std::max(lo, std::min(pa, pb)) < -tol;
  };
  for (std::size_t k = 0; k < mesh.triangles.size(); ++k) {
    const auto& tri = mesh.triangles[k];
    const std::array<Vec2, 3> t{mesh.nodes[static_cast<std::size_t>(tri[0])], mesh.nodes[static_cast<std::size_t>(tri[1])],
                                mesh.nodes[static_cast<std::size_t>(tri[2])]};
    bool apart = separated(nab, t) || separated(ab / len, t);
    for (int i = 0; i < 3 && !apart; ++i) {
      const Vec2 e = t[static_cast<std::size_t>((i + 1) % 3)] - t[static_cast<std::size_t>(i)];
      apart = separated(Vec2{-e.y(), e.x()}.normalized(), t);
    }
    if (!apart) out.push_back(static_cast<int>(k));
  }
  return out;
}

}  // namespace floesim::fracture
