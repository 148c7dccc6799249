#include "contact/detection.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace floesim::contact {

namespace {

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

struct Entry {
  Box box;
  std::uint32_t floe;
  Vec2 shift;
};

struct Candidate {
  std::uint32_t a, b;  // a < b
  Vec2 shift;          // of b
};

// Pairs of entries whose boxes overlap, through a uniform grid: each box is
// listed in the cells it covers (cell side: the mean box size, so a box
// covers about four), the (cell, entry) list is sorted by cell, and within a
// cell a pair is reported only if the cell holds the lower-left corner of the
// two boxes' intersection, so once. O(n) for a pack (counting sort), O(n log n)
// for floes spread over an open domain (cells hashed by sorting), with a
// bounded number of boxes per cell (a sweep along one axis grows as n^1.5).
std::vector<Candidate> broad_phase(const std::vector<Entry>& entries, const std::vector<std::uint8_t>& is_static) {
  std::vector<Candidate> out;
  if (entries.empty()) return out;
  double size = 0.0, x0 = entries[0].box.xmin, y0 = entries[0].box.ymin, x1 = x0, y1 = y0;
  for (const Entry& e : entries) {
    size += std::max(e.box.xmax - e.box.xmin, e.box.ymax - e.box.ymin);
    x0 = std::min(x0, e.box.xmin);
    y0 = std::min(y0, e.box.ymin);
    x1 = std::max(x1, e.box.xmax);
    y1 = std::max(y1, e.box.ymax);
  }
  const double h = std::max(size / static_cast<double>(entries.size()), 1e-9);
  // Boxes that are not finite (a state that overflowed; the step's state
  // check then fails the run) cannot be gridded: their cell numbers would be
  // undefined behaviour (UBSan: signed overflow). No pair is found among them.
  if (!std::isfinite(size) || !std::isfinite(x1 - x0) || !std::isfinite(y1 - y0)) return out;
  auto cell = [&](double v, double v0) { return static_cast<std::int64_t>(std::floor((v - v0) / h)); };
  // A pack's grid has about as many cells as floes: its cells are numbered
  // row by row and the items ordered by a counting sort, O(n). A grid with
  // many more cells than items (floes far apart in an open domain) is hashed
  // by sorting instead, so empty cells cost nothing. Both give the same order.
  const double cells = (static_cast<double>(cell(x1, x0)) + 1.0) * (static_cast<double>(cell(y1, y0)) + 1.0);
  const bool dense = cells <= 8.0 * static_cast<double>(entries.size());
  const std::int64_t row = dense ? cell(x1, x0) + 1 : std::int64_t{1} << 31;
  struct Item {
    std::int64_t key;
    std::uint32_t entry;
  };
  std::vector<Item> items;
  items.reserve(4 * entries.size());
  for (std::uint32_t e = 0; e < entries.size(); ++e) {
    const Box& b = entries[e].box;
    for (std::int64_t cy = cell(b.ymin, y0); cy <= cell(b.ymax, y0); ++cy)
      for (std::int64_t cx = cell(b.xmin, x0); cx <= cell(b.xmax, x0); ++cx) items.push_back({cy * row + cx, e});
  }
  if (dense) {
    // Items were made in entry order, so each cell's stay in entry order.
    std::vector<std::uint32_t> first(static_cast<std::size_t>(cells) + 1, 0);
    for (const Item& it : items) ++first[static_cast<std::size_t>(it.key) + 1];
    for (std::size_t c = 1; c < first.size(); ++c) first[c] += first[c - 1];
    std::vector<Item> sorted(items.size());
    for (const Item& it : items) sorted[first[static_cast<std::size_t>(it.key)]++] = it;
    items.swap(sorted);
  } else {
    std::sort(items.begin(), items.end(), [](const Item& p, const Item& q) {
      return p.key != q.key ? p.key < q.key : p.entry < q.entry;
    });
  }
  for (std::size_t first = 0; first < items.size();) {
    std::size_t last = first;
    while (last < items.size() && items[last].key == items[first].key) ++last;
    const std::int64_t key = items[first].key;
    for (std::size_t i = first; i < last; ++i) {
      const Entry& p = entries[items[i].entry];
      for (std::size_t j = i + 1; j < last; ++j) {
        const Entry& q = entries[items[j].entry];
        if (p.floe == q.floe || !p.box.overlaps(q.box)) continue;
        if (is_static[p.floe] && is_static[q.floe]) continue;
        const std::int64_t owner = cell(std::max(p.box.ymin, q.box.ymin), y0) * row +
                                   cell(std::max(p.box.xmin, q.box.xmin), x0);
        if (owner != key) continue;
        // Canonical order a < b, with b shifted relative to a.
        if (p.floe < q.floe) out.push_back({p.floe, q.floe, q.shift - p.shift});
        else out.push_back({q.floe, p.floe, p.shift - q.shift});
      }
    }
    first = last;
  }
  return out;
}

Box shifted_box(Box b, const Vec2& s) {
  b.xmin += s.x(); b.xmax += s.x(); b.ymin += s.y(); b.ymax += s.y();
  return b;
}

}  // namespace

