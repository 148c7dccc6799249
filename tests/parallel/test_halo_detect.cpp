// The halo band in the library and the detect phase's passes over the held
// floes (docs/parallel.md, "The state held by owner with a halo (plan)",
// "The band" and "The detect phase over the held floes"), on simulated
// ranks in one process:
//
// - parallel::held_floes, with H the simulated ranks' largest
//   largest_half_band (the run's one max reduction), is the band written
//   out from its definition (test::halo_band_by_rule) mask for mask, and H
//   is the pack's largest half band; H from the rank's own floes alone (no
//   reduction) gives other bands, which the comparison sees (they lose no
//   pair of the rank's part: counted, not asserted); the band of one pad
//   (no + h_j) is test_halo.cpp's named mutation;
// - parallel::detection_subset over the held floes reads only them: on a
//   copy in which every floe not held is a lure (moved into the rank's
//   strip, with a wide reach: a floe there would be posed) it gives the
//   subset of the whole state, and on a copy poisoned outside the held
//   floes (NaN) the rank's part of the detection; the named mutation: the
//   subset over every floe of the lured copy poses the lures. A NaN alone
//   does not show a pass over every floe (a band test with a NaN is
//   false, so a poisoned floe is never posed): hence the lure.
//
// - Moorings::kick over the floes a rank drifts (the drift's owners after
//   their update): its moored floes get the whole kick's bits, on a copy
//   poisoned outside them, and no other floe is written; the named
//   mutation: the kick over every floe writes the others.
//
// Strips: equal counts, uneven (an empty strip, a cut beyond the pack) and
// the sea's slabs (owners by grid row), on 2, 3 and 7 ranks, in a periodic
// box and the open plane, the pack moving at up to 0.5 and 2 m/s.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include "contact/detection.hpp"
#include "contact/shapes.hpp"
#include "core/floe.hpp"
#include "coupling/mooring.hpp"
#include "parallel/detect.hpp"
#include "parallel/place.hpp"
#include "tests/parallel/halo_case.hpp"
#include "tests/parallel/same_detection.hpp"

TEST_SUITE_BEGIN("mpi");

using namespace floesim;
using namespace floesim::test;

namespace {

// A copy in which every floe not held is a lure: its centroid at `y` (a
// place inside the rank's strip) and its reach `reach`, wide. A pass that
// read it would pose it.
struct Lured {
  Floes floes;
  contact::DetectionOptions detect;
};
Lured lured(const Pack& p, const Held& held, double y, double reach) {
  Lured out{p.floes, p.detect};
  for (std::size_t i = 0; i < held.size(); ++i) {
    if (held[i]) continue;
    out.floes.state[i].y = y;
    out.detect.reach[i] = reach;
  }
  return out;
}

bool same_subset(const contact::DetectionSubset& a, const contact::DetectionSubset& b) {
  return a.posed == b.posed && a.keep == b.keep;
}

}  // namespace

TEST_CASE("the held floes from the library are the band by its rule, H one max over the ranks' own floes") {
  std::size_t configs = 0, local_differs = 0, local_lost = 0, held_total = 0, local_total = 0;
  for_each_strip_case([&](const Pack& p, const StripCase& c) {
    const std::size_t n = p.floes.size();
    const int ranks = c.ranks;
    const std::string where = c.name();
    CAPTURE(where);
    const parallel::FloeOwners owners = owners_of(p, ranks, c.kind);
    // H: the simulated ranks' parts, their largest, is the pack's.
    double pack_largest = 0.0;
    for (std::size_t j = 0; j < n; ++j) pack_largest = std::max(pack_largest, parallel::half_band(owners, p.floes, p.shapes, p.detect, j));
    const double largest = largest_by_ranks(owners, p.floes, p.shapes, p.detect);
    CHECK(bits(largest, pack_largest));
    for (int r = 0; r < ranks; ++r) {
      CAPTURE(r);
      const parallel::HeldFloes held = parallel::held_floes(owners, r, p.floes, p.shapes, p.detect, largest);
      CHECK(bits(held.largest, largest));
      CHECK(held.mask == halo_band_by_rule(owners, r, p.floes, p.shapes, p.detect));
      // The index: the mask's floes, ascending; the rank's own among them.
      std::vector<std::uint32_t> from_mask;
      for (std::size_t i = 0; i < n; ++i)
        if (held.mask[i]) from_mask.push_back(static_cast<std::uint32_t>(i));
      CHECK(held.index == from_mask);
      bool own = true;
      for (std::size_t i = 0; i < n; ++i) own = own && (owners.owner()[i] != r || held.holds(i));
      CHECK(own);
      // H from this rank's own floes alone (no reduction): another
      // band, which the comparison with the rule sees.
      const double mine = parallel::largest_half_band(owners, r, p.floes, p.shapes, p.detect);
      const parallel::HeldFloes local = parallel::held_floes(owners, r, p.floes, p.shapes, p.detect, mine);
      held_total += held.index.size();
      local_total += local.index.size();
      if (local.mask != held.mask) {
        ++local_differs;
        contact::DetectionOptions d = p.detect;
        d.reach = poisoned(d.reach, local.mask);
        const contact::Detection thin = parallel::detect_part(owners, r, poisoned(p.floes, local.mask),
                                                              poisoned(p.shapes, local.mask), d);
        const contact::Detection whole = parallel::detect_part(owners, r, p.floes, p.shapes, p.detect);
        if (thin.pairs.size() < whole.pairs.size()) local_lost += whole.pairs.size() - thin.pairs.size();
      }
      ++configs;
    }
  });
  // It is thinner and loses no pair: the rank's part needs h_a of its own
  // floes a only (dist(y_b, S_r) <= h_a + h_b). The run keeps the one H of
  // the plan (docs/parallel.md, "The band in the library").
  MESSAGE("H from the rank's own floes alone: " << local_differs << " of " << configs << " bands differ, "
                                                << local_lost << " pairs lost; floes held " << held_total
                                                << " with the pack's H, " << local_total << " with the rank's own");
  CHECK(local_differs > 0);
}

