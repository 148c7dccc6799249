// The collision shapes held by band (contact/shapes.hpp): the compaction's
// thresholds (CollisionShapesOptions) change where a floe's parts lie in
// the arrays and how much room they keep, never a floe's parts.
#include <doctest/doctest.h>

#include <algorithm>
#include <cstdint>
#include <vector>

#include "contact/shapes.hpp"
#include "core/floe.hpp"
#include "core/floes.hpp"

using namespace floesim;

namespace {
// Nine floes in a row: squares and non-convex L shapes (two parts each).
Floes row_of_floes() {
  Floes floes;
  for (int k = 0; k < 9; ++k) {
    const double x = 30.0 * k;
    FloeInput in;
    if (k % 3 == 2)
      in.vertices = {{x, 0.0}, {x + 12.0, 0.0}, {x + 12.0, 4.0}, {x + 4.0, 4.0}, {x + 4.0, 12.0}, {x, 12.0}};
    else
      in.vertices = {{x, 0.0}, {x + 10.0, 0.0}, {x + 10.0, 10.0}, {x, 10.0}};
    floes.add(make_floe_shape(in), in);
  }
  return floes;
}

// Every floe's parts: held alike, the same vertices part by part.
void check_same_parts(const contact::CollisionShapes& a, const contact::CollisionShapes& b, std::size_t floes) {
  CHECK(a.radius == b.radius);
  for (std::size_t i = 0; i < floes; ++i) {
    CAPTURE(i);
    REQUIRE(a.has(i) == b.has(i));
    if (!a.has(i)) continue;
    REQUIRE(a.parts_of(i) == b.parts_of(i));
    for (std::size_t k = 0; k < a.parts_of(i); ++k) {
      const auto pa = a.part(a.parts_begin(i) + k), pb = b.part(b.parts_begin(i) + k);
      CHECK(std::equal(pa.begin(), pa.end(), pb.begin(), pb.end()));
    }
  }
}
}  // namespace

TEST_CASE("collision shapes: the compaction's thresholds change the layout, not a floe's parts") {
  const Floes floes = row_of_floes();
  contact::CollisionShapesOptions eager;
  eager.compact_dead = 0.0;  // any dead vertex compacts
  eager.spare = 1.0;         // into room for twice the live and needed vertices
  contact::CollisionShapes lazy = contact::build_collision_shapes(floes),
                           kept = contact::build_collision_shapes(floes, eager);
  check_same_parts(lazy, kept, floes.size());
  const std::size_t all = lazy.vertices.size(), square = 4;
  // Floe 1 (a square) let go: its dead vertices, below half the live ones,
  // the defaults leave; compact_dead 0 compacts, with the spare asked for.
  REQUIRE(2 * square <= all - square);
  std::vector<std::uint8_t> held(floes.size(), 1);
  held[1] = 0;
  lazy.hold(floes, held);
  kept.hold(floes, held);
  check_same_parts(lazy, kept, floes.size());
  CHECK(lazy.dead_vertices == square);
  CHECK(kept.dead_vertices == 0);
  const std::size_t live = all - square;
  CHECK(kept.vertices.size() == live);
  CHECK(kept.vertices.capacity() == 2 * live);
  // Floe 1 back (appended at the arrays' end): the defaults' arrays, shrunk
  // to fit at the build, have no room and compact first (a quarter spare);
  // the spare ones have room.
  held[1] = 1;
  lazy.hold(floes, held);
  kept.hold(floes, held);
  check_same_parts(lazy, kept, floes.size());
  CHECK(lazy.dead_vertices == 0);
  CHECK(lazy.vertices.capacity() == all + all / 4);
  CHECK(kept.vertices.capacity() == 2 * live);
  // forget() keeps the options.
  kept.forget(floes);
  CHECK(kept.options.compact_dead == 0.0);
  CHECK(kept.options.spare == 1.0);
}
