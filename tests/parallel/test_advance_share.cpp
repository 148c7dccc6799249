// Stage seven without ranks: the multirate advance split by cluster owner
// over 1, 2, 3 and 7 "ranks" (each share run on its own copy of the floes,
// as each rank runs it), combined as parallel::advance_by_owner combines the
// gathered parts, is the serial advance (contact::advance_with_collisions)
// bit for bit: the floes' states (memcmp), the collision counts and the
// sub-step report. Where the shares interact (a cluster of one merges with a
// cluster of another, or two take one free floe) the combination refuses and
// the step is redone whole, which is the serial advance. In a run that keeps
// the impulse record, the shares' records merged are the serial record.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <numeric>
#include <random>
#include <string>

#include "contact/detection.hpp"
#include "contact/shapes.hpp"
#include "contact/substep.hpp"
#include "core/error.hpp"
#include "core/pack_generator.hpp"
#include "parallel/advance_share.hpp"
#include "parallel/detect.hpp"
#include "parallel/place.hpp"
#include "tests/parallel/advance_case.hpp"
#include "tests/parallel/collide_case.hpp"
#include "tests/parallel/halo_case.hpp"

TEST_SUITE_BEGIN("mpi");

using namespace floesim;

namespace {

// The cases (tests/parallel/advance_case.hpp).
using Case = test::AdvanceCase;
using test::same_stats;
Case dense_pack(double speed, unsigned seed, double concentration = 0.75) {
  return test::dense_advance_pack(speed, seed, concentration);
}

bool same_report(const contact::SubstepReport& a, const contact::SubstepReport& b) {
  return a.clusters == b.clusters && a.substeps == b.substeps && a.time_steps == b.time_steps &&
         a.largest_cluster == b.largest_cluster && a.joined == b.joined && a.merges == b.merges &&
         a.rejected == b.rejected && a.floor_steps == b.floor_steps && a.rebuilt == b.rebuilt &&
         a.reach_exceeded == b.reach_exceeded && a.floor_pair == b.floor_pair;
}

struct Serial {
  std::vector<FloeState> state;
  contact::CollisionStats stats;
  contact::SubstepReport report;
};
Serial serial_advance(const Case& c) {
  Floes f = c.floes;
  Serial s;
  contact::advance_with_collisions(f, c.shapes, c.detection, c.dt, c.options, s.stats, s.report);
  s.state = f.state;
  return s;
}

// Plays `ranks` ranks: each sets its share up on its own copy, the tight
// pairs and then the parts go through pack/unpack (the bytes every rank
// gathers), and rank 0's copy combines them. Returns whether they combined;
// `f` and the counts hold the combined answer, or, when not, the whole
// advance redone (the fallback). `outcomes` gets each share's outcome.
// With `merged`, each share records its solves into a record of its own,
// whose events are merged into `merged` (or the fallback records into it);
// `events` gets each share's event count.
bool play(const Case& c, std::span<const int> owner, int ranks, Floes& f, contact::CollisionStats& stats,
          contact::SubstepReport& report, std::vector<contact::ShareOutcome>& outcomes,
          contact::ImpulseRecord* merged = nullptr, std::vector<std::uint32_t>* events = nullptr) {
  std::vector<Floes> copies(static_cast<std::size_t>(ranks), c.floes);
  std::vector<contact::ImpulseRecord> own(static_cast<std::size_t>(ranks));
  std::vector<std::unique_ptr<contact::ShareAdvance>> shares;
  std::vector<contact::ShareRooms> rooms;
  for (int r = 0; r < ranks; ++r) {
    contact::SubstepOptions o = c.options;
    if (merged) o.impulse.record = &own[static_cast<std::size_t>(r)];
    shares.push_back(std::make_unique<contact::ShareAdvance>(copies[static_cast<std::size_t>(r)], c.shapes,
                                                             c.detection, c.dt, o, contact::ClusterShare{owner, r}));
    rooms.push_back(parallel::unpack_share_rooms(parallel::pack(shares.back()->rooms())));
  }
  contact::ShareRooms tight;
  bool ok = parallel::combine_rooms(rooms, tight);
  if (ok) {
    std::vector<parallel::AdvancePart> parts;
    for (int r = 0; r < ranks; ++r) {
      const std::size_t k = static_cast<std::size_t>(r);
      const parallel::AdvancePart part =
          parallel::finish_share(*shares[k], tight, copies[k], merged ? &own[k] : nullptr);
      outcomes.push_back(part.outcome);
      if (merged) {
        if (part.outcome.conflict == contact::ShareOutcome::Conflict::none)
          REQUIRE(part.outcome.events.size() == part.record.events);
        events->push_back(part.record.events);
      }
      parts.push_back(parallel::unpack_advance_part(parallel::pack(part)));
    }
    f = std::move(copies.front());
    ok = parallel::combine_parts(parts, f, stats, report, merged);
  }
  if (ok) return true;
  f = c.floes;
  contact::SubstepOptions whole = c.options;
  if (merged) whole.impulse.record = merged;
  contact::advance_with_collisions(f, c.shapes, c.detection, c.dt, whole, stats, report);
  return false;
}

std::vector<contact::ShareOutcome::Conflict> conflicts_of(const std::vector<contact::ShareOutcome>& outcomes) {
  std::vector<contact::ShareOutcome::Conflict> out;
  for (const contact::ShareOutcome& o : outcomes) out.push_back(o.conflict);
  return out;
}

// The set-up by share: one share computes every pair's room (the serial
// set-up); on several, each computes those of its own pairs and the few it
// reads besides (pads, its members' budgets and breaks), so each fewer than
// the whole, and together not much more than the whole (unless `pads`:
// every share computes the rooms of every jam-sized cluster's pairs).
void check_rooms(const std::vector<contact::ShareOutcome>& outcomes, int ranks, bool pads = false) {
  long sum = 0, most = 0;
  for (const contact::ShareOutcome& o : outcomes) {
    sum += o.rooms;
    most = std::max(most, o.rooms);
  }
  if (outcomes.empty()) return;
  const long pairs = outcomes.front().pairs;
  MESSAGE(ranks << " ranks: rooms computed " << sum << " (most by one rank " << most << ") of " << pairs << " pairs");
  REQUIRE(pairs > 0);
  if (ranks == 1) {
    CHECK(sum == pairs);
    return;
  }
  for (const contact::ShareOutcome& o : outcomes) {
    CHECK(o.pairs == pairs);
    CHECK(o.rooms < pairs);
  }
  if (pads) return;
  CHECK(static_cast<double>(most) < static_cast<double>(pairs) * (1.0 / ranks + 0.25));
  CHECK(static_cast<double>(sum) < 1.25 * static_cast<double>(pairs));
}

}  // namespace

