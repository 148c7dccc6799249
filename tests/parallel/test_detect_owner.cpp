// The detection's lists by owner without ranks (docs/parallel.md, "The
// detection's lists by owner"): each simulated rank holds only the pairs it
// detected (those whose floe a it owned at the detection), says its pairs'
// edges (contact::group_edges), finds the step groups from every rank's
// edges (contact::step_groups), sends the pairs of the groups other ranks own
// to them (parallel::pairs_for_groups) and runs its share on its pairs and
// those received. Over 1, 2, 3 and 7 strips, with the groups' owners not the
// detection's, the shares combined are the serial solve bit for bit (states
// by memcmp, counts, speculative contacts), the pairs sent are a small part
// of the lists, and shares that use the warm store (each on its copy)
// leave the serial store. In a run
// that keeps the impulse record, the shares on their parts record their
// loads keyed by pair (contact::ContactPlace), and the parts merged are the
// serial record.
#include <doctest/doctest.h>

#include <algorithm>
#include <cstring>
#include <numeric>
#include <vector>

#include "parallel/collide_share.hpp"
#include "parallel/detect.hpp"
#include "parallel/place.hpp"
#include "tests/parallel/collide_case.hpp"
#include "tests/parallel/same_detection.hpp"

TEST_SUITE_BEGIN("mpi");

using namespace floesim;
using test::CollideCase;
using test::same_states;
using test::same_stats;

namespace {

std::vector<int> strips(const CollideCase& c, int ranks) {
  parallel::FloeOwners owners(0, ranks, c.domain);
  owners.assign(c.floes);
  return {owners.owner().begin(), owners.owner().end()};
}

struct Played {
  Floes floes;
  contact::CollisionStats stats;
  std::size_t speculative = 0;
  std::vector<long> groups;
  std::size_t sent = 0, whole = 0;  // pairs sent between ranks; pairs in the detection
  bool combined = false;
  std::vector<std::size_t> loads;  // with a record: each rank's loads
};

// `ranks` ranks: rank r detected the pairs whose floe a detected[a] == r;
// the step groups belong to the owners `owner` (of the step, after the
// drift). Each rank's share runs on its own copy of W^-. With `merged`, the
// shares record (each into its part's own record) and the parts' records
// are merged into `merged`. With c.options.warm, the parts' stored pairs
// are written into it.
Played play(const CollideCase& c, const std::vector<int>& detected, const std::vector<int>& owner, int ranks,
            contact::ImpulseRecord* merged = nullptr) {
  Played out;
  out.whole = c.detection.pairs.size();
  std::vector<contact::Detection> part(static_cast<std::size_t>(ranks));
  std::vector<contact::GroupEdge> edges;
  for (int r = 0; r < ranks; ++r) {
    part[static_cast<std::size_t>(r)] =
        parallel::select_pairs(c.detection, [&](const contact::NearPair& p) { return detected[p.a] == r; });
    const std::vector<contact::GroupEdge> e =
        contact::group_edges(c.floes, c.start, part[static_cast<std::size_t>(r)], c.dt, c.options, owner);
    edges.insert(edges.end(), e.begin(), e.end());
  }
  const contact::StepGroups groups = contact::step_groups(c.floes, edges, c.options);
  // The groups do not depend on the edges' order.
  std::reverse(edges.begin(), edges.end());
  const contact::StepGroups reversed = contact::step_groups(c.floes, edges, c.options);
  CHECK(reversed.floes == groups.floes);
  CHECK(reversed.lowest == groups.lowest);
  CHECK(reversed.jam == groups.jam);
  CHECK(reversed.owner == groups.owner);
  // What each rank receives: the pairs of its groups that others detected.
  std::vector<std::vector<contact::Detection>> to(static_cast<std::size_t>(ranks));
  for (int r = 0; r < ranks; ++r)
    to[static_cast<std::size_t>(r)] = parallel::pairs_for_groups(c.floes, part[static_cast<std::size_t>(r)], groups,
                                                                ranks, r, c.options.collision_distance);
  std::vector<parallel::CollidePart> parts;
  contact::ImpulseRecord unused;  // the options' record: the shares record into their parts'
  contact::ImpulseOptions options = c.options;
  if (merged) options.record = &unused;
  for (int s = 0; s < ranks; ++s) {
    std::vector<contact::Detection> held{part[static_cast<std::size_t>(s)]};
    for (int r = 0; r < ranks; ++r) {
      const contact::Detection& d = to[static_cast<std::size_t>(r)][static_cast<std::size_t>(s)];
      if (r == s) CHECK(d.pairs.empty());
      if (d.pairs.empty()) continue;
      out.sent += d.pairs.size();
      held.push_back(parallel::unpack_detection(parallel::pack(d)));
    }
    const contact::Detection local = parallel::merge(std::move(held));
    Floes mine = c.floes;
    const parallel::CollidePart p =
        parallel::run_collide_share(mine, c.start, local, c.dt, options, owner, s, &groups);
    out.groups.push_back(p.outcome.groups);
    if (merged) {
      REQUIRE(p.outcome.places.size() == p.record.loads.size());
      out.loads.push_back(p.record.loads.size());
    }
    parts.push_back(parallel::unpack_collide_part(parallel::pack(p)));
    if (merged) CHECK(parts.back().outcome.places == p.outcome.places);  // the bytes carry the places
    if (s == 0) out.floes = std::move(mine);
  }
  CHECK(unused.loads.empty());
  CHECK(unused.events == 0);
  out.combined =
      parallel::combine_collide_parts(parts, out.floes, out.stats, out.speculative, merged, c.options.warm);
  return out;
}

}  // namespace

