// Stage seven without ranks: the collisions at the step's start split by
// owner (contact::resolve_step_collisions_share) over 1, 2, 3 and 7 strips,
// and with every floe its own rank, each share run on its own copy of the
// floes as each rank runs it, packed, unpacked and combined as
// parallel::collide_by_owner combines the gathered parts, are the serial
// solve (contact::resolve_step_collisions) bit for bit: the floes' states
// (memcmp), the collision counts and the speculative contacts' count. A
// speculative contact that joins two ranks' contact components puts both in
// one step group, on one rank. Shares that use the warm store run on copies
// of it and their stored pairs, written into every rank's store, keep it the
// serial store over several steps; under the test hook
// (CollideShareOptions::warm_conflict) they fall back to the serial solve,
// with the advance's back-off. In a run that keeps the impulse record, the
// shares' records merged are the serial record.
#include <doctest/doctest.h>

#include <algorithm>
#include <cstring>
#include <random>
#include <numeric>
#include <map>
#include <string>

#include "core/pack_generator.hpp"
#include "parallel/collide_share.hpp"
#include "parallel/place.hpp"
#include "tests/parallel/collide_case.hpp"

TEST_SUITE_BEGIN("mpi");

using namespace floesim;
using test::CollideCase;
using test::same_record;
using test::same_states;
using test::same_stats;

namespace {

struct Serial {
  std::vector<FloeState> state;
  contact::CollisionStats stats;
  std::size_t speculative = 0;
};
Serial serial_solve(const CollideCase& c) {
  Floes f = c.floes;
  Serial s;
  s.speculative = contact::resolve_step_collisions(f, c.start, c.detection, c.dt, c.options, s.stats);
  s.state = f.state;
  return s;
}

// Plays `ranks` ranks: each runs its share on its own copy, the parts go
// through pack/unpack, and rank 0's copy combines them. Returns whether they
// combined; `f`, `stats` and `speculative` hold the combined answer, or,
// when not, the whole solve redone (the fallback). `groups`: each rank's.
// With `merged`, the shares record their impulses (each into its part's own
// record, not the options' one, which stays empty), their parts' records
// are merged into `merged` (a record the step's earlier solves began), or
// the fallback records into it; `loads` gets each rank's count of loads.
bool play(const CollideCase& c, std::span<const int> owner, int ranks, Floes& f, contact::CollisionStats& stats,
          std::size_t& speculative, std::vector<long>& groups, contact::ImpulseRecord* merged = nullptr,
          std::vector<std::size_t>* loads = nullptr) {
  std::vector<parallel::CollidePart> parts;
  contact::ImpulseRecord unused;
  contact::ImpulseOptions o = c.options;
  if (merged) o.record = &unused;
  Floes first;
  for (int r = 0; r < ranks; ++r) {
    Floes mine = c.floes;
    const parallel::CollidePart part = parallel::run_collide_share(mine, c.start, c.detection, c.dt, o, owner, r);
    parts.push_back(parallel::unpack_collide_part(parallel::pack(part)));
    REQUIRE(parts.back().outcome.moved == part.outcome.moved);  // the bytes carry the part
    REQUIRE(parts.back().states.size() == part.states.size());
    groups.push_back(part.outcome.groups);
    if (merged) {
      REQUIRE(part.outcome.places.size() == part.record.loads.size());
      loads->push_back(part.record.loads.size());
    }
    if (r == 0) first = std::move(mine);
  }
  CHECK(unused.loads.empty());
  CHECK(unused.events == 0);
  f = std::move(first);
  if (parallel::combine_collide_parts(parts, f, stats, speculative, merged)) return true;
  f.state = c.floes.state;
  contact::ImpulseOptions whole = c.options;
  if (merged) whole.record = merged;
  speculative = contact::resolve_step_collisions(f, c.start, c.detection, c.dt, whole, stats);
  return false;
}

// The owners of the case's floes over `ranks` equal strips, or with 0
// every floe its own rank (every row then spans four ranks); `n` gets the
// number of ranks.
std::vector<int> owners_of(const CollideCase& c, int ranks, int& n) {
  n = ranks;
  if (ranks > 0) {
    parallel::FloeOwners owners(0, ranks, c.domain);
    owners.assign(c.floes);
    return {owners.owner().begin(), owners.owner().end()};
  }
  std::vector<int> owner(c.floes.size());
  std::iota(owner.begin(), owner.end(), 0);
  n = static_cast<int>(owner.size());
  return owner;
}

}  // namespace

