// The fracture checks by owner (coupling/percussion.hpp, docs/parallel.md
// "The fracture checks by owner"): the loaded floes' analyses split among
// 1, 2 and 3 simulated ranks, each with its own Percussion (its own models),
// their counts and initiations exchanged and concluded on every rank, give
// the serial check's floes (to the bit), events and counts. Two steps, the
// owners changed between them: a floe analysed on a rank that did not build
// its model in the first step gets a new model, which must give the bits of
// the serial run's kept one. Then floes close together: the splits their
// owners decide, kept or decided again in conclude when an earlier split of
// the step came within reach, are the serial splits.
#include <doctest/doctest.h>

#include <cmath>
#include <cstring>
#include <random>
#include <vector>

#include "coupling/percussion.hpp"
#include "core/floe.hpp"

using namespace floesim;

TEST_SUITE_BEGIN("coupling");

namespace {

// A 6 x 5 grid of 40 m x 30 m floes, `pitch` m from corner to corner
// along x (and pitch - 10 m along y), turned by various yaws (0 with
// `yaw` = 0). At 80 m no two are within a split's reach of each other (the
// overlap checks pass).
Floes grid_of_floes(double pitch = 80.0, double yaw = 0.1) {
  Floes floes;
  for (int k = 0; k < 30; ++k) {
    FloeInput in;
    const double x = pitch * (k % 6), y = (pitch - 10.0) * (k / 6);
    in.vertices = {{x, y}, {x + 40.0, y}, {x + 40.0, y + 30.0}, {x, y + 30.0}};
    const std::size_t i = floes.add(make_floe_shape(in), in);
    floes.state[i].yaw = yaw * k;
  }
  return floes;
}

// The step's record: on each floe of `struck` an impact at the middle of its
// left edge (body frame), of impulse J in [1, 1e6] N s drawn from `rng`
// (from screened through bounded to cracked), in one or two events; every
// fourth floe also pressed (sustained) at two points on its right edge, and
// every fifth pressed only, by 30 J (its static case screened, judged by the
// stress bound, or analysed).
contact::ImpulseRecord record_for(const Floes& floes, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> exponent(0.0, std::log10(1e6)), along(-10.0, 10.0);
  contact::ImpulseRecord record;
  record.events = 2;
  for (std::uint32_t i = 0; i < floes.size(); ++i) {
    const double J = std::pow(10.0, exponent(rng));
    contact::ImpulseRecord::Load l;
    l.floe = i;
    l.other = i;
    l.event = i % 2;
    double left = 0.0;
    for (const Vec2& p : floes.vertices(i)) left = std::min(left, p.x());
    l.point = Vec2{left, along(rng)};
    l.impulse = Vec2{J, 0.1 * J};
    l.normal = J;
    if (i % 5 != 3) record.loads.push_back(l);  // every fifth floe is only pressed
    if (i % 4 == 0 || i % 5 == 3) {
      for (const double y : {-12.0, 12.0}) {
        contact::ImpulseRecord::Load s = l;
        s.sustained = true;
        s.point = Vec2{-left, y};
        s.impulse = Vec2{i % 5 == 3 ? -30.0 * J : -0.02 * J, 0.0};
        record.loads.push_back(s);
      }
    }
  }
  return record;
}

bool same_floes(const Floes& a, const Floes& b) {
  auto bits = [](const auto& u, const auto& v) {
    return u.size() == v.size() &&
           (u.empty() || std::memcmp(u.data(), v.data(), u.size() * sizeof(u[0])) == 0);
  };
  return a.size() == b.size() && bits(a.offsets, b.offsets) && bits(a.body, b.body) && bits(a.state, b.state) &&
         bits(a.id, b.id) && bits(a.area, b.area) && bits(a.mass, b.mass) && bits(a.inertia_z, b.inertia_z) &&
         a.ids_issued == b.ids_issued;
}

bool same_events(const std::vector<FractureEventRow>& a, const std::vector<FractureEventRow>& b) {
  return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(a[0])) == 0);
}

FractureParams params() {
  FractureParams p;
  p.enabled = true;
  p.split = true;
  p.mesh_size = 4.0;
  return p;
}