TEST_CASE("the step-start collisions from each rank's detected pairs and its groups' pairs are the serial solve") {
  for (const unsigned seed : {3u, 11u}) {
    CAPTURE(seed);
    const CollideCase c = test::rows_of_four(seed);
    Floes serial = c.floes;
    contact::CollisionStats serial_stats;
    const std::size_t serial_speculative =
        contact::resolve_step_collisions(serial, c.start, c.detection, c.dt, c.options, serial_stats);
    REQUIRE(serial_speculative >= 64);  // every row's components joined by a speculative contact
    for (const int ranks : {1, 2, 3, 7}) {
      CAPTURE(ranks);
      const std::vector<int> detected = strips(c, ranks);
      // The groups' owners: the detection's strips, and the strips shifted
      // by one rank (the floes migrated: every group's pairs travel).
      for (const int shift : {0, 1}) {
        CAPTURE(shift);
        std::vector<int> owner = detected;
        for (int& o : owner) o = (o + shift) % ranks;
        const Played p = play(c, detected, owner, ranks);
        CHECK(p.combined);
        CHECK(same_states(p.floes.state, serial.state));
        CHECK(same_stats(p.stats, serial_stats));
        CHECK(p.speculative == serial_speculative);
        CHECK(std::accumulate(p.groups.begin(), p.groups.end(), 0L) == 64);  // one group a row
        MESSAGE(ranks << " ranks, shift " << shift << ": " << p.sent << " of " << p.whole << " pairs sent");
        if (ranks == 1) CHECK(p.sent == 0);
        // Unshifted, only the rows across a cut send pairs; shifted, every
        // group's pairs go to the next rank, still never a pair no group reads.
        if (ranks > 1 && shift == 0) CHECK(p.sent < p.whole / 4);
        if (ranks > 1 && shift == 1) CHECK(p.sent > 0);
        CHECK(p.sent <= p.whole);
      }
    }
  }
}