TEST_CASE("the advance by cluster owner over 1, 2, 3 and 7 strips is the serial advance bit for bit") {
  int combined = 0;
  for (const unsigned seed : {3u, 11u}) {
    CAPTURE(seed);
    const Case c = dense_pack(2.0, seed, 0.5);
    const Serial serial = serial_advance(c);
    MESSAGE("serial: " << serial.report.clusters << " clusters, " << serial.report.substeps << " sub-steps, "
                       << serial.report.joined << " joined, " << serial.report.merges << " merges, "
                       << serial.stats.lcps << " LCPs");
    REQUIRE(serial.report.clusters > 20);  // many clusters to share
    REQUIRE(serial.stats.lcps > 0);
    for (const int ranks : {1, 2, 3, 7}) {
      CAPTURE(ranks);
      parallel::FloeOwners owners(0, ranks, c.domain);
      owners.assign(c.floes);
      Floes f;
      contact::CollisionStats stats;
      contact::SubstepReport report;
      std::vector<contact::ShareOutcome> outcomes;
      const bool ok = play(c, owners.owner(), ranks, f, stats, report, outcomes);
      MESSAGE(ranks << " ranks: " << std::string(ok ? "combined" : "fell back"));
      if (ranks > 1) combined += ok ? 1 : 0;
      if (ranks == 1) CHECK(ok);  // one rank owns every cluster: nothing to conflict with
      check_rooms(outcomes, ranks);
      REQUIRE(f.state.size() == serial.state.size());
      CHECK(std::memcmp(f.state.data(), serial.state.data(), f.state.size() * sizeof(FloeState)) == 0);
      CHECK(same_stats(stats, serial.stats));
      CHECK(same_report(report, serial.report));
    }
  }
  // Splits over several ranks that combined (a fallback is the serial
  // advance itself and proves nothing about the shares): 3 of the 6 here.
  CHECK(combined >= 2);
}

TEST_CASE("the pads of jam-sized clusters, whose rooms a share computes when it reads them, are the serial ones") {
  // jam.floes = 2: every cluster is "big" (2 floes or more) and its pad
  // (the dynamic floes whose room to it is below jam.pad xi = 10 m) joins
  // it at the step's start (make_clusters). The pads' rooms are mostly not
  // tight, so no share sent them: each share computes those it reads. The
  // clusters must be the serial ones on every share, and the answer too.
  int combined = 0;
  for (const unsigned seed : {3u, 11u}) {
    CAPTURE(seed);
    Case c = dense_pack(2.0, seed, 0.5);
    c.options.impulse.jam.floes = 2;
    const Serial serial = serial_advance(c);
    Case plain = c;
    plain.options.impulse.jam.pad = 0.0;  // no pads: the pads above must change the answer
    const Serial unpadded = serial_advance(plain);
    MESSAGE("serial: " << serial.report.clusters << " clusters, largest " << serial.report.largest_cluster
                       << " (without pads " << unpadded.report.largest_cluster << "), " << serial.report.time_steps
                       << " time steps");
    REQUIRE(serial.report.largest_cluster >= 2);
    REQUIRE(std::memcmp(serial.state.data(), unpadded.state.data(), serial.state.size() * sizeof(FloeState)) != 0);
    for (const int ranks : {2, 3}) {
      CAPTURE(ranks);
      parallel::FloeOwners owners(0, ranks, c.domain);
      owners.assign(c.floes);
      Floes f;
      contact::CollisionStats stats;
      contact::SubstepReport report;
      std::vector<contact::ShareOutcome> outcomes;
      const bool ok = play(c, owners.owner(), ranks, f, stats, report, outcomes);
      MESSAGE(ranks << " ranks: " << std::string(ok ? "combined" : "fell back"));
      combined += ok ? 1 : 0;
      check_rooms(outcomes, ranks, true);
      CHECK(std::memcmp(f.state.data(), serial.state.data(), f.state.size() * sizeof(FloeState)) == 0);
      CHECK(same_stats(stats, serial.stats));
      CHECK(same_report(report, serial.report));
    }
  }
  CHECK(combined >= 1);
}

TEST_CASE("clusters of different ranks that merge, or share a free floe, fall back to the serial advance") {
  // Every floe its own rank (owner[i] = i): each cluster is alone on its
  // rank, so every merge and every free floe taken by two clusters of the
  // serial advance is between ranks.
  const Case c = dense_pack(2.0, 3, 0.5);
  const Serial serial = serial_advance(c);
  REQUIRE(serial.report.merges + serial.report.joined > 0);
  std::vector<int> owner(c.floes.size());
  std::iota(owner.begin(), owner.end(), 0);
  Floes f;
  contact::CollisionStats stats;
  contact::SubstepReport report;
  std::vector<contact::ShareOutcome> outcomes;
  const bool ok = play(c, owner, static_cast<int>(owner.size()), f, stats, report, outcomes);
  const std::vector<contact::ShareOutcome::Conflict> conflicts = conflicts_of(outcomes);
  const long foreign = std::count(conflicts.begin(), conflicts.end(), contact::ShareOutcome::Conflict::foreign_cluster);
  MESSAGE("serial: " << serial.report.merges << " merges, " << serial.report.joined << " joined; shares: " << foreign
                     << " met another rank's cluster");
  if (serial.report.merges > 0) CHECK(foreign > 0);
  CHECK_FALSE(ok);
  CHECK(std::memcmp(f.state.data(), serial.state.data(), f.state.size() * sizeof(FloeState)) == 0);
  CHECK(same_stats(stats, serial.stats));
  CHECK(same_report(report, serial.report));
}

TEST_CASE("two ranks' clusters that take the same free floe fall back to the serial advance") {
  // The row of test::row_taking_one_free_floe (a's cluster and b's both
  // take the free floe j; serially the first takes j and the second merges
  // with it): as shares on two ranks, neither sees the other (no foreign
  // cluster), both take j: only the floe moved twice says so, and the
  // combination must refuse.
  const Case c = test::row_taking_one_free_floe();
  const Serial serial = serial_advance(c);
  MESSAGE("serial: " << serial.report.clusters << " clusters, " << serial.report.joined << " joined, "
                     << serial.report.merges << " merges");
  REQUIRE(serial.report.merges == 1);
  REQUIRE(serial.report.joined >= 1);
  const std::vector<int> owner{0, 0, 1, 1, 0};  // a's cluster on rank 0, b's on rank 1
  Floes f;
  contact::CollisionStats stats;
  contact::SubstepReport report;
  std::vector<contact::ShareOutcome> outcomes;
  const bool ok = play(c, owner, 2, f, stats, report, outcomes);
  const std::vector<contact::ShareOutcome::Conflict> conflicts = conflicts_of(outcomes);
  CHECK(conflicts == std::vector<contact::ShareOutcome::Conflict>(2, contact::ShareOutcome::Conflict::none));
  CHECK_FALSE(ok);
  CHECK(std::memcmp(f.state.data(), serial.state.data(), f.state.size() * sizeof(FloeState)) == 0);
  CHECK(same_stats(stats, serial.stats));
  CHECK(same_report(report, serial.report));
}

