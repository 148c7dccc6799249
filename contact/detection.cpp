#include "contact/detection.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace floesim::contact {

namespace {

struct Box {
  double xmin, xmax, ymin, ymax;
  bool overlaps(const Box& o) const {
    return xmin <= o.xmax && o.xmin <= xmax && ymin <= o.ymax && o.ymin <= ymax;
  }
};

Box box_of(std::span<const Vec2> v, double pad) {
  Box b{std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity(),
        std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity()};
  for (const Vec2& p : v) {
    b.xmin = std::min(b.xmin, p.x());
    b.xmax = std::max(b.xmax, p.x());
    b.ymin = std::min(b.ymin, p.y());
    b.ymax = std::max(b.ymax, p.y());
  }
  b.xmin -= pad; b.xmax += pad; b.ymin -= pad; b.ymax += pad;
  return b;
}

// Closest point of segment [p, q] to x.
Vec2 closest_on_segment(const Vec2& p, const Vec2& q, const Vec2& x) {
  const Vec2 e = q - p;
  const double l2 = e.squaredNorm();
  if (l2 == 0.0) return p;
  const double s = std::clamp((x - p).dot(e) / l2, 0.0, 1.0);
  return p + s * e;
}

// Closest point of a polygon's boundary to x.
Vec2 closest_on_boundary(std::span<const Vec2> poly, const Vec2& x) {
  Vec2 best = poly[0];
  double best_d2 = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < poly.size(); ++i) {
    const Vec2 c = closest_on_segment(poly[i], poly[(i + 1) % poly.size()], x);
    const double d2 = (c - x).squaredNorm();
    if (d2 < best_d2) { best_d2 = d2; best = c; }
  }
  return best;
}

// Largest separation of two convex CCW polygons along the outward normals of
// their edges: > 0 means disjoint, and then it is a lower bound on their
// distance; `normal` is that axis oriented from a towards b.
struct Separation {
  double gap = -std::numeric_limits<double>::infinity();
  Vec2 normal = Vec2::UnitX();
};
Separation separation(std::span<const Vec2> a, std::span<const Vec2> b) {
  Separation best;
  auto scan = [&](std::span<const Vec2> p, std::span<const Vec2> q, double sign) {
    for (std::size_t i = 0; i < p.size(); ++i) {
      const Vec2& v = p[i];
      const Vec2 e = p[(i + 1) % p.size()] - v;
      const double len = e.norm();
      if (len == 0.0) continue;
      const Vec2 n{e.y() / len, -e.x() / len};  // outward for counter-clockwise p
      double m = std::numeric_limits<double>::infinity();
      for (const Vec2& x : q) m = std::min(m, n.dot(x - v));
      if (m > best.gap) { best.gap = m; best.normal = sign * n; }
    }
  };
  scan(a, b, 1.0);
  scan(b, a, -1.0);
  return best;
}

// Distance between two convex polygons with the closest points; 0 and
// overlap = true when they intersect.
struct ConvexDistance {
  double distance = 0.0;
  Vec2 pa = Vec2::Zero(), pb = Vec2::Zero();
  bool overlap = false;
};

ConvexDistance distance_of(std::span<const Vec2> a, std::span<const Vec2> b) {
  ConvexDistance r;
  if (!(separation(a, b).gap > 0.0)) {
    r.overlap = true;
    r.pa = r.pb = a[0];
    return r;
  }
  r.distance = std::numeric_limits<double>::infinity();
  for (const Vec2& v : a) {
    const Vec2 c = closest_on_boundary(b, v);
    const double d = (c - v).norm();
    if (d < r.distance) { r.distance = d; r.pa = v; r.pb = c; }
  }
  for (const Vec2& v : b) {
    const Vec2 c = closest_on_boundary(a, v);
    const double d = (c - v).norm();
    if (d < r.distance) { r.distance = d; r.pa = c; r.pb = v; }
  }
  return r;
}

struct Entry {
  Box box;
  std::uint32_t floe;
  Vec2 shift;
};

}  // namespace