TEST_CASE("the detection subset over the held floes reads only them (lured and poisoned copies)") {
  std::size_t parts = 0, lures_posed = 0, lured_parts = 0, held_total = 0, whole_total = 0;
  for_each_strip_case([&](const Pack& p, const StripCase& c) {
    const std::size_t n = p.floes.size();
    const int ranks = c.ranks;
    const std::string where = c.name();
    CAPTURE(where);
    const parallel::FloeOwners owners = owners_of(p, ranks, c.kind);
    const double largest = largest_by_ranks(owners, p.floes, p.shapes, p.detect);
    for (int r = 0; r < ranks; ++r) {
      CAPTURE(r);
      const parallel::HeldFloes held = parallel::held_floes(owners, r, p.floes, p.shapes, p.detect, largest);
      const contact::DetectionSubset whole = parallel::detection_subset(owners, r, p.floes, p.shapes, p.detect);
      // Poisoned (NaN) outside the held floes: the same part of the detection.
      contact::DetectionOptions d = p.detect;
      d.reach = poisoned(d.reach, held.mask);
      const Floes nan_floes = poisoned(p.floes, held.mask);
      const contact::CollisionShapes nan_shapes = poisoned(p.shapes, held.mask);
      CHECK(same_subset(parallel::detection_subset(owners, r, nan_floes, nan_shapes, d, &held), whole));
      CHECK(same_detection(parallel::detect_part(owners, r, nan_floes, nan_shapes, d, &held),
                           parallel::detect_part(owners, r, p.floes, p.shapes, p.detect)));
      ++parts;
      held_total += held.index.size();
      whole_total += n;
      if (owners.owner().end() == std::find(owners.owner().begin(), owners.owner().end(), r)) continue;
      // Lured outside the held floes: the first own floe's place, a reach of 500 m.
      const std::size_t first =
          static_cast<std::size_t>(std::find(owners.owner().begin(), owners.owner().end(), r) - owners.owner().begin());
      const Lured l = lured(p, held.mask, owners.place(p.floes.state[first]), 500.0);
      CHECK(same_subset(parallel::detection_subset(owners, r, l.floes, p.shapes, l.detect, &held), whole));
      // The mutation, named: the subset over every floe poses the lures.
      const contact::DetectionSubset every = parallel::detection_subset(owners, r, l.floes, p.shapes, l.detect);
      ++lured_parts;
      if (every.posed.size() > whole.posed.size()) lures_posed += every.posed.size() - whole.posed.size();
      if (held.index.size() < n) CHECK(!same_subset(every, whole));  // some floe is a lure
    }
  });
  MESSAGE(parts << " parts from their held floes (" << held_total << " floes held of " << whole_total
                << "); a subset over every floe of the lured copies poses " << lures_posed << " lures in "
                << lured_parts << " parts");
  CHECK(lures_posed > 0);
}