TEST_CASE("the advance's impulse records by cluster owner merge into the serial record") {
  // The packs above (events of many clusters at many sub-step times), and
  // with jams of two floes (time steps, whose solves again drop their loads
  // but keep counting events), over 2, 3 and 7 strips: where the shares
  // combine, every rank's events merged are the serial record's, in the
  // serial queue's order, numbered after the record's earlier ones.
  int combined = 0;
  for (const unsigned seed : {3u, 11u})
    for (const std::size_t jam : {std::size_t{0}, std::size_t{2}}) {
      CAPTURE(seed);
      CAPTURE(jam);
      Case c = dense_pack(2.0, seed, 0.5);
      if (jam > 0) c.options.impulse.jam.floes = jam;
      contact::ImpulseRecord serial;
      serial.events = 1;  // the step-start collisions' event
      {
        Floes f = c.floes;
        contact::SubstepOptions o = c.options;
        o.impulse.record = &serial;
        contact::CollisionStats stats;
        contact::SubstepReport report;
        contact::advance_with_collisions(f, c.shapes, c.detection, c.dt, o, stats, report);
        MESSAGE("serial: " << serial.events - 1 << " events, " << serial.loads.size() << " loads, "
                           << report.time_steps << " time steps");
      }
      REQUIRE(serial.events > 20);
      REQUIRE(!serial.loads.empty());
      for (const int ranks : {1, 2, 3, 7}) {
        CAPTURE(ranks);
        parallel::FloeOwners owners(0, ranks, c.domain);
        owners.assign(c.floes);
        contact::ImpulseRecord merged;
        merged.events = 1;
        std::vector<std::uint32_t> events;
        Floes f;
        contact::CollisionStats stats;
        contact::SubstepReport report;
        std::vector<contact::ShareOutcome> outcomes;
        const bool ok = play(c, owners.owner(), ranks, f, stats, report, outcomes, &merged, &events);
        MESSAGE(ranks << " ranks: " << std::string(ok ? "combined" : "fell back"));
        if (ranks == 1) CHECK(ok);
        if (!ok) continue;
        CHECK(test::same_record(merged, serial));
        if (ranks > 1) {
          ++combined;
          CHECK(std::count_if(events.begin(), events.end(), [](std::uint32_t e) { return e > 0; }) >= 2);
        }
      }
    }
  CHECK(combined >= 3);
}

TEST_CASE("merge_advance_record orders the events by (tau, cluster), renumbered, their loads with them") {
  // Rank 0: events at (0, 4) [loads 10, 11], (2.5, 4) [none: its loads
  // dropped], (2.5, 4) again [12]; rank 1: (0, 1) [20], (1.0, 1) [21, 22].
  // Serial order: (0, 1), (0, 4), (1.0, 1), (2.5, 4), (2.5, 4) -> events
  // 5..9, loads 20 | 10 11 | 21 22 | - | 12.
  auto load = [](std::uint32_t floe, std::uint32_t event) {
    contact::ImpulseRecord::Load l;
    l.floe = floe;
    l.event = event;
    return l;
  };
  contact::ImpulseRecord a, b;
  a.loads = {load(10, 0), load(11, 0), load(12, 2)};
  a.events = 3;
  const std::vector<contact::EventPlace> a_events{{0.0, 4}, {2.5, 4}, {2.5, 4}};
  b.loads = {load(20, 0), load(21, 1), load(22, 1)};
  b.events = 2;
  const std::vector<contact::EventPlace> b_events{{0.0, 1}, {1.0, 1}};
  contact::ImpulseRecord into;
  into.events = 5;
  const std::vector<contact::RecordPart> parts{{&a, {}, a_events}, {&b, {}, b_events}};
  contact::merge_advance_record(into, parts);
  std::vector<std::pair<std::uint32_t, std::uint32_t>> got;
  for (const auto& l : into.loads) got.emplace_back(l.floe, l.event);
  CHECK(got == std::vector<std::pair<std::uint32_t, std::uint32_t>>{{20, 5}, {10, 6}, {11, 6}, {21, 7}, {22, 7},
                                                                     {12, 9}});
  CHECK(into.events == 10);
}

