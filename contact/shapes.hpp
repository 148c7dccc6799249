#pragma once
// Collision shapes: each floe as a set of convex parts (a convex floe is its
// own single part; a non-convex one is cut by core/convex_partition), in the
// body frame. A floe's shape is a function of its body vertices alone.
//
// Held by band (docs/parallel.md, "The collision shapes held by band
// (shapes28)"): on several ranks, with the advance on each rank's part, a
// rank reads the parts of the floes it holds only (its own and its band:
// the detection of its part, the advance's clusters), and of the floes
// routed to it with their pairs (hold(RoutedShapes), parallel/
// advance_share.hpp). So it keeps those and no other (part_count 0), as the
// drift's quadrature does (coupling/drift.hpp): a floe entering the held
// set gets its parts appended at the end (built from its vertices, which
// every rank keeps: the same bits), a floe leaving leaves dead parts
// behind, and the arrays are compacted in floe order when the dead
// vertices exceed a fraction of the live ones or an append would outgrow
// the capacity (CollisionShapesOptions). A floe's parts are contiguous and
// in the order the partition gives; every reader walks a floe's parts in
// that order and indexes the floes by floe number, so the layout changes
// no result.
//
// The radius stays every floe's (8 B a floe): it is what decides who holds
// a floe (the band's half width R_j + reach_j + xi/2, parallel/place.hpp),
// so it is read for floes the rank does not hold.
#include <span>
#include <vector>

#include "core/floes.hpp"

namespace floesim::contact {

// When the held floes' arrays are compacted (CollisionShapes::hold,
// ensure, append; their layout only: no result reads it). A compaction
// copies the live vertices; an append that outgrows the capacity would
// reallocate by doubling and hold up to twice the vertices.
struct CollisionShapesOptions {
  // Compacted when the dead vertices exceed this fraction of the live ones:
  // at 0.5 a compaction copies at most twice the dead vertices it frees.
  double compact_dead = 0.5;
  // A compaction leaves room for this fraction more than the live and the
  // needed vertices, so that the next floes entering append in place.
  double spare = 0.25;
};

struct CollisionShapes {
  std::vector<std::size_t> first_part;         // per floe: its first part
  std::vector<std::uint32_t> part_count;       // per floe: its parts (0: not held)
  std::vector<std::size_t> vertex_offsets{0};  // part p owns vertices [vertex_offsets[p], vertex_offsets[p+1])
  std::vector<Vec2> vertices;                  // m, body frame, counter-clockwise per part
  std::vector<double> radius;                  // per floe, every floe: max |vertex| (bounding circle about G)
  std::size_t dead_vertices = 0;               // vertices in no held floe's parts (left by floes let go)
  CollisionShapesOptions options;              // kept by forget()

  std::span<const Vec2> part(std::size_t p) const {
    return {vertices.data() + vertex_offsets[p], vertex_offsets[p + 1] - vertex_offsets[p]};
  }
  // Floe i's parts are [parts_begin(i), parts_end(i)).
  std::size_t parts_begin(std::size_t floe) const { return first_part[floe]; }
  std::size_t parts_end(std::size_t floe) const { return first_part[floe] + part_count[floe]; }
  std::size_t parts_of(std::size_t floe) const { return part_count[floe]; }
  // Whether floe i's parts are here (every floe has one part at least).
  bool has(std::size_t floe) const { return floe < part_count.size() && part_count[floe] > 0; }

  // Keeps the parts of the floes `held` marks (empty: every floe) and of no
  // other: drops the others', builds the held floes' that have none (a floe
  // entering the held set; floes added since, e.g. a split's pieces), sets
  // the radii of floes added since; compacts when due.
  void hold(const Floes& floes, std::span<const std::uint8_t> held);
  // Builds the parts of the listed floes that have none, dropping nothing
  // (the floes a detection or an advance is about to read).
  void ensure(const Floes& floes, std::span<const std::uint32_t> which);
  // Builds every floe's missing parts (the whole paths: a rebuild of the
  // pair list over every floe, the whole advance).
  void ensure_every(const Floes& floes);
  // Appends the parts of a floe that has none (here from elsewhere: a
  // routed shape, the same bits as a build from its vertices). `vertices`
  // holds the parts one after the other, `sizes` their vertex counts.
  void append(std::size_t floe, std::span<const std::uint32_t> sizes, std::span<const Vec2> vertices);
  // Every floe's parts dropped and every radius set from `floes` (the floes
  // changed: a split's parent, a restart), the arrays freed; the options kept.
  void forget(const Floes& floes);

  // What these arrays allocate, against the entries of the floes `held`
  // marks (core/floe_bytes.hpp; empty: every floe): their part offsets and
  // radii, their parts' vertex offsets and vertices.
  FloeBytes memory(std::span<const std::uint8_t> held) const;
};

// Every floe's shape, in floe order, the arrays fitted to their size.
CollisionShapes build_collision_shapes(const Floes& floes, const CollisionShapesOptions& options = {});

// Appends the shapes of floes [first, floes.size()) (after floes were added, e.g. a split).
void extend_collision_shapes(CollisionShapes& shapes, const Floes& floes, std::size_t first);

}  // namespace floesim::contact