// Plays `ranks` ranks over the steps of `records` from `start`, each rank
// with its own Percussion (its own models): each analyses its share, the
// parts are packed, unpacked and combined, and every rank concludes. Owners
// by blocks of four floes, the last ranks first (so that the ranks'
// initiations are not in floe order), moved by one block at every step
// (floes past the owners' end, the pieces of earlier steps, are rank 0's).
// Every rank's floes (to the bit), events and counts must be the serial
// run's, and every rank must have analysed some floes. Returns how many
// splits the shares decided at less than the full opening `gap`.
long check_ranks(int ranks, const Floes& start, const std::vector<contact::ImpulseRecord>& records,
                 const Floes& serial, const std::vector<FractureEventRow>& serial_events, const PercussionStats& s,
                 double gap) {
  const double dt = 1.0;
  std::vector<Floes> floes(static_cast<std::size_t>(ranks), start);
  std::vector<Percussion> rank;
  for (int r = 0; r < ranks; ++r) rank.emplace_back(params(), gap);
  std::vector<std::vector<FractureEventRow>> events(static_cast<std::size_t>(ranks));
  PercussionRanks by_rank;  // each rank's checks and seconds, as the summary's parallel.fracture_*
  long narrower = 0;
  for (std::size_t step = 0; step < records.size(); ++step) {
    std::vector<int> owner(start.size());
    for (std::size_t i = 0; i < owner.size(); ++i)
      owner[i] = ranks - 1 - static_cast<int>((i / 4 + step) % static_cast<std::size_t>(ranks));
    const double t = 10.0 * static_cast<double>(step + 1);
    std::vector<PercussionAnalyses> parts;
    for (int r = 0; r < ranks; ++r) {
      const auto ru = static_cast<std::size_t>(r);
      parts.push_back(
          unpack_percussion(pack(rank[ru].analyse(floes[ru], records[step], t, dt, PercussionShare{owner, r, {}}))));
    }
    // In rank order, not floe order: conclude sorts them.
    const PercussionAnalyses all = combine(parts, by_rank);
    for (const FloeInitiation& fi : all.initiations)
      if (fi.split.verdict == SplitVerdict::split && fi.split.gap < gap) ++narrower;
    for (int r = 0; r < ranks; ++r) {
      const auto ru = static_cast<std::size_t>(r);
      rank[ru].conclude(floes[ru], all);
      for (const FractureEventRow& e : rank[ru].take_events()) events[ru].push_back(e);
    }
  }
  CHECK(by_rank.steps == static_cast<long>(records.size()));
  REQUIRE(by_rank.checks.size() == static_cast<std::size_t>(ranks));
  REQUIRE(by_rank.seconds.size() == static_cast<std::size_t>(ranks));
  long summed = 0;
  for (int r = 0; r < ranks; ++r) {
    const auto ru = static_cast<std::size_t>(r);
    CAPTURE(r);
    CHECK(same_floes(floes[ru], serial));
    CHECK(same_events(events[ru], serial_events));
    const PercussionStats& t = rank[ru].stats();
    CHECK(t.counts.checks == s.counts.checks);
    CHECK(t.counts.screened == s.counts.screened);
    CHECK(t.counts.bounded == s.counts.bounded);
    CHECK(t.counts.sustained == s.counts.sustained);
    CHECK(t.counts.cut_short == s.counts.cut_short);
    CHECK(t.counts.loop_steps == s.counts.loop_steps);
    CHECK(t.initiations == s.initiations);
    CHECK(t.splits == s.splits);
    CHECK(t.failed_splits == s.failed_splits);
    CHECK(t.refused_small == s.refused_small);
    CHECK(t.refused_overlap == s.refused_overlap);
    CHECK(t.splits_redone == s.splits_redone);
    CHECK(by_rank.checks[ru] > 0);  // every rank analysed some floes
    CHECK(by_rank.seconds[ru] > 0.0);
    summed += by_rank.checks[ru];
  }
  CHECK(summed == s.counts.checks);
  return narrower;
}

// The serial reference: two steps of check() at t = 10 and 20 s, each on
// its own random record of collisions (record_for, seed 7), kept for the
// shared runs with the events the steps gave.
void check_serially(Floes& serial, Percussion& whole, double dt, std::vector<contact::ImpulseRecord>& records,
                    std::vector<FractureEventRow>& events) {
  std::mt19937_64 rng(7);
  for (int step = 0; step < 2; ++step) {
    records.push_back(record_for(serial, rng));
    whole.check(serial, records.back(), 10.0 * (step + 1), dt);
    for (const FractureEventRow& e : whole.take_events()) events.push_back(e);
  }
}

}  // namespace