namespace {

// Plays parallel::advance_on_part over `ranks` ranks: each rank's part of the
// detection by `strips` (detect_part), its share on that part with the
// clusters given to `owner`, the tight pairs and edges, the join candidates
// (none with `candidates` false: only the members' pairs routed), then the
// routed pairs and the parts through pack/unpack (and the pad edges first
// when a cluster is jam-sized: `pads` counts those). Returns whether they
// combined (else `f` holds the whole advance); `sent` counts the routed
// pairs, `missing` the shares that stopped at a floe they did not hold.
// With `merged`, each share records into a record of its own, whose events
// are merged into `merged` (or the whole advance records into it), and
// `events` gets each share's event count.
//
// Each share is given its strip's floes (`mine`, the rank's by place) and
// moves the free floes it holds; every copy then moves the rest as
// parallel::advance_on_part does while every rank holds every floe
// (move_not_held). A floe outrunning its reach on some share (the flags
// gathered with the rooms) makes every share rebuild (rooms_rebuilt) and
// the rooms be gathered again (`rebuilds` counts those plays).
//
// With `poisoned` (the halo plan's pieces 2 and 9, docs/parallel.md): each
// share's copy has every floe NaN (state, mass, inertia, vertices, its
// collision shape, its reach in the part) and its owner -1 but its strip's
// and its part's pairs' floes (the clusters' runners come from the owners
// the tight pairs and edges carry), and then holds the floes the routed
// pairs carry (parallel::RoutedFloes, through their bytes) before it runs;
// a poisoned floe's x is kSentinel (finite: a share that moved it would
// write NaN there). `packed` gets each share's part as bytes, `fetched`
// counts the floes a share received that its copy did not hold, `held` and
// `states` each share's held floes and its copy's states after its
// advance (no move_not_held). `f` is then not the answer (the copies are
// poisoned): compare the parts with a clean play's.
constexpr double kSentinel = 1.0e30;
struct Poisoned {
  bool poison = true;  // false: the parts' bytes only, from the whole state
  // With poison false: only the parts' reaches beyond each share's own and
  // its part's pairs' floes are NaN (a rank writes only its band's reaches
  // at the detection, band18), the state whole.
  bool stale_reaches = false;
  std::vector<std::vector<std::byte>> packed;
  std::vector<std::vector<std::pair<int, std::uint32_t>>> routes;  // each share's routes (the candidates' closure)
  std::vector<std::vector<std::uint32_t>> held;                      // each share's held floes (ShareAdvance::held)
  std::vector<std::vector<FloeState>> states;                        // each share's copy after its advance
  long fetched = 0;
  // Each share's held pairs' floes whose reach, after the routed floes'
  // shapes and reaches were held, is not the detection's (bits).
  long reach_wrong = 0, reach_checked = 0;
  // drop_shape: the first floe routed to a share whose copy did not hold
  // it has its collision shape removed (NaN again) after the hold: `dropped`
  // that floe, `dropped_at` that share.
  bool drop_shape = false;
  long dropped = -1;
  int dropped_at = -1;
};
void poison_floe(Floes& f, std::size_t i) {
  constexpr double nan = std::numeric_limits<double>::quiet_NaN();
  double* d = reinterpret_cast<double*>(&f.state[i]);
  std::fill_n(d, sizeof(FloeState) / sizeof(double), nan);
  f.state[i].x = kSentinel;
  f.mass[i] = f.inertia_z[i] = nan;
  for (std::size_t k = f.offsets[i]; k < f.offsets[i + 1]; ++k) f.body[k] = Vec2::Constant(nan);
}
bool play_parts(const Case& c, const parallel::FloeOwners& strips, std::span<const int> owner, int ranks, Floes& f,
                contact::CollisionStats& stats, contact::SubstepReport& report, long& sent, long& missing,
                long& pads, bool candidates = true, contact::ImpulseRecord* merged = nullptr,
                std::vector<std::uint32_t>* events = nullptr, Poisoned* poisoned = nullptr, long* rebuilds = nullptr,
                parallel::JoinedClusters* joined = nullptr, bool* again = nullptr) {
  const auto n = static_cast<std::size_t>(ranks);
  std::vector<Floes> copies(n, c.floes);
  std::vector<std::vector<std::uint8_t>> held(n, std::vector<std::uint8_t>(c.floes.size(), 0));
  std::vector<contact::Detection> parts;
  std::vector<std::unique_ptr<contact::ShareAdvance>> shares;
  std::vector<contact::ShareRooms> rooms;
  std::vector<contact::ImpulseRecord> own(n);
  // Each share's owners: all of them, or poisoned (-1) beyond its floes.
  std::vector<std::vector<int>> owners(n, std::vector<int>(owner.begin(), owner.end()));
  // Each rank's floes by place (FloeOwners::mine on that rank).
  std::vector<std::vector<std::uint32_t>> strip_floes(n);
  for (std::uint32_t i = 0; i < c.floes.size(); ++i)
    strip_floes[static_cast<std::size_t>(strips.owner()[i])].push_back(i);
  for (int r = 0; r < ranks; ++r)
    parts.push_back(parallel::detect_part(strips, r, c.floes, c.shapes, c.detect_options));
  // Each share's collision shapes: the case's, or poisoned beyond its floes.
  std::vector<contact::CollisionShapes> shapes(n, c.shapes);
  if (poisoned && poisoned->poison)
    for (std::size_t k = 0; k < n; ++k) {
      for (std::size_t i = 0; i < c.floes.size(); ++i) held[k][i] = strips.owner()[i] == static_cast<int>(k);
      for (const contact::NearPair& q : parts[k].pairs) held[k][q.a] = held[k][q.b] = 1;
      for (std::size_t i = 0; i < c.floes.size(); ++i)
        if (!held[k][i]) {
          poison_floe(copies[k], i);
          owners[k][i] = -1;
          parts[k].reach[i] = std::numeric_limits<double>::quiet_NaN();
        }
      shapes[k] = test::poisoned(c.shapes, held[k]);
    }
  if (poisoned && !poisoned->poison && poisoned->stale_reaches)
    for (std::size_t k = 0; k < n; ++k) {
      std::vector<std::uint8_t> known(c.floes.size(), 0);
      for (std::size_t i = 0; i < c.floes.size(); ++i) known[i] = strips.owner()[i] == static_cast<int>(k);
      for (const contact::NearPair& q : parts[k].pairs) known[q.a] = known[q.b] = 1;
      for (std::size_t i = 0; i < c.floes.size(); ++i)
        if (!known[i]) parts[k].reach[i] = std::numeric_limits<double>::quiet_NaN();
    }
  // With `joined`: the clusters it joined on one rank run there.
  const std::span<const std::pair<std::int32_t, std::int32_t>> runners =
      joined ? joined->runners() : std::span<const std::pair<std::int32_t, std::int32_t>>{};
  for (int r = 0; r < ranks; ++r) {
    const std::size_t k = static_cast<std::size_t>(r);
    contact::SubstepOptions o = c.options;
    if (merged) o.impulse.record = &own[k];
    shares.push_back(std::make_unique<contact::ShareAdvance>(copies[k], shapes[k], parts[k], c.dt, o,
                                                             contact::ClusterShare{owners[k], r, runners}, true,
                                                             strip_floes[k]));
    rooms.push_back(parallel::unpack_share_rooms(parallel::pack(shares.back()->rooms())));
  }
  if (parallel::any_outrun(rooms)) {
    // Every share rebuilds alike, with every floe's reach from its owner
    // (the serial detection's: comm.complete_owned in advance_on_part), and
    // the rooms are gathered again.
    if (rebuilds) ++*rebuilds;
    for (std::size_t k = 0; k < n; ++k)
      rooms[k] = parallel::unpack_share_rooms(parallel::pack(shares[k]->rooms_rebuilt(c.detection.reach)));
  }
  contact::ShareRooms all;
  bool ok = parallel::combine_rooms(rooms, all);
  std::vector<contact::ShareAdvance::Routes> routes;
  for (std::size_t k = 0; ok && k < n; ++k) {
    routes.push_back(shares[k]->clusters(all));
    if (k > 0) CHECK((routes[k].conflict == contact::ShareOutcome::Conflict::none) == ok);  // alike on every rank
    if (k > 0) CHECK(routes[k].pads == routes[0].pads);
    ok = routes[k].conflict == contact::ShareOutcome::Conflict::none;
  }
  if (ok && routes[0].pads) {
    // A jam-sized cluster: every rank's pad edges (the allgather), then the clusters.
    ++pads;
    std::vector<contact::ContactEdge> edges;
    for (std::size_t k = 0; k < n; ++k) {
      const std::vector<contact::ContactEdge> mine = shares[k]->pad_edges();
      edges.insert(edges.end(), mine.begin(), mine.end());
    }
    for (std::size_t k = 0; k < n; ++k) routes[k] = shares[k]->pads(edges);
  }
  std::vector<contact::JoinCandidate> joins;  // every rank's, in rank order (the allgather)
  for (std::size_t k = 0; ok && candidates && k < n; ++k)
    joins.insert(joins.end(), routes[k].candidates.begin(), routes[k].candidates.end());
  std::vector<std::vector<contact::Detection>> out;
  for (std::size_t k = 0; ok && k < n; ++k) {
    const std::vector<std::pair<int, std::uint32_t>> to = shares[k]->routes(joins);
    if (poisoned) poisoned->routes.push_back(to);
    out.push_back(parallel::routed_pairs(parts[k], to, ranks));
  }
  // The routed floes' shapes and reaches (parallel::RoutedShapes), per
  // sender and receiver, written into the receiver's with its held pairs.
  std::vector<std::vector<parallel::RoutedShapes>> carried_shapes(n);
  if (ok && poisoned && poisoned->poison) {
    // The routed pairs' floes, from each sender's copy before any share
    // moves a floe (a rank sends them before it advances), through their bytes.
    std::vector<std::vector<parallel::RoutedFloes>> carried(n);
    for (std::size_t s = 0; s < n; ++s)
      for (std::size_t k = 0; k < n; ++k) {
        carried[s].push_back(parallel::unpack_routed_floes(
            parallel::pack(parallel::routed_floes(copies[s], {}, out[s][k]))));
        carried_shapes[s].push_back(parallel::unpack_routed_shapes(
            parallel::pack(parallel::routed_shapes(shapes[s], parts[s].reach, carried[s][k].floe))));
      }
    for (std::size_t k = 0; k < n; ++k)
      for (std::size_t s = 0; s < n; ++s) {
        for (const std::uint32_t i : carried[s][k].floe) poisoned->fetched += held[k][i] ? 0 : 1;
        parallel::hold(carried[s][k], copies[k], {});
      }
  }
  if (ok) {
    std::vector<parallel::AdvancePart> advanced;
    for (std::size_t k = 0; k < n; ++k) {
      std::vector<contact::Detection> pairs{parts[k]};
      for (std::size_t s = 0; s < n; ++s)
        if (!out[s][k].pairs.empty()) {
          sent += static_cast<long>(out[s][k].pairs.size());
          pairs.push_back(parallel::unpack_detection(parallel::pack(out[s][k])));
        }
      contact::Detection with = parallel::merge(std::move(pairs));
      for (std::size_t s = 0; s < carried_shapes.size(); ++s)
        if (!carried_shapes[s].empty()) parallel::hold(carried_shapes[s][k], shapes[k], with.reach);
      if (poisoned && poisoned->poison) {
        // The held pairs' floes' reaches: the detection's (the routed ones from their bytes).
        for (const contact::NearPair& q : with.pairs)
          for (const std::uint32_t i : {q.a, q.b}) {
            ++poisoned->reach_checked;
            poisoned->reach_wrong += std::memcmp(&with.reach[i], &c.detection.reach[i], sizeof(double)) == 0 ? 0 : 1;
          }
        for (std::size_t s = 0; poisoned->drop_shape && poisoned->dropped < 0 && s < carried_shapes.size(); ++s)
          for (const std::uint32_t i : carried_shapes[s].empty() ? std::vector<std::uint32_t>{}
                                                                : carried_shapes[s][k].floe)
            if (!held[k][i] && poisoned->dropped < 0) {
              // The routed floe's shape removed: as its copy had it before the hold.
              constexpr double nan = std::numeric_limits<double>::quiet_NaN();
              contact::CollisionShapes& sh = shapes[k];
              sh.radius[i] = nan;
              for (std::size_t q = sh.parts_begin(i); q < sh.parts_end(i); ++q)
                for (std::size_t v = sh.vertex_offsets[q]; v < sh.vertex_offsets[q + 1]; ++v)
                  sh.vertices[v] = Vec2::Constant(nan);
              poisoned->dropped = i;
              poisoned->dropped_at = static_cast<int>(k);
            }
      }
      shares[k]->hold(std::move(with));
      const parallel::AdvancePart part =
          parallel::share_part(*shares[k], shares[k]->advance(), copies[k], merged ? &own[k] : nullptr);
      const std::span<const std::uint32_t> held_floes = shares[k]->held();
      if (poisoned) {
        poisoned->held.emplace_back(held_floes.begin(), held_floes.end());
        poisoned->states.push_back(copies[k].state);
      }
      parallel::move_not_held(copies[k], held_floes, c.dt);
      if (part.outcome.conflict == contact::ShareOutcome::Conflict::missing_pairs) ++missing;
      if (merged) events->push_back(part.record.events);
      if (poisoned) poisoned->packed.push_back(parallel::pack(part));
      advanced.push_back(parallel::unpack_advance_part(parallel::pack(part)));
    }
    f = std::move(copies.front());
    ok = parallel::combine_parts(advanced, f, stats, report, merged);
    // With `joined`: clusters of two runners that met are joined on one
    // rank and the caller plays the step again (advance_on_part's next try).
    if (!ok && joined && joined->add(advanced, *shares.front())) {
      *again = true;
      return false;
    }
  }
  if (ok) return true;
  f = c.floes;
  stats = {};
  report = {};
  contact::SubstepOptions whole = c.options;
  if (merged) whole.impulse.record = merged;
  contact::advance_with_collisions(f, c.shapes, c.detection, c.dt, whole, stats, report);
  return false;
}

// play_parts over `ranks` strips of the case with the clusters' owners
// shifted by `shift` ranks (0: the strips'; 1: every cluster's pairs travel).
struct PartsPlay {
  bool ok = false;
  Floes f;
  contact::CollisionStats stats;
  contact::SubstepReport report;
  long sent = 0, stopped = 0, pads = 0, rebuilds = 0;
  contact::ImpulseRecord record;        // with `record`: the merged record (after one earlier event)
  std::vector<std::uint32_t> events;    // with `record`: each share's event count
};
PartsPlay play_shifted(const Case& c, int ranks, int shift, bool candidates = true, bool record = false,
                       Poisoned* poisoned = nullptr, parallel::JoinedClusters* joined = nullptr,
                       bool* again = nullptr) {
  parallel::FloeOwners strips(0, ranks, c.domain);
  strips.assign(c.floes);
  std::vector<int> owner(strips.owner().begin(), strips.owner().end());
  for (int& o : owner) o = (o + shift) % ranks;
  PartsPlay p;
  p.record.events = 1;  // the step-start collisions' event
  p.ok = play_parts(c, strips, owner, ranks, p.f, p.stats, p.report, p.sent, p.stopped, p.pads, candidates,
                    record ? &p.record : nullptr, &p.events, poisoned, &p.rebuilds, joined, again);
  return p;
}

// play_shifted with the tries of advance_on_part: while a try's parts
// refuse only because clusters of two runners meet, they are joined on one
// rank (JoinedClusters) and the step is played again from its start.
// `rounds` counts the tries made again; with `poisoned`, each try poisons
// afresh and `poisoned` is left with the last try's.
PartsPlay play_joined(const Case& c, int ranks, int shift, int& rounds, Poisoned* poisoned = nullptr) {
  parallel::JoinedClusters joined;
  rounds = 0;
  for (;;) {
    bool again = false;
    Poisoned fresh;
    if (poisoned) fresh.poison = poisoned->poison;
    PartsPlay p = play_shifted(c, ranks, shift, true, false, poisoned ? &fresh : nullptr, &joined, &again);
    if (poisoned) *poisoned = std::move(fresh);
    if (!again) return p;
    ++rounds;
    REQUIRE(rounds < 8);  // advance_on_part's max_rounds
  }
}
// The played advance is the serial one: states to the bit, counts, report.
void check_serial(const PartsPlay& p, const Serial& serial) {
  REQUIRE(p.f.state.size() == serial.state.size());
  CHECK(std::memcmp(p.f.state.data(), serial.state.data(), p.f.state.size() * sizeof(FloeState)) == 0);
  CHECK(same_stats(p.stats, serial.stats));
  CHECK(same_report(p.report, serial.report));
}

}  // namespace