TEST_CASE("the step-start collisions' records from each rank's part merge into the serial record") {
  // The rows of four (contact points and a speculative contact in every
  // row), and the same rows as jams of two floes solved at the step's start
  // (their speculative points: segment 1 of the places), over 1, 2, 3 and 7
  // strips, the groups' owners the strips and shifted by one rank: each
  // share holds only its part and the pairs sent to it, places its loads by
  // pair, and the parts merged are the serial record (every load field for
  // field, the doubles bit for bit, in its order, one event numbered after
  // the record's earlier ones).
  for (const bool jams : {false, true}) {
    CAPTURE(jams);
    const test::RecordedRows r = test::recorded_rows_of_four(jams);
    const CollideCase& c = r.c;
    const contact::ImpulseRecord& serial = r.record;
    const Floes& serial_floes = r.floes;
    const contact::CollisionStats& serial_stats = r.stats;
    MESSAGE("serial record: " << serial.loads.size() << " loads");
    REQUIRE(serial.events == 4);
    REQUIRE(serial.loads.size() > 100);
    for (const int ranks : {1, 2, 3, 7})
      for (const int shift : {0, 1}) {
        CAPTURE(ranks);
        CAPTURE(shift);
        const std::vector<int> detected = strips(c, ranks);
        std::vector<int> owner = detected;
        for (int& o : owner) o = (o + shift) % ranks;
        contact::ImpulseRecord merged;
        merged.events = 3;
        const Played p = play(c, detected, owner, ranks, &merged);
        REQUIRE(p.combined);
        CHECK(same_states(p.floes.state, serial_floes.state));
        CHECK(same_stats(p.stats, serial_stats));
        CHECK(test::same_record(merged, serial));
        // The loads came from several ranks (the merge had work to do).
        if (ranks > 1) CHECK(std::count_if(p.loads.begin(), p.loads.end(), [](std::size_t l) { return l > 0; }) >= 2);
      }
  }
}

TEST_CASE("the step groups from the edges are those of the whole detection, jams included") {
  // resolve_step_collisions_share without groups finds them from the whole
  // detection's edges; with jams of two floes (solved at the step's start or
  // left to their time step) a jam's pairs are contacts or nothing.
  for (const bool at_start : {false, true}) {
    CAPTURE(at_start);
    CollideCase c = test::rows_of_four(5);
    c.options.jam.floes = 2;
    c.options.jam.at_step_start = at_start;
    Floes serial = c.floes;
    contact::CollisionStats serial_stats;
    const std::size_t serial_speculative =
        contact::resolve_step_collisions(serial, c.start, c.detection, c.dt, c.options, serial_stats);
    for (const int ranks : {2, 3, 7}) {
      CAPTURE(ranks);
      const std::vector<int> detected = strips(c, ranks);
      const Played p = play(c, detected, detected, ranks);
      CHECK(p.combined);
      CHECK(same_states(p.floes.state, serial.state));
      CHECK(same_stats(p.stats, serial_stats));
      CHECK(p.speculative == serial_speculative);
    }
  }
}

TEST_CASE("shares on their pairs that use the warm store combine into the serial answer and store") {
  // warm_min = 0: every LCP starts from the warm store. Each share runs on
  // a copy of it (the store the shares see is left alone) and the parts'
  // stored pairs, written into it, make it the serial store.
  CollideCase c = test::rows_of_four(3);
  c.options.warm_min = 0;
  contact::WarmStart serial_warm, warm;
  Floes serial = c.floes;
  contact::CollisionStats serial_stats;
  contact::ImpulseOptions so = c.options;
  so.warm = &serial_warm;
  const std::size_t serial_speculative =
      contact::resolve_step_collisions(serial, c.start, c.detection, c.dt, so, serial_stats);
  c.options.warm = &warm;
  const std::vector<int> detected = strips(c, 3);
  const Played p = play(c, detected, detected, 3);
  CHECK(p.combined);
  CHECK(same_states(p.floes.state, serial.state));
  CHECK(same_stats(p.stats, serial_stats));
  CHECK(p.speculative == serial_speculative);
  CHECK(serial_warm.uses > 0);
  CHECK(test::same_store(warm, serial_warm));
}