PosedShapes::PosedShapes(const Floes& floes, const CollisionShapes& shapes)
    : shapes_(&shapes), world_(shapes.vertices.size()), part_box_(shapes.vertex_offsets.size() - 1),
      floe_box_(floes.size()) {
  for (std::size_t i = 0; i < floes.size(); ++i) update(floes, i);
}

PosedShapes::PosedShapes(const Floes& floes, const CollisionShapes& shapes, std::span<const std::uint32_t> which)
    : shapes_(&shapes), world_(shapes.vertices.size()), part_box_(shapes.vertex_offsets.size() - 1),
      floe_box_(floes.size()) {
  for (const std::uint32_t i : which) update(floes, i);
}

void PosedShapes::update(const Floes& floes, std::size_t i) {
  const CollisionShapes& shapes = *shapes_;
  const FloeState& s = floes.state[i];
  const double c = std::cos(s.yaw), sn = std::sin(s.yaw);
  Box fb = box_of({}, 0.0);
  for (std::size_t p = shapes.parts_begin(i); p < shapes.parts_end(i); ++p) {
    for (std::size_t k = shapes.vertex_offsets[p]; k < shapes.vertex_offsets[p + 1]; ++k) {
      const Vec2& b = shapes.vertices[k];
      world_[k] = {s.x + c * b.x() - sn * b.y(), s.y + sn * b.x() + c * b.y()};
    }
    part_box_[p] = box_of(part(p), 0.0);
    fb.xmin = std::min(fb.xmin, part_box_[p].xmin);
    fb.xmax = std::max(fb.xmax, part_box_[p].xmax);
    fb.ymin = std::min(fb.ymin, part_box_[p].ymin);
    fb.ymax = std::max(fb.ymax, part_box_[p].ymax);
  }
  floe_box_[i] = fb;
}

double exact_range(const Floes& floes, const CollisionShapes& shapes, std::uint32_t a, std::uint32_t b,
                   double horizon, double xi) {
  const FloeState &sa = floes.state[a], &sb = floes.state[b];
  const double speed = std::hypot(sb.vx - sa.vx, sb.vy - sa.vy) + std::abs(sa.yaw_rate) * shapes.radius[a] +
                       std::abs(sb.yaw_rate) * shapes.radius[b];
  return xi + speed * horizon;
}

NearPair measure_pair(const PosedShapes& posed, std::uint32_t a, std::uint32_t b, const Vec2& shift, double xi,
                      double range, std::vector<ContactPoint>& contacts, std::vector<Witness>& witnesses) {
  const CollisionShapes& shapes = posed.shapes();
  range = std::max(range, xi);
  NearPair pair;
  pair.a = a;
  pair.b = b;
  pair.shift = shift;
  pair.first_contact = static_cast<std::uint32_t>(contacts.size());
  pair.first_witness = static_cast<std::uint32_t>(witnesses.size());
  const Vec2 axes[4] = {Vec2::UnitX(), -Vec2::UnitX(), Vec2::UnitY(), -Vec2::UnitY()};
  // A separation along an axis, from boxes or separating axes: a lower bound.
  auto axis_bound = [&](double gap, const Vec2& normal) {
    if (pair.axis_distance < std::numeric_limits<double>::infinity()) pair.axis_any = true;
    if (gap < pair.axis_distance) {
      pair.axis_distance = gap;
      pair.axis_normal = normal;
    }
  };
  auto box_gap = [&](const Box& A, const Box& B, Vec2& normal) {
    const double g[4] = {B.xmin - A.xmax, A.xmin - B.xmax, B.ymin - A.ymax, A.ymin - B.ymax};
    const int widest = static_cast<int>(std::max_element(g, g + 4) - g);
    normal = axes[widest];
    return g[widest];
  };
  Vec2 n;
  double closest = std::numeric_limits<double>::infinity();  // least vertex distance
  bool touching = false;
  const double floe_gap = box_gap(posed.floe_box(a), shifted_box(posed.floe_box(b), shift), n);
  if (floe_gap > range) {
    axis_bound(floe_gap, n);
  } else {
    // Vertices of b's part, shifted (small: a few dozen at most).
    thread_local std::vector<Vec2> shifted;
    for (std::size_t pa = shapes.parts_begin(a); pa < shapes.parts_end(a); ++pa) {
      const std::span<const Vec2> A = posed.part(pa);
      for (std::size_t pb = shapes.parts_begin(b); pb < shapes.parts_end(b); ++pb) {
        const double part_gap = box_gap(posed.part_box(pa), shifted_box(posed.part_box(pb), shift), n);
        if (part_gap > range) {
          axis_bound(part_gap, n);
          continue;
        }
        shifted.clear();
        for (const Vec2& v : posed.part(pb)) shifted.push_back(v + shift);
        const Separation sep = separation(A, shifted);
        if (sep.gap > range) {
          axis_bound(sep.gap, sep.normal);
          continue;
        }
        if (!(sep.gap > 0.0)) {
          pair.overlap = true;
          continue;
        }
        // Vertex by vertex: witnesses, contact points, the distance.
        auto vertex = [&](const Vec2& v, const Vec2& q, bool from_a) {
          const double d = (q - v).norm();
          if (d == 0.0) {  // touching: no normal
            touching = true;
            return;
          }
          const Vec2 on_a = from_a ? v : q, on_b = from_a ? q : v;
          const Vec2 normal = (on_b - on_a) / d;
          if (d < closest) {
            closest = d;
            pair.pa = on_a;
            pair.pb = on_b;
            pair.normal = normal;
          }
          if (d >= range) {
            pair.far_distance = std::min(pair.far_distance, d);
            return;
          }
          witnesses.push_back({on_a, on_b, normal, d, !from_a});
          if (d >= xi) return;
          const Vec2 point = 0.5 * (v + q);
          for (std::size_t k = pair.first_contact; k < contacts.size(); ++k) {
            const ContactPoint& o = contacts[k];
            if ((o.point - point).norm() <= 1e-3 * xi && o.normal.dot(normal) > 1.0 - 1e-6) return;
          }
          contacts.push_back({a, b, point, normal, d, shift, false, !from_a});
        };
        for (const Vec2& v : A) vertex(v, closest_on_boundary(shifted, v), true);
        for (const Vec2& v : shifted) vertex(v, closest_on_boundary(A, v), false);
      }
    }
  }
  // The pair's distance: the least over its parts, exact or a bound.
  if (pair.overlap || touching) {
    pair.distance = 0.0;
  } else if (closest <= pair.axis_distance) {
    pair.distance = closest;
    pair.exact = true;
  } else {
    pair.distance = pair.axis_distance;
    pair.normal = pair.axis_normal;
  }
  pair.contact_count = static_cast<std::uint32_t>(contacts.size()) - pair.first_contact;
  pair.witness_count = static_cast<std::uint32_t>(witnesses.size()) - pair.first_witness;
  return pair;
}