TEST_CASE("the advance from each rank's part of the detection over 1, 2, 3 and 7 strips is the serial advance") {
  // The clusters' owners the strips, and the strips shifted by one rank
  // (every cluster's pairs then travel). The free floes a cluster may take
  // in are routed to its runner with its members (join candidates); a floe
  // joining that is not one is a conflict (missing_pairs): the whole
  // advance. Whether combined or not, the answer is the serial one; without
  // the candidates (only the members' pairs routed, as before them) the
  // splits with a join fall back.
  int combined = 0, combined_bare = 0, splits = 0;
  long routed = 0, missing = 0, missing_bare = 0;
  const std::pair<unsigned, double> packs[] = {{3u, 2.0}, {11u, 2.0}, {5u, 1.5}, {7u, 1.2}, {9u, 1.8}};
  for (const auto& [seed, speed] : packs) {
    CAPTURE(seed);
    const Case c = dense_pack(speed, seed, 0.5);
    const Serial serial = serial_advance(c);
    MESSAGE("serial: " << serial.report.clusters << " clusters, " << serial.report.joined << " joined");
    for (const int ranks : {1, 2, 3, 7}) {
      for (const int shift : {0, 1}) {
        for (const bool candidates : {true, false}) {
          CAPTURE(ranks);
          CAPTURE(shift);
          CAPTURE(candidates);
          const PartsPlay p = play_shifted(c, ranks, shift, candidates);
          const bool ok = p.ok;
          const long sent = p.sent, stopped = p.stopped;
          MESSAGE(ranks << " ranks, shift " << shift << std::string(candidates ? "" : ", no candidates") << ": "
                        << std::string(ok ? "combined" : "fell back") << ", " << sent << " pairs routed, " << stopped
                        << " shares stopped at a floe not held");
          if (ranks > 1 && candidates) {
            ++splits;
            combined += ok ? 1 : 0;
            routed += sent;
            missing += stopped;
          }
          if (ranks > 1 && !candidates) {
            combined_bare += ok ? 1 : 0;
            missing_bare += stopped;
          }
          // Without a free floe joining and a jam-sized cluster nothing is
          // missing: the shares combine.
          if (serial.report.joined == 0 && serial.report.time_steps == 0) CHECK(ok);
          check_serial(p, serial);
        }
      }
    }
  }
  MESSAGE(combined << " of " << splits << " splits over several ranks combined (" << combined_bare
                   << " without candidates), " << routed << " pairs routed, " << missing << " shares stopped at a floe not held ("
                   << missing_bare << " without candidates)");
  CHECK(routed > 0);
  CHECK(missing_bare > 0);  // the packs do have floes joining across parts
  CHECK(combined > combined_bare);
  CHECK(missing < missing_bare);
}

