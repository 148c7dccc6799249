// The advance's shares with the run's warm store (docs/parallel.md, "The
// conflicting clusters on one rank (onerank26)"): each share runs on a copy
// of the store as it was at the step's start and sends the pairs it stored;
// every rank writes every part's pairs into its store. Played over 1, 2, 3
// and 7 strips (each share on its own copy of the floes, the parts through
// their bytes), step after step, the states, counts and the store itself
// must be the serial advance's bit for bit; and the fallbacks are counted
// by kind (AdvanceShareCounts::conflicts), with no warm_start left.
#include <doctest/doctest.h>

#include <cmath>
#include <cstring>
#include <memory>
#include <numeric>
#include <string>
#include <vector>

#include "contact/detection.hpp"
#include "contact/shapes.hpp"
#include "contact/substep.hpp"
#include "parallel/advance_share.hpp"
#include "parallel/place.hpp"
#include "tests/parallel/advance_case.hpp"
#include "tests/parallel/collide_case.hpp"

TEST_SUITE_BEGIN("mpi");

using namespace floesim;

namespace {

// The dense periodic pack of test_advance_share.cpp (tests/parallel/
// advance_case.hpp): many small clusters, some merging; every LCP starts
// from the warm store and stores its basis.
using Case = test::AdvanceCase;
using test::same_stats;
using test::same_store;
Case dense_pack(double speed, unsigned seed, double concentration) {
  Case c = test::dense_advance_pack(speed, seed, concentration);
  c.options.impulse.warm_min = 0;
  return c;
}

// One step over `ranks` ranks, as parallel::advance_by_owner makes it: the
// shares set up on copies of the floes, the rooms and parts through their
// bytes, combined into `f` and `warm`, or, on a conflict (counted by kind
// in `counts`), the whole advance from the step's start with `warm`.
// Returns whether the parts combined; `stored` adds the pairs the parts
// stored.
bool play(const Case& c, std::span<const int> owner, int ranks, contact::WarmStart& warm, Floes& f,
          contact::CollisionStats& stats, contact::SubstepReport& report, parallel::AdvanceShareCounts& counts,
          long& stored) {
  contact::SubstepOptions o = c.options;
  o.impulse.warm = &warm;
  std::vector<Floes> copies(static_cast<std::size_t>(ranks), c.floes);
  std::vector<std::unique_ptr<contact::ShareAdvance>> shares;
  std::vector<contact::ShareRooms> rooms;
  for (int r = 0; r < ranks; ++r) {
    shares.push_back(std::make_unique<contact::ShareAdvance>(copies[static_cast<std::size_t>(r)], c.shapes,
                                                             c.detection, c.dt, o, contact::ClusterShare{owner, r}));
    rooms.push_back(parallel::unpack_share_rooms(parallel::pack(shares.back()->rooms())));
  }
  contact::ShareRooms all;
  REQUIRE(parallel::combine_rooms(rooms, all));
  std::vector<parallel::AdvancePart> parts;
  for (int r = 0; r < ranks; ++r) {
    const std::size_t k = static_cast<std::size_t>(r);
    parts.push_back(parallel::unpack_advance_part(parallel::pack(parallel::finish_share(*shares[k], all, copies[k]))));
  }
  f = std::move(copies.front());
  if (parallel::combine_parts(parts, f, stats, report, nullptr, &warm)) {
    for (const parallel::AdvancePart& p : parts) stored += static_cast<long>(p.outcome.warm.size());
    return true;
  }
  parallel::count_conflicts(parts, counts);
  f = c.floes;
  stats = {};
  report = {};
  contact::advance_with_collisions(f, c.shapes, c.detection, c.dt, o, stats, report);
  return false;
}

}  // namespace

TEST_CASE("the advance's shares on copies of the warm store, their stored pairs written on every rank, keep the "
          "serial store and answer") {
  // Four steps from the same start, the store carried from each to the next
  // (its entries are those of the step before: warm starts that hit); the
  // serial advance and each split keep a store of their own.
  long combined = 0, stored = 0, tries = 0;
  for (const unsigned seed : {3u, 11u}) {
    CAPTURE(seed);
    const Case c = dense_pack(2.0, seed, 0.5);
    for (const int ranks : {1, 2, 3, 7}) {
      CAPTURE(ranks);
      parallel::FloeOwners owners(0, ranks, c.domain);
      owners.assign(c.floes);
      contact::WarmStart serial_warm, shared_warm;
      parallel::AdvanceShareCounts counts;
      for (int step = 0; step < 4; ++step) {
        CAPTURE(step);
        Floes s = c.floes, f;
        contact::SubstepOptions so = c.options;
        so.impulse.warm = &serial_warm;
        contact::CollisionStats ss, fs;
        contact::SubstepReport sr, fr;
        contact::advance_with_collisions(s, c.shapes, c.detection, c.dt, so, ss, sr);
        long kept = 0;
        const bool ok = play(c, owners.owner(), ranks, shared_warm, f, fs, fr, counts, kept);
        if (ranks == 1) CHECK(ok);
        if (ranks > 1) {  // the splits: one rank's share is the serial advance itself
          ++tries;
          combined += ok ? 1 : 0;
          stored += kept;
        }
        CHECK(std::memcmp(f.state.data(), s.state.data(), f.state.size() * sizeof(FloeState)) == 0);
        CHECK(same_stats(fs, ss));
        CHECK(ss.lcps > 0);
        CHECK(same_store(shared_warm, serial_warm));
        serial_warm.tick();
        shared_warm.tick();
      }
      CHECK(serial_warm.uses > 0);
      // No share's fallback is for the warm store any more.
      CHECK_FALSE(counts.conflicts.contains("warm_start"));
    }
  }
  MESSAGE(combined << " of " << tries << " tries over several ranks combined, " << stored
                   << " warm pairs stored by their shares");
  // A share's use of the store is no conflict: a third of the tries at least combine.
  CHECK(combined >= tries / 3);
  CHECK(stored > 0);
}