Detection detect(const Floes& floes, const CollisionShapes& shapes, const DetectionOptions& opt) {
  Detection out;
  const std::size_t n = floes.size();
  const double xi = opt.collision_distance;
  const DetectionSubset& subset = opt.subset;
  const PosedShapes posed = subset.everything() ? PosedShapes(floes, shapes) : PosedShapes(floes, shapes, subset.posed);

  out.reach.resize(n);
  for (std::size_t i = 0; i < n; ++i) out.reach[i] = opt.reach_of(i);

  // Broad phase entries, boxes padded by reach + xi/2 (with periodic images of
  // floes that cross an edge).
  const std::size_t entered = subset.everything() ? n : subset.posed.size();
  std::vector<Entry> entries;
  entries.reserve(entered + entered / 4);
  const Domain& d = opt.domain;
  for (std::size_t k = 0; k < entered; ++k) {
    const std::uint32_t i = subset.everything() ? static_cast<std::uint32_t>(k) : subset.posed[k];
    const double pad = out.reach[i] + 0.5 * xi;
    const Box& f = posed.floe_box(i);
    const Box b{f.xmin - pad, f.xmax + pad, f.ymin - pad, f.ymax + pad};
    entries.push_back({b, i, Vec2::Zero()});
    if (!d.periodic) continue;
    // Shifts of the images: 0 and, where the box crosses an edge, one period.
    const double sx[2] = {0.0, b.xmax > d.xmax ? -d.width() : (b.xmin < d.xmin ? d.width() : 0.0)};
    const double sy[2] = {0.0, b.ymax > d.ymax ? -d.height() : (b.ymin < d.ymin ? d.height() : 0.0)};
    for (int kx = 0; kx < 2; ++kx)
      for (int ky = 0; ky < 2; ++ky) {
        const double ox = sx[kx], oy = sy[ky];
        if ((kx == 1 && ox == 0.0) || (ky == 1 && oy == 0.0) || (kx == 0 && ky == 0)) continue;
        entries.push_back({shifted_box(b, Vec2{ox, oy}), i, Vec2{ox, oy}});
      }
  }
  std::vector<Candidate> candidates = broad_phase(entries, floes.is_static);
  if (!subset.everything())
    std::erase_if(candidates, [&](const Candidate& c) { return subset.keep[c.a] == 0; });
  // A pair may be found through several images: keep each (a, b, shift) once.
  std::sort(candidates.begin(), candidates.end(), pair_before<Candidate>);
  candidates.erase(std::unique(candidates.begin(), candidates.end(),
                               [](const Candidate& x, const Candidate& y) {
                                 return x.a == y.a && x.b == y.b && x.shift == y.shift;
                               }),
                   candidates.end());

  out.pairs.reserve(candidates.size());
  for (const Candidate& c : candidates)
    out.pairs.push_back(measure_pair(posed, c.a, c.b, c.shift, xi,
                                     exact_range(floes, shapes, c.a, c.b, opt.horizon, xi), out.contacts,
                                     out.witnesses));
  return out;
}

}  // namespace floesim::contact