TEST_CASE("the advance's share reads its strip, its part's floes and the floes the routed pairs carry") {
  // The halo plan's piece 2 for the advance, and its set-up over the held
  // floes: each share's copy has every floe poisoned (state, mass,
  // inertia, vertices, collision shape, reach), its owner too (-1), but its
  // strip's and its part's pairs' floes, and holds the routed pairs' floes
  // from their bytes (state at the step's start, mass, inertia, collision
  // shape, reach) before it runs (ShareAdvance::hold takes their straight
  // paths from them). Each share's part, as bytes, equals its part on the
  // whole state, over 2, 3 and 7 strips, the clusters' owners the strips
  // and shifted by one rank (the members then lie on other strips), and
  // where they combine, the combination is the advance's; each share moved
  // the free floes it holds to the whole play's bits and wrote no other.
  long fetched = 0, free_moved = 0, reach_checked = 0;
  int compared = 0;
  const std::pair<unsigned, double> packs[] = {{3u, 2.0}, {11u, 2.0}, {9u, 1.8}};
  for (const auto& [seed, speed] : packs) {
    CAPTURE(seed);
    const Case c = dense_pack(speed, seed, 0.5);
    for (const int ranks : {2, 3, 7})
      for (const int shift : {0, 1}) {
        CAPTURE(ranks);
        CAPTURE(shift);
        Poisoned clean, poisoned;
        clean.poison = false;
        const PartsPlay whole = play_shifted(c, ranks, shift, true, false, &clean);
        const PartsPlay p = play_shifted(c, ranks, shift, true, false, &poisoned);
        CHECK(p.ok == whole.ok);
        // Each share's routes (the join candidates' closure over the near
        // pairs, reading their ends' reach less travel as the pairs carry
        // them) and part, as bytes: the poisoned copy's equal the whole state's.
        CHECK(poisoned.routes == clean.routes);
        CHECK(poisoned.packed == clean.packed);
        CHECK(poisoned.reach_wrong == 0);
        reach_checked += poisoned.reach_checked;
        if (whole.ok && poisoned.packed.size() == static_cast<std::size_t>(ranks)) {
          // Each share moved the free floes it holds, to the whole play's
          // bits, and wrote no floe it does not hold (x still kSentinel).
          std::vector<std::uint8_t> moved(c.floes.size(), 0);
          for (const auto& b : poisoned.packed)
            for (const std::uint32_t i : parallel::unpack_advance_part(b).outcome.moved) moved[i] = 1;
          long wrong = 0, written = 0, free_held = 0;
          for (std::size_t k = 0; k < poisoned.held.size(); ++k) {
            const std::vector<std::uint32_t>& h = poisoned.held[k];
            for (std::uint32_t i = 0; i < c.floes.size(); ++i) {
              const FloeState& s = poisoned.states[k][i];
              if (!std::binary_search(h.begin(), h.end(), i)) {
                written += s.x == kSentinel ? 0 : 1;
              } else if (!moved[i]) {
                ++free_held;
                wrong += std::memcmp(&s, &whole.f.state[i], sizeof(FloeState)) == 0 ? 0 : 1;
              }
            }
            CHECK(h.size() < c.floes.size());
          }
          CHECK(free_held > 0);
          CHECK(wrong == 0);
          CHECK(written == 0);
          free_moved += free_held;
        }
        MESSAGE(ranks << " ranks, shift " << shift << ": " << std::string(whole.ok ? "combined" : "fell back") << ", "
                      << poisoned.fetched << " floes fetched with the routed pairs");
        fetched += poisoned.fetched;
        if (poisoned.packed.size() == static_cast<std::size_t>(ranks)) {
          // Combined on the whole state: the poisoned parts combined are its answer.
          if (whole.ok) {
            std::vector<parallel::AdvancePart> parts;
            for (const auto& b : poisoned.packed) parts.push_back(parallel::unpack_advance_part(b));
            Floes f = c.floes;
            contact::CollisionStats stats;
            contact::SubstepReport report;
            // Free floes: where the whole play put them (every rank moves them itself).
            f.state = whole.f.state;
            REQUIRE(parallel::combine_parts(parts, f, stats, report, nullptr));
            CHECK(std::memcmp(f.state.data(), whole.f.state.data(), f.state.size() * sizeof(FloeState)) == 0);
            CHECK(same_stats(stats, whole.stats));
            CHECK(same_report(report, whole.report));
            ++compared;
          }
        }
      }
  }
  MESSAGE(compared << " splits compared, " << fetched << " floes fetched with the routed pairs, " << free_moved
                   << " free floes moved by the shares holding them");
  CHECK(compared >= 6);
  CHECK(fetched > 0);
  CHECK(reach_checked > 0);
}