TEST_CASE("the advance's fallbacks are counted by kind: a cluster meeting another rank's, a floe two ranks took, a warm pair two parts stored") {
  // Every floe its own rank: every merge of the serial advance is between
  // ranks (foreign_cluster).
  {
    const Case c = dense_pack(2.0, 3, 0.5);
    std::vector<int> owner(c.floes.size());
    std::iota(owner.begin(), owner.end(), 0);
    contact::WarmStart warm;
    Floes f;
    contact::CollisionStats stats;
    contact::SubstepReport report;
    parallel::AdvanceShareCounts counts;
    long stored = 0;
    CHECK_FALSE(play(c, owner, static_cast<int>(owner.size()), warm, f, stats, report, counts, stored));
    CHECK(counts.conflicts.size() == 1);
    CHECK(counts.conflicts["foreign_cluster"] == 1);
  }
  // Two parts that moved one floe and have no conflict: taken_twice.
  {
    std::vector<parallel::AdvancePart> parts(2);
    parts[0].outcome.moved = {1, 4};
    parts[1].outcome.moved = {2, 4};
    parallel::AdvanceShareCounts counts;
    parallel::count_conflicts(parts, counts);
    CHECK(counts.conflicts.size() == 1);
    CHECK(counts.conflicts["taken_twice"] == 1);
    // A part with a conflict names it, each kind once per try.
    parts[0].outcome.conflict = contact::ShareOutcome::Conflict::missing_pairs;
    parts[1].outcome.conflict = contact::ShareOutcome::Conflict::missing_pairs;
    parallel::count_conflicts(parts, counts);
    CHECK(counts.conflicts["missing_pairs"] == 1);
    CHECK(counts.conflicts["taken_twice"] == 1);
  }
  // Two parts that stored one warm pair (and moved different floes): they
  // do not combine, the store and the states are left alone, and the try
  // counts as `stored_twice` (the rule combine_parts refuses by is the one
  // the count names: parallel/refusals.hpp).
  {
    std::vector<parallel::AdvancePart> parts(2);
    parts[0].outcome.moved = {0};
    parts[1].outcome.moved = {1};
    parts[0].states = {FloeState{}};
    parts[1].states = {FloeState{}};
    parts[0].states[0].x = 5.0;
    parts[1].states[0].x = 6.0;
    const std::uint64_t key = 7;
    parts[0].outcome.warm.emplace_back(key, contact::WarmStart::Pair{});
    parts[1].outcome.warm.emplace_back(key, contact::WarmStart::Pair{});
    Floes f;
    f.state.resize(2);
    f.thickness.resize(2, 1.0);
    contact::WarmStart warm;
    contact::CollisionStats stats;
    contact::SubstepReport report;
    CHECK_FALSE(parallel::combine_parts(parts, f, stats, report, nullptr, &warm));
    CHECK(warm.pairs.empty());
    CHECK(f.state[0].x == 0.0);
    CHECK(f.state[1].x == 0.0);
    parallel::AdvanceShareCounts counts;
    parallel::count_conflicts(parts, counts);
    CHECK(counts.conflicts.size() == 1);
    CHECK(counts.conflicts["stored_twice"] == 1);
    // One pair each: they combine, both states written, both pairs stored.
    parts[1].outcome.warm.front().first = key + 1;
    CHECK(parallel::combine_parts(parts, f, stats, report, nullptr, &warm));
    CHECK(f.state[0].x == 5.0);
    CHECK(f.state[1].x == 6.0);
    CHECK(warm.pairs.size() == 2);
  }
}

TEST_CASE("the back-off of the advance by owner: after fallbacks in a row, waits of 1, 2, 4 up to max_wait") {
  // Ten advances whose every try falls back: tried at advances 0, 2 and 5
  // (then waits of 1, 2 and 4, the cap), the rest whole.
  parallel::AdvanceShareCounts counts;
  parallel::AdvanceShareOptions o;
  o.max_wait = 4;
  std::vector<int> tried;
  for (int step = 0; step < 10; ++step)
    if (!counts.whole_now()) {
      tried.push_back(step);
      counts.fell_back(o);
    }
  CHECK(tried == std::vector<int>{0, 2, 5});
  CHECK(counts.steps == 3);
  CHECK(counts.fallbacks == 3);
  CHECK(counts.whole == 7);
  // A try that combines resets the next wait to 1.
  counts.combined();
  CHECK(counts.next_wait == 1);
}