Detection detect(const Floes& floes, const CollisionShapes& shapes, const DetectionOptions& opt) {
  Detection out;
  const std::size_t n = floes.size();
  const double xi = opt.collision_distance;

  // World vertices of every part, same layout as shapes.vertices.
  std::vector<Vec2> world(shapes.vertices.size());
  std::vector<Box> part_box(shapes.vertex_offsets.size() - 1);
  std::vector<Box> floe_box(n);  // padded by half the search margin
  for (std::size_t i = 0; i < n; ++i) {
    const FloeState& s = floes.state[i];
    const double c = std::cos(s.yaw), sn = std::sin(s.yaw);
    Box fb = box_of({}, 0.0);
    for (std::size_t p = shapes.part_offsets[i]; p < shapes.part_offsets[i + 1]; ++p) {
      for (std::size_t k = shapes.vertex_offsets[p]; k < shapes.vertex_offsets[p + 1]; ++k) {
        const Vec2& b = shapes.vertices[k];
        world[k] = {s.x + c * b.x() - sn * b.y(), s.y + sn * b.x() + c * b.y()};
      }
      part_box[p] = box_of({world.data() + shapes.vertex_offsets[p], shapes.vertex_offsets[p + 1] - shapes.vertex_offsets[p]},
                           0.5 * opt.search_margin);
      fb.xmin = std::min(fb.xmin, part_box[p].xmin);
      fb.xmax = std::max(fb.xmax, part_box[p].xmax);
      fb.ymin = std::min(fb.ymin, part_box[p].ymin);
      fb.ymax = std::max(fb.ymax, part_box[p].ymax);
    }
    floe_box[i] = fb;
  }

  // Broad phase entries (with periodic images of floes that cross an edge).
  std::vector<Entry> entries;
  entries.reserve(n + n / 4);
  const Domain& d = opt.domain;
  for (std::uint32_t i = 0; i < n; ++i) {
    const Box& b = floe_box[i];
    entries.push_back({b, i, Vec2::Zero()});
    if (!d.periodic) continue;
    // Shifts of the images: 0 and, where the box crosses an edge, one period.
    const double sx[2] = {0.0, b.xmax > d.xmax ? -d.width() : (b.xmin < d.xmin ? d.width() : 0.0)};
    const double sy[2] = {0.0, b.ymax > d.ymax ? -d.height() : (b.ymin < d.ymin ? d.height() : 0.0)};
    for (int kx = 0; kx < 2; ++kx)
      for (int ky = 0; ky < 2; ++ky) {
        const double ox = sx[kx], oy = sy[ky];
        if ((kx == 1 && ox == 0.0) || (ky == 1 && oy == 0.0) || (kx == 0 && ky == 0)) continue;
        entries.push_back({{b.xmin + ox, b.xmax + ox, b.ymin + oy, b.ymax + oy}, i, Vec2{ox, oy}});
      }
  }
  std::sort(entries.begin(), entries.end(), [](const Entry& x, const Entry& y) { return x.box.xmin < y.box.xmin; });

  struct Candidate { std::uint32_t a, b; Vec2 shift; };
  std::vector<Candidate> candidates;
  std::vector<std::size_t> active;
  for (std::size_t e = 0; e < entries.size(); ++e) {
    const Entry& cur = entries[e];
    std::size_t keep = 0;
    for (std::size_t k = 0; k < active.size(); ++k)
      if (entries[active[k]].box.xmax >= cur.box.xmin) active[keep++] = active[k];
    active.resize(keep);
    for (std::size_t k : active) {
      const Entry& o = entries[k];
      if (o.floe == cur.floe || !o.box.overlaps(cur.box)) continue;
      if (floes.is_static[o.floe] && floes.is_static[cur.floe]) continue;
      // Canonical order a < b, with b shifted relative to a.
      if (o.floe < cur.floe) candidates.push_back({o.floe, cur.floe, cur.shift - o.shift});
      else candidates.push_back({cur.floe, o.floe, o.shift - cur.shift});
    }
    active.push_back(e);
  }
  // A pair may be found through several images: keep each (a, b, shift) once.
  auto key_less = [](const Candidate& x, const Candidate& y) {
    if (x.a != y.a) return x.a < y.a;
    if (x.b != y.b) return x.b < y.b;
    if (x.shift.x() != y.shift.x()) return x.shift.x() < y.shift.x();
    return x.shift.y() < y.shift.y();
  };
  std::sort(candidates.begin(), candidates.end(), key_less);
  candidates.erase(std::unique(candidates.begin(), candidates.end(),
                               [](const Candidate& x, const Candidate& y) {
                                 return x.a == y.a && x.b == y.b && x.shift == y.shift;
                               }),
                   candidates.end());

  // Narrow phase.
  std::vector<Vec2> shifted;
  const double pad = 0.5 * opt.search_margin;
  for (const Candidate& c : candidates) {
    NearPair pair;
    pair.a = c.a;
    pair.b = c.b;
    pair.shift = c.shift;
    // Box gap (unpadded boxes): a cheap lower bound for pairs well apart.
    const Box& A0 = floe_box[c.a];
    const Box& B0 = floe_box[c.b];
    const double gaps[4] = {B0.xmin + c.shift.x() - A0.xmax + 2 * pad, A0.xmin - B0.xmax - c.shift.x() + 2 * pad,
                            B0.ymin + c.shift.y() - A0.ymax + 2 * pad, A0.ymin - B0.ymax - c.shift.y() + 2 * pad};
    const Vec2 axes[4] = {Vec2::UnitX(), -Vec2::UnitX(), Vec2::UnitY(), -Vec2::UnitY()};
    const int widest = static_cast<int>(std::max_element(gaps, gaps + 4) - gaps);
    if (gaps[widest] > xi) {
      pair.distance = gaps[widest];
      pair.normal = axes[widest];
      out.pairs.push_back(pair);
      continue;
    }
    pair.distance = std::numeric_limits<double>::infinity();
    const std::size_t first_contact = out.contacts.size();
    for (std::size_t pa = shapes.part_offsets[c.a]; pa < shapes.part_offsets[c.a + 1]; ++pa) {
      const std::span<const Vec2> A{world.data() + shapes.vertex_offsets[pa],
                                    shapes.vertex_offsets[pa + 1] - shapes.vertex_offsets[pa]};
      for (std::size_t pb = shapes.part_offsets[c.b]; pb < shapes.part_offsets[c.b + 1]; ++pb) {
        Box bb = part_box[pb];
        bb.xmin += c.shift.x(); bb.xmax += c.shift.x(); bb.ymin += c.shift.y(); bb.ymax += c.shift.y();
        if (!part_box[pa].overlaps(bb)) continue;
        shifted.clear();
        for (std::size_t k = shapes.vertex_offsets[pb]; k < shapes.vertex_offsets[pb + 1]; ++k)
          shifted.push_back(world[k] + c.shift);
        // Parts separated by more than xi along an edge normal: that separation
        // is a lower bound (no contact points to find).
        const Separation sep = separation(A, shifted);
        if (sep.gap > xi) {
          if (sep.gap < pair.distance) {
            pair.distance = sep.gap;
            pair.normal = sep.normal;
            pair.exact = false;
          }
          continue;
        }
        const ConvexDistance dist = distance_of(A, shifted);
        if (dist.overlap) pair.overlap = true;
        if (dist.distance < pair.distance) {
          pair.distance = dist.distance;
          pair.pa = dist.pa;
          pair.pb = dist.pb;
          pair.exact = true;
          if (dist.distance > 0.0) pair.normal = (dist.pb - dist.pa) / dist.distance;
        }
        if (dist.overlap || dist.distance >= xi) continue;
        // Contact points: vertices of one part within xi of the other part.
        auto add = [&](const Vec2& v, const Vec2& q, bool from_a) {
          const double gap = (q - v).norm();
          if (gap >= xi || gap == 0.0) return;
          const Vec2 normal = from_a ? Vec2((q - v) / gap) : Vec2((v - q) / gap);
          const Vec2 point = 0.5 * (v + q);
          for (std::size_t k = first_contact; k < out.contacts.size(); ++k) {
            const ContactPoint& o = out.contacts[k];
            if ((o.point - point).norm() <= 1e-3 * xi && o.normal.dot(normal) > 1.0 - 1e-6) return;
          }
          out.contacts.push_back({c.a, c.b, point, normal, gap, c.shift});
        };
        for (const Vec2& v : A) add(v, closest_on_boundary(shifted, v), true);
        for (const Vec2& v : shifted) add(v, closest_on_boundary(A, v), false);
      }
    }
    if (pair.overlap) pair.distance = 0.0;
    out.pairs.push_back(pair);
  }
  return out;
}

}  // namespace floesim::contact