TEST_CASE("clusters of two ranks that meet, joined on one rank and run there from their members only, are the "
          "serial advance") {
  // The tries of advance_on_part (docs/parallel.md, "The conflicting
  // clusters on one rank"): a try whose shares met another runner's
  // cluster or took one free floe is played again with those clusters
  // joined on the runner of their lowest, until the parts combine. Over 2,
  // 3 and 7 strips, the clusters' owners the strips and shifted by one
  // rank: the answer is the serial advance bit for bit, and every split
  // the single try left to the whole advance for meeting clusters now
  // combines. Played again with each share's copy poisoned beyond its
  // strip and part (the joined clusters' members and candidates reach
  // their runner only with the routed pairs), the last try's parts are the
  // clean play's byte for byte.
  int splits = 0, single = 0, cured = 0, poisoned_compared = 0;
  long rounds_total = 0;
  const std::pair<unsigned, double> packs[] = {{3u, 2.0}, {11u, 2.0}, {5u, 1.5}, {7u, 1.2}, {9u, 1.8}};
  for (const auto& [seed, speed] : packs) {
    CAPTURE(seed);
    const Case c = dense_pack(speed, seed, 0.5);
    const Serial serial = serial_advance(c);
    for (const int ranks : {2, 3, 7})
      for (const int shift : {0, 1}) {
        CAPTURE(ranks);
        CAPTURE(shift);
        ++splits;
        single += play_shifted(c, ranks, shift).ok ? 1 : 0;
        int rounds = 0;
        const PartsPlay p = play_joined(c, ranks, shift, rounds);
        check_serial(p, serial);
        rounds_total += rounds;
        if (p.ok && rounds > 0) ++cured;
        MESSAGE(ranks << " ranks, shift " << shift << ": " << std::string(p.ok ? "combined" : "fell back")
                      << " after " << rounds << " tries joining clusters");
        // The clean and the poisoned plays of the same tries.
        Poisoned clean, poisoned;
        clean.poison = false;
        int clean_rounds = 0, poisoned_rounds = 0;
        const PartsPlay whole = play_joined(c, ranks, shift, clean_rounds, &clean);
        const PartsPlay q = play_joined(c, ranks, shift, poisoned_rounds, &poisoned);
        CHECK(poisoned_rounds == clean_rounds);
        CHECK(q.ok == whole.ok);
        CHECK(poisoned.packed == clean.packed);
        if (rounds > 0 && q.ok) ++poisoned_compared;
      }
  }
  MESSAGE(single << " of " << splits << " splits combined in one try, " << cured << " more once their meeting clusters "
                 << "were joined (" << rounds_total << " tries again); " << poisoned_compared
                 << " of those compared poisoned");
  CHECK(cured > 0);
  CHECK(poisoned_compared > 0);
  CHECK(single + cured == splits);  // no split left to the whole advance on these packs
}

TEST_CASE("two ranks' clusters that take the same free floe, from the parts: joined on one rank, the serial advance") {
  // The row of "two ranks' clusters that take the same free floe" above (a's
  // cluster on rank 0, b's on rank 1, both take j), played from each rank's
  // part: the first try's parts both move j (no conflict, taken twice), so
  // the two clusters are joined on rank 0 (the runner of the lower) and the
  // second try combines, equal to the serial advance.
  const Case c = test::row_taking_one_free_floe();
  const Serial serial = serial_advance(c);
  REQUIRE(serial.report.merges == 1);
  parallel::FloeOwners strips(0, 2, c.domain);
  strips.assign(c.floes);
  const std::vector<int> owner{0, 0, 1, 1, 0};
  parallel::JoinedClusters joined;
  int tries = 0;
  PartsPlay p;
  for (bool again = true; again; ++tries) {
    again = false;
    long sent = 0, stopped = 0, pads = 0;
    p = PartsPlay{};
    p.ok = play_parts(c, strips, owner, 2, p.f, p.stats, p.report, sent, stopped, pads, true, nullptr, nullptr,
                      nullptr, nullptr, &joined, &again);
    REQUIRE(tries < 8);
  }
  MESSAGE(tries << " tries, " << joined.runners().size() << " clusters given another runner");
  CHECK(tries == 2);
  CHECK(p.ok);
  CHECK(joined.runners().size() == 2);
  check_serial(p, serial);
}

TEST_CASE("the advance's share given a routed floe without its collision shape fails at once, naming the floe and the rank") {
  // The poisoned play of the case above (each share's copy NaN beyond its
  // strip and part), with the first routed floe a share did not hold left
  // without its shape after the hold (NaN radius and vertices). Before the
  // check (ShareAdvance::hold, Stepper::whole) such a share's sub-steps met
  // NaN limits: a cluster near the step's end took sub-steps of length 0,
  // which never end. Now its advance returns at once, a missing_floe
  // conflict naming the floe, and parallel::check_routed_floes (what
  // advance_on_part calls on the gathered parts) throws a RunError naming
  // the rank and the floe.
  const Case c = dense_pack(2.0, 3u, 0.5);
  int failed = 0;
  for (const int ranks : {2, 3})
    for (const int shift : {0, 1}) {
      CAPTURE(ranks);
      CAPTURE(shift);
      Poisoned poisoned;
      poisoned.drop_shape = true;
      play_shifted(c, ranks, shift, true, false, &poisoned);
      if (poisoned.dropped < 0) continue;  // no floe routed to a share that did not hold it
      ++failed;
      REQUIRE(poisoned.packed.size() == static_cast<std::size_t>(ranks));
      std::vector<parallel::AdvancePart> parts;
      for (const auto& b : poisoned.packed) parts.push_back(parallel::unpack_advance_part(b));
      const contact::ShareOutcome& o = parts[static_cast<std::size_t>(poisoned.dropped_at)].outcome;
      CHECK(o.conflict == contact::ShareOutcome::Conflict::missing_floe);
      REQUIRE(o.moved.size() == 1);
      CHECK(o.moved.front() == poisoned.dropped);
      std::string said;
      try {
        parallel::check_routed_floes(parts);
      } catch (const RunError& e) {
        said = e.what();
      }
      MESSAGE(ranks << " ranks, shift " << shift << ": " << said);
      CHECK(said.find("rank " + std::to_string(poisoned.dropped_at) + ": floe " +
                      std::to_string(poisoned.dropped) + " ") != std::string::npos);
    }
  CHECK(failed >= 2);
}

TEST_CASE("the advance from each rank's part with jam-sized clusters gathers their pads and is the serial advance") {
  // jam.floes = 2: every cluster is "big" and its pad (room below jam.pad
  // xi = 10 m) joins it at the step's start; on a part those pairs are
  // spread over the ranks, which exchange their pad edges. Clusters owned
  // by the strips and shifted by one rank; the answer is the serial one.
  int combined = 0, padded = 0;
  for (const unsigned seed : {3u, 11u}) {
    CAPTURE(seed);
    Case c = dense_pack(2.0, seed, 0.5);
    c.options.impulse.jam.floes = 2;
    const Serial serial = serial_advance(c);
    REQUIRE(serial.report.largest_cluster >= 2);
    for (const int ranks : {2, 3, 7})
      for (const int shift : {0, 1}) {
        CAPTURE(ranks);
        CAPTURE(shift);
        const PartsPlay p = play_shifted(c, ranks, shift);
        MESSAGE(ranks << " ranks, shift " << shift << ": " << std::string(p.ok ? "combined" : "fell back") << ", "
                      << p.pads << " pad exchanges, " << p.sent << " pairs routed");
        combined += p.ok ? 1 : 0;
        padded += static_cast<int>(p.pads);
        check_serial(p, serial);
      }
  }
  CHECK(padded == 12);  // every split had a jam-sized cluster
  CHECK(combined >= 1);
}

