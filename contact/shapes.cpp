#include "contact/shapes.hpp"

#include <algorithm>

#include "core/convex_partition.hpp"
#include "core/error.hpp"

namespace floesim::contact {

namespace {
// Max |v| over the body vertices: the bounding circle about G.
double radius_of(std::span<const Vec2> v) {
  double r = 0.0;
  for (const Vec2& p : v) r = std::max(r, p.norm());
  return r;
}

// Appends floe i's parts (the floe itself when convex, else its convex
// partition's pieces) at the end of the arrays, as its range.
void append_floe(CollisionShapes& s, const Floes& floes, std::size_t i) {
  const auto v = floes.vertices(i);
  s.first_part[i] = s.vertex_offsets.size() - 1;
  if (is_convex(v)) {
    s.vertices.insert(s.vertices.end(), v.begin(), v.end());
    s.vertex_offsets.push_back(s.vertices.size());
  } else {
    for (const auto& piece : convex_partition(v)) {
      s.vertices.insert(s.vertices.end(), piece.begin(), piece.end());
      s.vertex_offsets.push_back(s.vertices.size());
    }
  }
  s.part_count[i] = static_cast<std::uint32_t>(s.vertex_offsets.size() - 1 - s.first_part[i]);
}

std::size_t vertices_of(const CollisionShapes& s, std::size_t i) {
  return s.vertex_offsets[s.parts_end(i)] - s.vertex_offsets[s.parts_begin(i)];
}

// The held floes' parts copied in floe order into arrays with room for
// `capacity` vertices (and parts in the stored parts' proportion to the
// stored vertices).
void compact(CollisionShapes& s, std::size_t capacity) {
  const std::size_t stored = s.vertex_offsets.size() - 1;  // parts, dead ones included
  std::vector<std::size_t> offsets{0};
  std::vector<Vec2> vertices;
  vertices.reserve(capacity);
  offsets.reserve(1 + (s.vertices.empty() ? stored : stored * capacity / s.vertices.size() + 1));
  for (std::size_t i = 0; i < s.part_count.size(); ++i) {
    if (s.part_count[i] == 0) continue;
    const std::size_t from = s.first_part[i];
    s.first_part[i] = offsets.size() - 1;
    for (std::size_t p = from; p < from + s.part_count[i]; ++p) {
      const std::span<const Vec2> v = s.part(p);
      vertices.insert(vertices.end(), v.begin(), v.end());
      offsets.push_back(vertices.size());
    }
  }
  s.vertex_offsets = std::move(offsets);
  s.vertices = std::move(vertices);
  s.dead_vertices = 0;
}

// Room for `needed` more vertices: compacted when the dead vertices exceed
// options.compact_dead times the live ones or when the appends would
// reallocate, into room for options.spare more than the live and needed
// vertices (CollisionShapesOptions: why). `needed` is a bound (bound_of)
// when the partition is not made yet.
void make_room(CollisionShapes& s, std::size_t needed) {
  const CollisionShapesOptions& o = s.options;
  FLOESIM_ASSERT(o.compact_dead >= 0.0 && o.spare >= 0.0);
  const std::size_t live = s.vertices.size() - s.dead_vertices;
  const auto share = [](double fraction, std::size_t n) {
    return static_cast<std::size_t>(fraction * static_cast<double>(n));
  };
  if (static_cast<double>(s.dead_vertices) > o.compact_dead * static_cast<double>(live) ||
      s.vertices.size() + needed > s.vertices.capacity())
    compact(s, live + needed + share(o.spare, live + needed));
}

// The vertices floe i's parts take, or a bound on them: a convex floe's
// own n (most floes: exact, so that the room reserved is not inflated); a
// partition adds diagonals only (core/convex_partition.hpp), each giving
// its two ends to one more piece, at most n - 3 of them: n + 2 (n - 3) < 3 n.
std::size_t bound_of(const Floes& floes, std::size_t i) {
  const auto v = floes.vertices(i);
  return is_convex(v) ? v.size() : 3 * v.size();
}

// The per-floe arrays sized to the floes (floes added since: no parts, their radii set).
void size_to(CollisionShapes& s, const Floes& floes) {
  const std::size_t n = floes.size(), had = s.radius.size();
  FLOESIM_ASSERT(had <= n);
  s.first_part.resize(n, 0);
  s.part_count.resize(n, 0);
  s.radius.resize(n, 0.0);
  for (std::size_t i = had; i < n; ++i) s.radius[i] = radius_of(floes.vertices(i));
}
}  // namespace

void extend_collision_shapes(CollisionShapes& s, const Floes& floes, std::size_t first) {
  FLOESIM_ASSERT(first == s.radius.size());
  size_to(s, floes);
  for (std::size_t i = first; i < floes.size(); ++i) append_floe(s, floes, i);
}

CollisionShapes build_collision_shapes(const Floes& floes, const CollisionShapesOptions& options) {
  CollisionShapes s;
  s.options = options;
  extend_collision_shapes(s, floes, 0);
  s.vertex_offsets.shrink_to_fit();
  s.vertices.shrink_to_fit();
  return s;
}

void CollisionShapes::hold(const Floes& floes, std::span<const std::uint8_t> held) {
  const std::size_t n = floes.size();
  FLOESIM_ASSERT(held.empty() || held.size() == n);
  size_to(*this, floes);
  std::size_t needed = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const bool keep = held.empty() || held[i] != 0;
    if (!keep && part_count[i] > 0) {
      dead_vertices += vertices_of(*this, i);
      part_count[i] = 0;
    } else if (keep && part_count[i] == 0) {
      needed += bound_of(floes, i);
    }
  }
  make_room(*this, needed);
  if (needed == 0) return;
  for (std::size_t i = 0; i < n; ++i)
    if ((held.empty() || held[i] != 0) && part_count[i] == 0) append_floe(*this, floes, i);
}

