// The fracture checks by owner (coupling/percussion.hpp, docs/parallel.md
// "The fracture checks by owner"): the loaded floes' analyses split among
// 1, 2 and 3 simulated ranks, each with its own Percussion (its own models),
// their counts and initiations exchanged and concluded on every rank, give
// the serial check's floes (to the bit), events and counts. Two steps, the
// owners changed between them: a floe analysed on a rank that did not build
// its model in the first step gets a new model, which must give the bits of
// the serial run's kept one.
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

// A 6 x 5 grid of 40 m x 30 m floes 80 m apart (no two near: a split's
// overlap checks pass), turned by various yaws.
Floes grid_of_floes() {
  Floes floes;
  for (int k = 0; k < 30; ++k) {
    FloeInput in;
    const double x = 80.0 * (k % 6), y = 80.0 * (k / 6);
    in.vertices = {{x, y}, {x + 40.0, y}, {x + 40.0, y + 30.0}, {x, y + 30.0}};
    const std::size_t i = floes.add(make_floe_shape(in), in);
    floes.state[i].yaw = 0.1 * k;
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

}  // namespace

TEST_CASE("percussion by owner: the analyses shared by 1, 2 and 3 ranks and concluded on each are the serial check") {
  const double dt = 1.0, gap = 0.01;
  // Serial: two steps of check().
  Floes serial = grid_of_floes();
  Percussion whole(params(), gap);
  std::vector<contact::ImpulseRecord> records;
  std::vector<FractureEventRow> serial_events;
  std::mt19937_64 rng(7);
  for (int step = 0; step < 2; ++step) {
    records.push_back(record_for(serial, rng));
    whole.check(serial, records.back(), 10.0 * (step + 1), dt);
    for (const FractureEventRow& e : whole.take_events()) serial_events.push_back(e);
  }
  const PercussionStats& s = whole.stats();
  MESSAGE("serial: " << s.checks << " checks, " << s.screened << " screened, " << s.bounded << " bounded, "
                     << s.sustained << " sustained, " << s.initiations << " initiations, " << s.splits << " splits");
  // The case covers every kind of verdict, and splits in both steps.
  REQUIRE(s.checks > 0);
  REQUIRE(s.screened > 0);
  REQUIRE(s.bounded > 0);
  REQUIRE(s.sustained > 0);
  REQUIRE(s.splits >= 2);
  REQUIRE(serial.size() > 30);
  REQUIRE(serial_events.back().time == 20.0);

  for (int ranks = 1; ranks <= 3; ++ranks) {
    CAPTURE(ranks);
    std::vector<Floes> floes(static_cast<std::size_t>(ranks), grid_of_floes());
    std::vector<Percussion> rank;
    for (int r = 0; r < ranks; ++r) rank.emplace_back(params(), gap);
    std::vector<std::vector<FractureEventRow>> events(static_cast<std::size_t>(ranks));
    std::vector<long> checks(static_cast<std::size_t>(ranks), 0);
    for (int step = 0; step < 2; ++step) {
      // Owners by blocks of four floes, the last ranks first (so that the
      // ranks' initiations are not in floe order), moved by one block in the
      // second step (floes past the owners' end, the pieces of the first
      // step, are rank 0's).
      std::vector<int> owner(30);
      for (std::size_t i = 0; i < owner.size(); ++i)
        owner[i] = ranks - 1 - static_cast<int>((i / 4 + static_cast<std::size_t>(step)) % static_cast<std::size_t>(ranks));
      PercussionCounts counts;
      std::vector<FloeInitiation> all;
      std::vector<PercussionAnalyses> parts;
      for (int r = 0; r < ranks; ++r) {
        const auto ru = static_cast<std::size_t>(r);
        parts.push_back(unpack_percussion(
            pack(rank[ru].analyse(floes[ru], records[static_cast<std::size_t>(step)], 10.0 * (step + 1), dt,
                                  PercussionShare{owner, r}))));
      }
      for (int r = 0; r < ranks; ++r) {
        const PercussionAnalyses& p = parts[static_cast<std::size_t>(r)];
        checks[static_cast<std::size_t>(r)] += p.counts.checks;
        counts += p.counts;
        // In rank order, not floe order: conclude sorts them.
        all.insert(all.end(), p.initiations.begin(), p.initiations.end());
      }
      for (int r = 0; r < ranks; ++r) {
        const auto ru = static_cast<std::size_t>(r);
        rank[ru].conclude(floes[ru], counts, all);
        for (const FractureEventRow& e : rank[ru].take_events()) events[ru].push_back(e);
      }
    }
    long summed = 0;
    for (int r = 0; r < ranks; ++r) {
      const auto ru = static_cast<std::size_t>(r);
      CAPTURE(r);
      CHECK(same_floes(floes[ru], serial));
      CHECK(same_events(events[ru], serial_events));
      const PercussionStats& t = rank[ru].stats();
      CHECK(t.checks == s.checks);
      CHECK(t.screened == s.screened);
      CHECK(t.bounded == s.bounded);
      CHECK(t.sustained == s.sustained);
      CHECK(t.cut_short == s.cut_short);
      CHECK(t.loop_steps == s.loop_steps);
      CHECK(t.initiations == s.initiations);
      CHECK(t.splits == s.splits);
      CHECK(t.failed_splits == s.failed_splits);
      CHECK(checks[ru] > 0);  // every rank analysed some floes
      summed += checks[ru];
    }
    CHECK(summed == s.checks);
  }
}

TEST_SUITE_END();