TEST_CASE("percussion by owner: the analyses shared by 1, 2 and 3 ranks and concluded on each are the serial check") {
  const double dt = 1.0, gap = 0.01;
  // Serial: two steps of check().
  Floes serial = grid_of_floes();
  Percussion whole(params(), gap);
  std::vector<contact::ImpulseRecord> records;
  std::vector<FractureEventRow> serial_events;
  check_serially(serial, whole, dt, records, serial_events);
  const PercussionStats& s = whole.stats();
  MESSAGE("serial: " << s.counts.checks << " checks, " << s.counts.screened << " screened, " << s.counts.bounded
                     << " bounded, " << s.counts.sustained << " sustained, " << s.initiations << " initiations, "
                     << s.splits << " splits");
  // The case covers every kind of verdict, and splits in both steps.
  REQUIRE(s.counts.checks > 0);
  REQUIRE(s.counts.screened > 0);
  REQUIRE(s.counts.bounded > 0);
  REQUIRE(s.counts.sustained > 0);
  REQUIRE(s.splits >= 2);
  REQUIRE(serial.size() > 30);
  REQUIRE(serial_events.back().time == 20.0);

  for (int ranks = 1; ranks <= 3; ++ranks) {
    CAPTURE(ranks);
    check_ranks(ranks, grid_of_floes(), records, serial, serial_events, s, gap);
  }
}

TEST_CASE("percussion by owner: splits within reach of each other, decided by their owners and again when an earlier "
          "split came near, are the serial splits") {
  // The floes 1 m apart (the neighbours along x, y and the diagonals within
  // a split's reach), the pieces opened by 1.5 m: a full opening pushes a
  // piece into a neighbour, so some splits open less. Floe 8 is moved 1.5 m
  // onto floe 9: the splits near them are refused for overlap. Splits of
  // neighbouring floes in one step: the later one's neighbours changed, its
  // decision is made again in conclude (PercussionStats::splits_redone).
  const double dt = 1.0, gap = 1.5;
  auto floes_near = [] {
    Floes f = grid_of_floes(41.0, 0.0);
    f.state[8].x += 1.5;
    return f;
  };
  Floes serial = floes_near();
  Percussion whole(params(), gap);
  std::vector<contact::ImpulseRecord> records;
  std::vector<FractureEventRow> serial_events;
  check_serially(serial, whole, dt, records, serial_events);
  const PercussionStats& s = whole.stats();
  // The serial loop as it was: every split decided in floe order against
  // the floes as they are when it is reached (conclude decides the
  // undecided ones so). check() must give its floes and events.
  {
    Floes in_order = floes_near();
    Percussion p(params(), gap);
    std::vector<FractureEventRow> events;
    for (std::size_t step = 0; step < records.size(); ++step) {
      PercussionAnalyses a =
          p.analyse(in_order, records[step], 10.0 * static_cast<double>(step + 1), dt, PercussionShare{});
      for (FloeInitiation& fi : a.initiations) fi.split = {};
      p.conclude(in_order, std::move(a));
      for (const FractureEventRow& e : p.take_events()) events.push_back(e);
    }
    CHECK(same_floes(in_order, serial));
    CHECK(same_events(events, serial_events));
    CHECK(p.stats().splits == s.splits);
    CHECK(p.stats().splits_redone == 0);
  }
  MESSAGE("serial: " << s.initiations << " initiations, " << s.splits << " splits, " << s.splits_redone
                     << " decided again, " << s.refused_overlap << " refused for overlap, " << s.refused_small
                     << " for a small piece");
  REQUIRE(s.splits >= 3);
  REQUIRE(s.splits_redone >= 1);
  REQUIRE(s.refused_overlap >= 1);
  // Some splits were kept as their owner decided them.
  REQUIRE(s.splits + s.refused_overlap > s.splits_redone);
  for (int ranks = 1; ranks <= 3; ++ranks) {
    CAPTURE(ranks);
    const long narrower = check_ranks(ranks, floes_near(), records, serial, serial_events, s, gap);
    // Some splits were decided at less than the full opening (at the full
    // one a piece would have met a neighbour).
    CHECK(narrower >= 1);
  }
}

TEST_SUITE_END();