void CollisionShapes::ensure(const Floes& floes, std::span<const std::uint32_t> which) {
  size_to(*this, floes);
  std::size_t needed = 0;
  for (const std::uint32_t i : which)
    if (part_count[i] == 0) needed += bound_of(floes, i);
  if (needed == 0) return;
  make_room(*this, needed);
  for (const std::uint32_t i : which)
    if (part_count[i] == 0) append_floe(*this, floes, i);
}

void CollisionShapes::ensure_every(const Floes& floes) { hold(floes, {}); }

void CollisionShapes::append(std::size_t floe, std::span<const std::uint32_t> sizes, std::span<const Vec2> v) {
  FLOESIM_ASSERT(floe < part_count.size() && part_count[floe] == 0 && !sizes.empty());
  make_room(*this, v.size());
  first_part[floe] = vertex_offsets.size() - 1;
  std::size_t at = 0;
  for (const std::uint32_t k : sizes) {
    vertices.insert(vertices.end(), v.begin() + static_cast<std::ptrdiff_t>(at),
                    v.begin() + static_cast<std::ptrdiff_t>(at + k));
    vertex_offsets.push_back(vertices.size());
    at += k;
  }
  FLOESIM_ASSERT(at == v.size());
  part_count[floe] = static_cast<std::uint32_t>(sizes.size());
}

void CollisionShapes::forget(const Floes& floes) {
  const CollisionShapesOptions kept = options;
  *this = CollisionShapes();
  options = kept;
  size_to(*this, floes);
}

FloeBytes CollisionShapes::memory(std::span<const std::uint8_t> held) const {
  const std::size_t n = radius.size();
  std::size_t floes = 0, parts = 0, points = 0;
  for (std::size_t i = 0; i < n; ++i) {
    if (!held.empty() && (i >= held.size() || !held[i])) continue;
    ++floes;
    parts += parts_of(i);
    points += vertices_of(*this, i);
  }
  // A layout of the held floes alone: CSR part offsets (one more), their
  // parts' vertex offsets and vertices, their radii.
  return {capacity_bytes(first_part) + capacity_bytes(part_count) + capacity_bytes(vertex_offsets) +
              capacity_bytes(vertices) + capacity_bytes(radius),
          (floes + 1 + parts) * sizeof(std::size_t) + points * sizeof(Vec2) + floes * sizeof(double)};
}

}  // namespace floesim::contact