TEST_CASE("the step-start collisions by owner over 1, 2, 3 and 7 strips, and by floe, are the serial solve") {
  for (const unsigned seed : {3u, 11u}) {
    CAPTURE(seed);
    const CollideCase c = test::rows_of_four(seed);
    const Serial serial = serial_solve(c);
    MESSAGE("serial: " << c.detection.contacts.size() << " contact points, " << serial.stats.lcps << " LCPs, "
                       << serial.speculative << " speculative contacts");
    REQUIRE(serial.stats.lcps > 64);         // every row's two components, and again joined
    REQUIRE(serial.speculative >= 64);       // a speculative contact in every row
    for (const int ranks : {1, 2, 3, 7, 0}) {
      CAPTURE(ranks);
      int n = ranks;
      const std::vector<int> owner = owners_of(c, ranks, n);
      Floes f;
      contact::CollisionStats stats;
      std::size_t speculative = 0;
      std::vector<long> groups;
      CHECK(play(c, owner, n, f, stats, speculative, groups));  // no warm store: nothing to conflict
      CHECK(same_states(f.state, serial.state));
      CHECK(same_stats(stats, serial.stats));
      CHECK(speculative == serial.speculative);
      // One group a row (its two components joined by the witness), each on one rank.
      CHECK(std::accumulate(groups.begin(), groups.end(), 0L) == 64);
      if (n > 1) CHECK(std::count_if(groups.begin(), groups.end(), [](long g) { return g > 0; }) >= 2);
    }
  }
}

TEST_CASE("a dense pack is one step group, solved by one rank") {
  // 400 floes at 90 % cover moving at up to 0.5 m/s, xi the distance of the
  // nearest tenth of the pairs: witnesses link every contact component to
  // the next, so the step group is the pack; the shares still combine to
  // the serial solve (all of it on one rank).
  PackOptions o;
  o.floes = 400;
  o.concentration = 0.9;
  o.width = o.height = 2000.0;
  o.seed = 3;
  GeneratedPack g = generate_pack(o);
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-0.5, 0.5);
  CollideCase c;
  c.floes = std::move(g.floes);
  for (FloeState& s : c.floes.state) {
    s.vx = u(rng);
    s.vy = u(rng);
  }
  c.start = c.floes.state;
  for (FloeState& s : c.start) s.vx *= 0.6;
  const contact::CollisionShapes shapes = contact::build_collision_shapes(c.floes);
  c.domain = {true, g.window[0], g.window[1], g.window[2], g.window[3]};
  contact::DetectionOptions d;
  d.domain = c.domain;
  d.horizon = c.dt;
  d.reach.assign(c.floes.size(), 10.0);
  std::vector<double> gaps;
  for (const contact::NearPair& p : contact::detect(c.floes, shapes, d).pairs) gaps.push_back(p.distance);
  std::sort(gaps.begin(), gaps.end());
  d.collision_distance = gaps[gaps.size() / 10];
  c.detection = contact::detect(c.floes, shapes, d);
  c.options.collision_distance = d.collision_distance;
  const Serial serial = serial_solve(c);
  REQUIRE(serial.stats.lcps > 20);
  REQUIRE(serial.speculative > 0);
  parallel::FloeOwners owners(0, 3, c.domain);
  owners.assign(c.floes);
  Floes f;
  contact::CollisionStats stats;
  std::size_t speculative = 0;
  std::vector<long> groups;
  CHECK(play(c, owners.owner(), 3, f, stats, speculative, groups));
  CHECK(std::accumulate(groups.begin(), groups.end(), 0L) == 1);
  CHECK(same_states(f.state, serial.state));
  CHECK(same_stats(stats, serial.stats));
  CHECK(speculative == serial.speculative);
}