TEST_CASE("the advance's records from each rank's part merge into the serial record") {
  // The packs of the advance from the parts (events of many clusters at
  // many sub-step times, free floes joining), and with jams of two floes
  // (time steps and their pads' exchange), over 1, 2, 3 and 7 strips, the
  // clusters' owners the strips and shifted by one rank: where the shares
  // combine, their events merged are the serial record's, in the serial
  // queue's order, numbered after the step-start event; where they fall
  // back, the whole advance records the serial record itself.
  int combined = 0;
  const std::pair<unsigned, double> packs[] = {{3u, 2.0}, {11u, 2.0}, {9u, 1.8}};
  for (const auto& [seed, speed] : packs)
    for (const std::size_t jam : {std::size_t{0}, std::size_t{2}}) {
      CAPTURE(seed);
      CAPTURE(jam);
      Case c = dense_pack(speed, seed, 0.5);
      if (jam > 0) c.options.impulse.jam.floes = jam;
      contact::ImpulseRecord serial;
      serial.events = 1;
      Serial whole;
      {
        Floes f = c.floes;
        contact::SubstepOptions o = c.options;
        o.impulse.record = &serial;
        contact::advance_with_collisions(f, c.shapes, c.detection, c.dt, o, whole.stats, whole.report);
        whole.state = f.state;
      }
      MESSAGE("serial: " << serial.events - 1 << " events, " << serial.loads.size() << " loads");
      REQUIRE(serial.events > 20);
      REQUIRE(!serial.loads.empty());
      for (const int ranks : {1, 2, 3, 7})
        for (const int shift : {0, 1}) {
          CAPTURE(ranks);
          CAPTURE(shift);
          const PartsPlay p = play_shifted(c, ranks, shift, true, true);
          MESSAGE(ranks << " ranks, shift " << shift << ": " << std::string(p.ok ? "combined" : "fell back"));
          if (ranks == 1) CHECK(p.ok);
          check_serial(p, whole);
          CHECK(test::same_record(p.record, serial));
          if (p.ok && ranks > 1) {
            ++combined;
            CHECK(std::count_if(p.events.begin(), p.events.end(), [](std::uint32_t e) { return e > 0; }) >= 2);
          }
        }
    }
  MESSAGE(combined << " splits over several ranks combined");
  CHECK(combined >= 6);
}

TEST_CASE("a floe outrunning its reach on one rank's strip makes every share rebuild the pair list") {
  // One floe of the last strip is sped up past its reach (the detection
  // was made before): the serial set-up rebuilds the pair list once. On a
  // part only that floe's owner sees it (each share checks its own floes);
  // the flag gathered with the rooms makes every share rebuild
  // (rooms_rebuilt) and the rooms be gathered again: the serial advance,
  // the clusters' owners the strips and shifted by one rank.
  Case c = dense_pack(2.0, 11, 0.5);
  std::size_t fast = 0;
  for (std::size_t i = 1; i < c.floes.size(); ++i)
    if (c.floes.state[i].y > c.floes.state[fast].y) fast = i;
  FloeState& s = c.floes.state[fast];
  const double speed = std::hypot(s.vx, s.vy);
  REQUIRE(speed > 0.0);
  const double scale = 1.3 * c.detection.reach[fast] / (c.dt * speed);
  s.vx *= scale;
  s.vy *= scale;
  const Serial serial = serial_advance(c);
  MESSAGE("serial: rebuilt " << serial.report.rebuilt << ", " << serial.report.clusters << " clusters");
  REQUIRE(serial.report.rebuilt == 1);
  REQUIRE(serial.report.clusters > 20);
  int combined = 0;
  for (const int ranks : {2, 3, 7})
    for (const int shift : {0, 1}) {
      CAPTURE(ranks);
      CAPTURE(shift);
      // Each share's part holds the reaches of its own floes and its
      // pairs' floes only (band18), the others NaN: the rebuild reads the
      // reaches from their owners, not the part's.
      Poisoned stale;
      stale.poison = false;
      stale.stale_reaches = true;
      const PartsPlay p = play_shifted(c, ranks, shift, true, false, &stale);
      MESSAGE(ranks << " ranks, shift " << shift << ": " << std::string(p.ok ? "combined" : "fell back") << ", "
                    << p.rebuilds << " rebuilds agreed");
      CHECK(p.rebuilds == 1);
      combined += p.ok ? 1 : 0;
      check_serial(p, serial);
    }
  CHECK(combined >= 2);  // the shares' advance on the rebuilt list, not only the fallback
}

TEST_CASE("joins at depth three and on: the share on the poisoned copy takes in a row of free floes as the clean play") {
  // A column of 10 m squares along y: a1 (floe 0, 1 m/s up) hits a2
  // (floe 1) 0.5 m ahead; above a2 six floes at rest, 0.05 m apart (beyond
  // xi = 0.01 m, below the near pairs' 10 xi): each floe hit leaves its
  // straight path (rest) and brings in the next, a Newton's cradle, so the
  // cluster takes them in one after another (joins at depth one to six).
  // The column crosses every cut of 2 and 3 strips, and with the owners
  // shifted by one rank the cluster's runner holds none of the chain's
  // pairs: they reach it only through the candidates' closure over the
  // gathered near pairs. Each share's part and routes on the poisoned copy
  // (state, shape, reach, owners beyond its floes) equal the clean play's,
  // and the played advance is the serial one.
  auto box = [](double y0, double vy) {
    FloeInput f;
    f.vertices = {{0.0, y0}, {10.0, y0}, {10.0, y0 + 10.0}, {0.0, y0 + 10.0}};
    f.velocity = {0.0, vy};
    return f;
  };
  Case c;
  double y = 0.0;
  for (int k = 0; k < 8; ++k) {
    const FloeInput in = box(y, k == 0 ? 1.0 : 0.0);
    c.floes.add(make_floe_shape(in), in);
    y += 10.0 + (k == 0 ? 0.5 : 0.05);
  }
  c.shapes = contact::build_collision_shapes(c.floes);
  c.domain = {false, -50.0, 60.0, -50.0, 150.0};
  contact::DetectionOptions d;
  d.domain = c.domain;
  d.horizon = c.dt;
  d.reach.assign(c.floes.size(), 15.0);  // m: a1 travels 10 m (no rebuild)
  c.detection = contact::detect(c.floes, c.shapes, d);
  c.detect_options = d;
  c.options.floor = 1e-3 * c.dt;
  c.options.domain = c.domain;
  const Serial serial = serial_advance(c);
  MESSAGE("serial: " << serial.report.clusters << " clusters, " << serial.report.joined << " joined, "
                     << serial.report.merges << " merges");
  REQUIRE(serial.report.joined >= 3);  // in a row: the third joined through the second, through the first
  REQUIRE(serial.report.rebuilt == 0);
  int combined = 0;
  for (const int ranks : {2, 3})
    for (const int shift : {0, 1}) {
      CAPTURE(ranks);
      CAPTURE(shift);
      Poisoned clean, poisoned;
      clean.poison = false;
      const PartsPlay whole = play_shifted(c, ranks, shift, true, false, &clean);
      const PartsPlay p = play_shifted(c, ranks, shift, true, false, &poisoned);
      MESSAGE(ranks << " ranks, shift " << shift << ": " << std::string(whole.ok ? "combined" : "fell back") << ", "
                    << whole.sent << " pairs routed, " << poisoned.fetched << " floes fetched");
      check_serial(whole, serial);
      CHECK(p.ok == whole.ok);
      CHECK(poisoned.routes == clean.routes);
      CHECK(poisoned.packed == clean.packed);
      combined += whole.ok ? 1 : 0;
    }
  CHECK(combined == 4);
}