TEST_CASE("the first overlapping pair and its distance at t from the ranks' parts are the serial scan's") {
  // The rows of four moved on straight paths over the step: A runs into B
  // and D into C, so many pairs overlap. Each simulated rank detects its
  // part (detect_part, strips at the new places); the least key over the
  // parts and the distance said by the rank that held the pair in the
  // previous detection (strips at the old places) are the serial scan's:
  // the first overlapping pair in pair order, and the distance at t of the
  // last pair of its two floes.
  const CollideCase c = test::rows_of_four(3);
  Floes moved = c.floes;
  for (FloeState& s : moved.state) {
    s.x += s.vx * c.dt;
    s.y += s.vy * c.dt;
  }
  const contact::CollisionShapes shapes = contact::build_collision_shapes(moved);
  contact::DetectionOptions d;
  d.domain = c.domain;
  d.horizon = c.dt;
  d.reach.assign(moved.size(), 6.0);
  const contact::Detection whole = contact::detect(moved, shapes, d);
  const auto first = std::find_if(whole.pairs.begin(), whole.pairs.end(), [](const auto& p) { return p.overlap; });
  REQUIRE(first != whole.pairs.end());
  REQUIRE(std::count_if(whole.pairs.begin(), whole.pairs.end(), [](const auto& p) { return p.overlap; }) > 10);
  double before = -1.0;
  for (const contact::NearPair& q : c.detection.pairs)
    if (q.a == first->a && q.b == first->b) before = q.distance;
  REQUIRE(before >= 0.0);
  for (const int ranks : {1, 2, 3, 7}) {
    CAPTURE(ranks);
    parallel::FloeOwners now(0, ranks, c.domain), then(0, ranks, c.domain);
    now.assign(moved);
    then.assign(c.floes);
    long long key = parallel::kNoOverlap;
    for (int r = 0; r < ranks; ++r)
      key = std::min(key, parallel::overlap_key(parallel::detect_part(now, r, moved, shapes, d)));
    CHECK(key == (static_cast<long long>(first->a) << 32 | first->b));
    const auto a = static_cast<std::uint32_t>(key >> 32), b = static_cast<std::uint32_t>(key & 0xffffffffLL);
    int holders = 0;
    for (int r = 0; r < ranks; ++r) {
      const contact::Detection previous =
          parallel::select_pairs(c.detection, [&](const contact::NearPair& p) { return then.owner()[p.a] == r; });
      double distance = -1.0;
      if (!parallel::distance_before(previous, a, b, distance)) continue;
      ++holders;
      CHECK(std::memcmp(&distance, &before, sizeof(double)) == 0);
    }
    CHECK(holders == 1);
  }
  // The serial communicator: the whole detection is the one part.
  const parallel::Overlap o = parallel::first_overlap(parallel::Communicator(), whole, c.detection);
  CHECK(o.any);
  CHECK(o.a == first->a);
  CHECK(o.b == first->b);
  CHECK(o.before == before);
  CHECK_FALSE(parallel::first_overlap(parallel::Communicator(), c.detection, c.detection).any);
}

TEST_CASE("a routed pairs' message (the collisions' and the advance's exchange) carries its pairs and pieces back whole, at 8 bytes a piece's count") {
  // parallel::pack_routed / unpack_routed, the one framing of exchange_pairs
  // (the collisions' pairs with their floes, the advance's with their floes
  // and shapes): the pairs, contact points and witnesses and every piece
  // read back byte for byte, with 0, 1, 2 and 3 pieces (an empty one
  // included), and the message no longer than the pairs and pieces and one
  // 8-byte count a piece (the last piece's size is the message's rest).
  const CollideCase c = test::rows_of_four(3);
  const contact::Detection pairs =
      parallel::select_pairs(c.detection, [](const contact::NearPair& p) { return p.a % 3 == 0; });
  REQUIRE(!pairs.pairs.empty());
  REQUIRE(!pairs.contacts.empty());
  const std::vector<std::byte> bare = parallel::pack(pairs);
  for (std::size_t count = 0; count <= 3; ++count) {
    CAPTURE(count);
    parallel::Pieces pieces;
    std::size_t bytes = bare.size();
    for (std::size_t k = 0; k < count; ++k) {
      // Piece k: 5 k + 3 bytes, the last empty when there are three.
      const std::size_t size = count == 3 && k == 2 ? 0 : 5 * k + 3;
      std::vector<std::byte> piece(size);
      for (std::size_t j = 0; j < size; ++j) piece[j] = static_cast<std::byte>(17 * k + j);
      bytes += size;
      pieces.push_back(std::move(piece));
    }
    const std::vector<std::byte> message = parallel::pack_routed(pairs, pieces);
    CHECK(message.size() == bytes + 8 * count);
    parallel::Pieces back{{std::byte{1}}};  // overwritten
    const contact::Detection read = parallel::unpack_routed(message, count, back);
    CHECK(test::same_lists(read.pairs, pairs.pairs));
    CHECK(test::same_lists(read.contacts, pairs.contacts));
    CHECK(test::same_lists(read.witnesses, pairs.witnesses));
    CHECK(back == pieces);
  }
}