TEST_CASE("a speculative contact between two ranks' contact components puts both on one rank") {
  // In a row along x, 10 m squares: floe 0 (1 m/s) touches floe 1 (0.1 m/s)
  // 5 mm ahead of it, floe 3 (-1 m/s) touches floe 2 (-0.1 m/s) from the
  // other side; floes 1 and 2 are 0.5 m apart, a witness. Components {0, 1}
  // (rank 0) and {2, 3} (rank 1); the collisions throw 1 and 2 at each other,
  // a speculative contact that joins them, solved again together from W^-.
  // A share that solved its component and tested the witness with the other
  // rank's stale velocities would part from the serial answer; the step
  // group {0, 1, 2, 3} is rank 0's alone.
  auto box = [](double x0, double vx) {
    FloeInput f;
    f.vertices = {{x0, 0.0}, {x0 + 10.0, 0.0}, {x0 + 10.0, 10.0}, {x0, 10.0}};
    f.velocity = {vx, 0.0};
    return f;
  };
  CollideCase c;
  for (const FloeInput& in : {box(0.0, 1.0), box(10.005, 0.1), box(20.505, -0.1), box(30.51, -1.0)})
    c.floes.add(make_floe_shape(in), in);
  c.start = c.floes.state;
  contact::DetectionOptions d;
  d.horizon = c.dt;
  d.reach.assign(c.floes.size(), 6.0);
  c.detection = contact::detect(c.floes, contact::build_collision_shapes(c.floes), d);
  REQUIRE(c.detection.contacts.size() >= 2);
  const Serial serial = serial_solve(c);
  REQUIRE(serial.speculative > 0);
  const std::vector<int> owner{0, 0, 1, 1};
  Floes f;
  contact::CollisionStats stats;
  std::size_t speculative = 0;
  std::vector<long> groups;
  CHECK(play(c, owner, 2, f, stats, speculative, groups));
  CHECK(groups == std::vector<long>{1, 0});
  CHECK(same_states(f.state, serial.state));
  CHECK(same_stats(stats, serial.stats));
  CHECK(speculative == serial.speculative);
}

TEST_CASE("under the test hook, step-start shares that use the warm store fall back, with the advance's back-off") {
  // One rank (the serial communicator) owning every floe; every LCP starts
  // from the warm store (warm_min = 0), which the hook
  // (CollideShareOptions::warm_conflict) makes a conflict: each try falls
  // back, then waits 1, 2, 4 steps (AdvanceShareOptions), every step equal
  // to the serial solve with its own warm store.
  CollideCase c = test::rows_of_four(3);
  c.options.warm_min = 0;
  contact::WarmStart serial_warm, shared_warm;
  const parallel::Communicator comm;
  const std::vector<int> owner(c.floes.size(), 0);
  parallel::AdvanceShareCounts counts;
  parallel::CollideShareOptions share;
  share.back_off.max_wait = 4;
  share.warm_conflict = true;
  for (int step = 0; step < 10; ++step) {
    CAPTURE(step);
    Floes s = c.floes, f = c.floes;
    contact::ImpulseOptions so = c.options, fo = c.options;
    so.warm = &serial_warm;
    fo.warm = &shared_warm;
    contact::CollisionStats ss, fs;
    const std::size_t a = contact::resolve_step_collisions(s, c.start, c.detection, c.dt, so, ss);
    const std::size_t b = parallel::collide_by_owner(comm, owner, f, c.start, c.detection, c.dt, fo, fs, counts, share);
    CHECK(same_states(f.state, s.state));
    CHECK(same_stats(fs, ss));
    CHECK(a == b);
    CHECK(test::same_store(shared_warm, serial_warm));
  }
  CHECK(counts.steps == 3);  // tried at steps 0, 2 and 5
  CHECK(counts.fallbacks == 3);
  CHECK(counts.whole == 7);
  CHECK(counts.conflicts == std::map<std::string, long>{{"warm_start", 3}});
  CHECK(serial_warm.uses > 0);
}

namespace {

// The rows of four with W^- and the step's start scaled by `scale`: the same
// contacts and witnesses (positions), other velocities, so that the store
// one step leaves is matched and read by the next (warm starts that hit).
CollideCase scaled(const CollideCase& c, double scale) {
  CollideCase out = c;
  for (std::vector<FloeState>* v : {&out.floes.state, &out.start})
    for (FloeState& x : *v) {
      x.vx *= scale;
      x.vy *= scale;
      x.yaw_rate *= scale;
    }
  return out;
}

// Plays `ranks` ranks with the run's warm store `warm` (each share on its
// copy of it, as each rank's share runs), the parts through their bytes,
// combined into `f`, `stats` and, with `write`, `warm`. Returns whether they
// combined; `uses` gets each part's solves from the store and `stored` adds
// the pairs the parts stored.
bool play_warm(const CollideCase& c, std::span<const int> owner, int ranks, contact::WarmStart& warm, bool write,
               const parallel::CollideShareOptions& share, Floes& f, contact::CollisionStats& stats,
               std::size_t& speculative, std::vector<long>& uses, long& stored) {
  contact::ImpulseOptions o = c.options;
  o.warm = &warm;
  const contact::WarmStart before = warm;
  std::vector<parallel::CollidePart> parts;
  for (int r = 0; r < ranks; ++r) {
    Floes mine = c.floes;
    parts.push_back(parallel::unpack_collide_part(
        parallel::pack(parallel::run_collide_share(mine, c.start, c.detection, c.dt, o, owner, r, nullptr, share))));
    uses.push_back(parts.back().outcome.warm_uses);
    stored += static_cast<long>(parts.back().outcome.warm.size());
    if (r == 0) f = std::move(mine);
  }
  CHECK(test::same_store(warm, before));  // the shares ran on copies
  return parallel::combine_collide_parts(parts, f, stats, speculative, nullptr, write ? &warm : nullptr);
}

}  // namespace