TEST_CASE("the held floes hold the detection's floes when the sea's slabs own floes beyond the grid (open box)") {
  // Slabs on a grid from y = 0 to the window's height, the pack moved 150 m
  // down in an open box: the floes below y = 0 are owned by the rows they
  // wrap to (the last slab's), far from that slab in y. The band is taken
  // about the strip widened to the rank's own floes' places: each rank's
  // subset from every floe poses only floes it holds, and its part from a
  // copy poisoned outside them is its part from the whole state. Without
  // the widening (the band by the strip alone, test::halo_band_by_rule)
  // some posed floes are not held: counted and asserted.
  std::size_t beyond = 0, missed_by_strip = 0;
  for (const double speed : {0.5, 2.0}) {
    Pack p = moving_pack(7, false, speed);
    for (FloeState& s : p.floes.state) s.y -= 150.0;
    const std::size_t n = p.floes.size();
    for (std::size_t i = 0; i < n; ++i) beyond += p.floes.state[i].y < 0.0;
    for (const int ranks : {2, 3, 7}) {
      CAPTURE(speed);
      CAPTURE(ranks);
      const parallel::FloeOwners owners = owners_of(p, ranks, Strips::beyond);
      const double largest = largest_by_ranks(owners, p.floes, p.shapes, p.detect);
      for (int r = 0; r < ranks; ++r) {
        CAPTURE(r);
        const parallel::HeldFloes held = parallel::held_floes(owners, r, p.floes, p.shapes, p.detect, largest);
        const contact::DetectionSubset every = parallel::detection_subset(owners, r, p.floes, p.shapes, p.detect);
        CHECK(std::all_of(every.posed.begin(), every.posed.end(), [&](std::uint32_t i) { return held.holds(i); }));
        const Held by_strip = halo_band_by_rule(owners, r, p.floes, p.shapes, p.detect);
        for (const std::uint32_t i : every.posed) missed_by_strip += by_strip[i] ? 0 : 1;
        contact::DetectionOptions d = p.detect;
        d.reach = poisoned(d.reach, held.mask);
        CHECK(same_detection(parallel::detect_part(owners, r, poisoned(p.floes, held.mask), poisoned(p.shapes, held.mask), d, &held),
                             parallel::detect_part(owners, r, p.floes, p.shapes, p.detect)));
      }
    }
  }
  MESSAGE(beyond << " floes below the grid (two packs); the band about the strip alone misses " << missed_by_strip
                 << " posed floes (2, 3, 7 slabs)");
  CHECK(beyond > 0);
  CHECK(missed_by_strip > 0);
}

TEST_CASE("the moorings' kick over the floes a rank drifts reads and writes only those") {
  // A third of the pack moored (period 300 s, damping 0.2) where it
  // starts, then moved 40 m off its anchors and given its velocities: the
  // kick over each rank's floes, on a copy whose other floes are NaN, gives
  // its moored floes the bits of the kick over every floe, and leaves every
  // other floe as it was (a lure copy: finite values that a kick would change).
  const Pack p = moving_pack(5, true);
  const std::size_t n = p.floes.size();
  std::vector<FloeInput> inputs(n);
  for (std::size_t i = 0; i < n; i += 3) {
    inputs[i].mooring_period = 300.0;
    inputs[i].mooring_damping = 0.2;
  }
  const Moorings moorings(p.floes, inputs);
  Floes moved = p.floes;
  for (FloeState& s : moved.state) {
    s.x += 40.0;
    s.y -= 25.0;
  }
  const double dt = 10.0;
  Floes serial = moved;
  moorings.kick(serial, dt);
  std::size_t kicked = 0;
  for (std::size_t i = 0; i < n; ++i) kicked += std::memcmp(&serial.state[i], &moved.state[i], sizeof(FloeState)) != 0;
  REQUIRE(kicked > 100);
  std::size_t others_written_by_every = 0;
  for (const int ranks : {2, 3, 7})
    for (const Strips kind : {Strips::equal, Strips::uneven, Strips::slabs}) {
      CAPTURE(ranks);
      CAPTURE(strips_name(kind));
      Pack at = p;
      at.floes = moved;
      const parallel::FloeOwners owners = owners_of(at, ranks, kind);
      for (int r = 0; r < ranks; ++r) {
        CAPTURE(r);
        Held mine(n, 0);
        std::vector<std::uint32_t> list;
        for (std::size_t i = 0; i < n; ++i)
          if (owners.owner()[i] == r) {
            mine[i] = 1;
            list.push_back(static_cast<std::uint32_t>(i));
          }
        Floes poisoned_copy = poisoned(moved, mine);
        moorings.kick(poisoned_copy, dt, list);
        Floes lure = moved;
        moorings.kick(lure, dt, list);
        Floes every = moved;  // the mutation: the kick over every floe
        moorings.kick(every, dt);
        bool own = true, others = true;
        for (std::size_t i = 0; i < n; ++i) {
          if (mine[i]) {
            own = own && std::memcmp(&poisoned_copy.state[i], &serial.state[i], sizeof(FloeState)) == 0;
          } else {
            others = others && std::memcmp(&lure.state[i], &moved.state[i], sizeof(FloeState)) == 0;
            others_written_by_every += std::memcmp(&every.state[i], &moved.state[i], sizeof(FloeState)) != 0;
          }
        }
        CHECK(own);
        CHECK(others);
      }
    }
  MESSAGE(kicked << " moored floes of " << n << "; the kick over every floe writes " << others_written_by_every
                 << " floes that ranks do not drift (over 2, 3, 7 ranks and three kinds of strips)");
  CHECK(others_written_by_every > 0);
}

TEST_SUITE_END();