TEST_CASE("step-start shares on copies of the warm store, their stored pairs written on every rank, keep the serial "
          "store and answer over several steps") {
  // Four steps over 1, 2, 3 and 7 strips, every LCP from the warm store
  // (warm_min = 0), the store carried from each step to the next (its
  // entries are those of the step before: warm starts that hit). The serial
  // solve and each split keep a store of their own. Under the test hook
  // each multi-rank try falls back (warm_start).
  long tries = 0, combined = 0, stored = 0;
  for (const unsigned seed : {3u, 11u}) {
    CAPTURE(seed);
    CollideCase base = test::rows_of_four(seed);
    base.options.warm_min = 0;
    for (const int ranks : {1, 2, 3, 7}) {
      CAPTURE(ranks);
      int n = ranks;
      const std::vector<int> owner = owners_of(base, ranks, n);
      contact::WarmStart serial_warm, shared_warm, unwritten;
      for (int step = 0; step < 4; ++step) {
        CAPTURE(step);
        const CollideCase c = scaled(base, 1.0 + 0.25 * step);
        Floes s = c.floes;
        contact::ImpulseOptions so = c.options;
        so.warm = &serial_warm;
        contact::CollisionStats ss;
        const std::size_t a = contact::resolve_step_collisions(s, c.start, c.detection, c.dt, so, ss);
        if (step > 0) CHECK(ss.warm > 0);  // the last step's entries were read
        Floes f;
        contact::CollisionStats fs;
        std::size_t b = 0;
        std::vector<long> uses;
        const bool ok = play_warm(c, owner, n, shared_warm, true, {}, f, fs, b, uses, stored);
        CHECK(ok);
        CHECK(same_states(f.state, s.state));
        CHECK(same_stats(fs, ss));
        CHECK(a == b);
        CHECK(test::same_store(shared_warm, serial_warm));
        if (n > 1) {
          ++tries;
          combined += ok ? 1 : 0;
          // Several parts solved from the store: each a warm_start conflict under the hook.
          CHECK(std::count_if(uses.begin(), uses.end(), [](long u) { return u > 0; }) >= 2);
          Floes g;
          contact::CollisionStats gs;
          std::size_t gb = 0;
          std::vector<long> hook_uses;
          long hook_stored = 0;
          contact::WarmStart hooked = serial_warm;
          parallel::CollideShareOptions hook;
          hook.warm_conflict = true;
          CHECK_FALSE(play_warm(c, owner, n, hooked, true, hook, g, gs, gb, hook_uses, hook_stored));
          CHECK(hook_stored == 0);
        }
        // Without the parts' pairs written (the store stays empty) the
        // next steps' solves start cold: their counts part from the serial
        // ones (what the store's equality above guards).
        Floes h;
        contact::CollisionStats hs;
        std::size_t hb = 0;
        std::vector<long> unused_uses;
        long unused_stored = 0;
        CHECK(play_warm(c, owner, n, unwritten, false, {}, h, hs, hb, unused_uses, unused_stored));
        if (step > 0) CHECK_FALSE(same_stats(hs, ss));
        serial_warm.tick();
        shared_warm.tick();
        unwritten.tick();
      }
      CHECK(serial_warm.uses > 0);
      CHECK_FALSE(test::same_store(unwritten, serial_warm));
    }
  }
  MESSAGE(combined << " of " << tries << " tries over several ranks combined, " << stored
                   << " warm pairs stored by their shares");
  CHECK(tries == 2 * 3 * 4);
  CHECK(stored > 0);
}

TEST_CASE("two parts that stored one warm pair do not combine, and the store is left alone") {
  // Never expected (a pair's solves are one group's, so one share's), and
  // refused all the same: the whole solve then writes the store.
  CollideCase c = test::rows_of_four(3);
  c.options.warm_min = 0;
  contact::WarmStart warm;
  contact::ImpulseOptions o = c.options;
  o.warm = &warm;
  const std::vector<int> owner(c.floes.size(), 0);
  Floes mine = c.floes;
  const parallel::CollidePart part = parallel::run_collide_share(mine, c.start, c.detection, c.dt, o, owner, 0);
  REQUIRE_FALSE(part.outcome.warm.empty());
  parallel::CollidePart other;  // another part that stored the first part's first pair and moved nothing
  other.outcome.warm = {part.outcome.warm.front()};
  Floes f = c.floes;
  contact::CollisionStats stats;
  std::size_t speculative = 0;
  const std::vector<parallel::CollidePart> parts{part, other};
  CHECK_FALSE(parallel::combine_collide_parts(parts, f, stats, speculative, nullptr, &warm));
  CHECK(warm.pairs.empty());
  CHECK(same_states(f.state, c.floes.state));
  // Each part alone combines and writes its pairs.
  CHECK(parallel::combine_collide_parts(std::span(parts).first(1), f, stats, speculative, nullptr, &warm));
  CHECK(warm.pairs.size() == part.outcome.warm.size());
}

namespace {

contact::ImpulseRecord begun() {
  contact::ImpulseRecord r;
  r.events = 3;
  return r;
}

}  // namespace

TEST_CASE("the step-start collisions' impulse records by owner merge into the serial record") {
  // The rows of four (jams off) over 2, 3 and 7 strips and by floe, and the
  // same rows as jams of two floes solved at the step's start (jam.floes 2,
  // at_step_start: a jam's speculative points, segment 1 of the places):
  // every rank's loads, merged, are the serial record's, in its order, as
  // one event numbered after the record's earlier ones.
  for (const bool jams : {false, true}) {
    CAPTURE(jams);
    const test::RecordedRows r = test::recorded_rows_of_four(jams);
    const CollideCase& c = r.c;
    const contact::ImpulseRecord& serial = r.record;
    MESSAGE("serial record: " << serial.loads.size() << " loads, " << serial.events << " events");
    REQUIRE(serial.events == 4);
    REQUIRE(serial.loads.size() > 100);
    for (const int ranks : {1, 2, 3, 7, 0}) {
      CAPTURE(ranks);
      int n = ranks;
      const std::vector<int> owner = owners_of(c, ranks, n);
      contact::ImpulseRecord merged = begun();
      std::vector<std::size_t> loads;
      Floes f;
      contact::CollisionStats stats;
      std::size_t speculative = 0;
      std::vector<long> groups;
      REQUIRE(play(c, owner, n, f, stats, speculative, groups, &merged, &loads));
      CHECK(same_record(merged, serial));
      // The loads came from several ranks (the merge had work to do).
      if (n > 1) CHECK(std::count_if(loads.begin(), loads.end(), [](std::size_t l) { return l > 0; }) >= 2);
    }
  }
}

TEST_CASE("merge_step_record orders the loads by their contacts' places, not by rank") {
  // Two simulated shares whose loads interleave in the serial list (places
  // as segment, pair (a, b, shift), index): rank 0 has (0, (1, 2), 1) and
  // (2, (0, 3), 5), rank 1 (0, (1, 2), 0) with two loads (a's and b's) and
  // (1, (1, 2, shift -100 m), 2). The merge: (0, (1, 2), 0) twice,
  // (0, (1, 2), 1), (1, ...), (2, ...), all event 7, and the count 8.
  auto load = [](std::uint32_t floe) {
    contact::ImpulseRecord::Load l;
    l.floe = floe;
    l.event = 0;
    return l;
  };
  contact::ImpulseRecord a, b;
  a.loads = {load(10), load(11)};
  a.events = 1;
  const std::vector<contact::ContactPlace> a_places{{0, 1, 2, 0.0, 0.0, 1}, {2, 0, 3, 0.0, 0.0, 5}};
  b.loads = {load(20), load(21), load(22)};
  b.events = 1;
  const std::vector<contact::ContactPlace> b_places{
      {0, 1, 2, 0.0, 0.0, 0}, {0, 1, 2, 0.0, 0.0, 0}, {1, 1, 2, -100.0, 0.0, 2}};
  contact::ImpulseRecord into;
  into.events = 7;
  const std::vector<contact::RecordPart> parts{{&a, a_places, {}}, {&b, b_places, {}}};
  contact::merge_step_record(into, parts);
  std::vector<std::uint32_t> floes;
  for (const auto& l : into.loads) {
    floes.push_back(l.floe);
    CHECK(l.event == 7);
  }
  CHECK(floes == std::vector<std::uint32_t>{20, 21, 10, 22, 11});
  CHECK(into.events == 8);
}
