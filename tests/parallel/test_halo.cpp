// The state held by owner with a halo, its first proof (docs/parallel.md,
// "The state held by owner with a halo (plan)"): the phases that already run
// by place read only the floes a rank would hold. The poison tool (halo_case.hpp) sets
// to NaN the state of every floe a simulated rank should not need, and the
// per-floe data held with it (its mass, inertia, drag, vertices, collision
// shape, reach, drift quadrature, the step's start); each phase, run on the
// poisoned copy, must give the rank's part bit for bit as on the whole state:
//
// - detection by place (parallel::detect_part): the rank holds its strip's
//   floes and the halo band, the floes whose place lies within H + h_j of
//   its strip (h_j = R_j + reach_j + xi/2, H the largest h of the pack),
//   across the periodic seam by the nearest image; the band holds the
//   detection subset's posed floes, and a band of one pad (H only) loses
//   pairs across the cuts: the comparison has teeth;
// - the drift of the rank's floes: its own floes only, and their water
//   velocities reach it from the coupling's owners by the hand-over
//   (parallel::plan_hand_over, the ranks simulated);
// - the collisions at the step's start from the rank's part
//   (parallel::collide_on_part's pieces): the edges from the band (the
//   floes' owners too, which the edges carry), then each share on the
//   members of its step groups its band holds and the floes the routed
//   pairs carry, no owner read.
//
// A NaN read whose only use is a comparison that comes out false either way
// is not seen; every read that changes a result is.
#include <doctest/doctest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <span>
#include <string>
#include <vector>

#include "contact/detection.hpp"
#include "contact/impulse.hpp"
#include "contact/shapes.hpp"
#include "core/pack_generator.hpp"
#include "coupling/drift.hpp"
#include "parallel/collide_share.hpp"
#include "parallel/comm.hpp"
#include "parallel/detect.hpp"
#include "parallel/place.hpp"
#include "tests/parallel/collide_case.hpp"
#include "tests/parallel/halo_case.hpp"
#include "tests/parallel/same_detection.hpp"

TEST_SUITE_BEGIN("mpi");

using namespace floesim;
using test::bits;
using test::same;
using test::same_detection;
using test::same_lists;
using namespace floesim::test;  // the poison tool (halo_case.hpp)

namespace {

// The drift's forcing shared by the drift's proofs: a uniform current and
// wind, and a water velocity per floe (the current and a small field that
// varies floe by floe, so that a floe read in another's place changes the
// answer).
struct DriftCase {
  DriftParams params{1025.0, 5e-3, 1.341, 1.7e-3, 1.4e-4};
  Vec2 current{0.12, -0.05}, wind{8.0, 3.0};
  double dt = 10.0;
  std::vector<Vec2> water;
};

DriftCase drift_case(std::size_t n) {
  DriftCase c;
  c.water.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    const double k = static_cast<double>(i);
    c.water[i] = c.current + Vec2{1e-3 * std::sin(0.1 * k), 1e-3 * std::cos(0.2 * k)};
  }
  return c;
}

}  // namespace

TEST_CASE("detection by place on a rank holding only its strip and halo band is its part of the serial detection") {
  // Over 2, 3 and 7 strips, equal and uneven, in a periodic box (pairs
  // across the seam) and the open plane: rank r's part from the poisoned
  // copy (every floe outside its band NaN: state, shape, reach, mass) equals
  // its part from the whole state field by field, bit for bit, with the
  // held floes' reach, and the parts merged are the serial detection.
  for (const bool periodic : {true, false})
  for (const double speed : {0.5, 2.0}) {
    CAPTURE(periodic);
    CAPTURE(speed);
    const Pack p = moving_pack(7, periodic, speed);
    const std::size_t n = p.floes.size();
    const contact::Detection serial = contact::detect(p.floes, p.shapes, p.detect);
    MESSAGE("serial: " << serial.pairs.size() << " pairs, " << serial.contacts.size() << " contact points, "
                       << serial.witnesses.size() << " witnesses");
    REQUIRE(serial.pairs.size() > 300);
    REQUIRE(serial.contacts.size() > 10);
    REQUIRE(serial.witnesses.size() > 10);
    for (const bool equal : {true, false})
      for (const int ranks : {2, 3, 7}) {
        CAPTURE(equal);
        CAPTURE(ranks);
        parallel::FloeOwners owners(0, ranks, p.detect.domain);
        if (!equal) owners.set_cuts(uneven_cuts(p, ranks));
        owners.assign(p.floes);
        std::vector<contact::Detection> parts;
        std::size_t across = 0, held_total = 0;
        for (const contact::NearPair& q : serial.pairs) across += owners.owner()[q.a] != owners.owner()[q.b] ? 1 : 0;
        CHECK(across > 0);  // pairs whose floes lie in different strips
        for (int r = 0; r < ranks; ++r) {
          CAPTURE(r);
          const contact::Detection whole = parallel::detect_part(owners, r, p.floes, p.shapes, p.detect);
          BandPart b = part_from_band(p, owners, r, false);
          // The band holds every floe the subset poses (the detection's own halo).
          const contact::DetectionSubset subset = parallel::detection_subset(owners, r, p.floes, p.shapes, p.detect);
          CHECK(std::all_of(subset.posed.begin(), subset.posed.end(), [&](std::uint32_t i) { return b.held[i] != 0; }));
          CHECK(same_detection(b.part, whole));
          for (std::size_t i = 0; i < n; ++i)
            if (b.held[i]) REQUIRE(bits(b.part.reach[i], whole.reach[i]));
          held_total += count_held(b.held);
          b.part.reach = serial.reach;  // the merge takes the first part's (poisoned outside its band)
          parts.push_back(std::move(b.part));
        }
        // The bands hold a part of the pack: on 7 strips about a third each.
        MESSAGE(std::string(periodic ? "periodic, " : "open, ") << "speeds up to " << speed << " m/s, " << ranks << " strips"
                                                     << std::string(equal ? "" : " (uneven)") << ": the bands hold " << held_total
                                                     << " floes of " << ranks * n << " (the whole pack on every rank)");
        if (ranks == 7) CHECK(held_total < static_cast<std::size_t>(ranks) * n / 2);
        const contact::Detection merged = parallel::merge(std::move(parts));
        CHECK(same_detection(merged, serial));
      }
  }
}

TEST_CASE("a halo band of one pad (the strip widened by the largest half band alone) loses pairs across the cuts") {
  // The mutation of the band's rule: floe b of a pair lies within h_a + h_b
  // of the strip, not within the largest h alone. With the thin band some
  // rank's part differs from its part on the whole state: the poisoned
  // floes it should have held are not posed, and their pairs are lost.
  std::size_t differ_all = 0, lost_all = 0;
  for (const bool periodic : {true, false})
  for (const double speed : {0.5, 2.0}) {
    CAPTURE(periodic);
    CAPTURE(speed);
    const Pack p = moving_pack(7, periodic, speed);
    std::size_t differ = 0, lost = 0;
    for (const int ranks : {2, 3, 7}) {
      parallel::FloeOwners owners(0, ranks, p.detect.domain);
      owners.assign(p.floes);
      for (int r = 0; r < ranks; ++r) {
        const contact::Detection whole = parallel::detect_part(owners, r, p.floes, p.shapes, p.detect);
        const BandPart thin = part_from_band(p, owners, r, true);
        if (!same_detection(thin.part, whole)) ++differ;
        if (thin.part.pairs.size() < whole.pairs.size()) lost += whole.pairs.size() - thin.part.pairs.size();
      }
    }
    MESSAGE("one pad, " << std::string(periodic ? "periodic" : "open") << ", speeds up to " << speed << " m/s: " << differ
                        << " of 12 parts differ, " << lost << " pairs lost");
    differ_all += differ;
    lost_all += lost;
  }
  CHECK(differ_all > 0);
  CHECK(lost_all > 0);
}

TEST_CASE("the drift of a rank's floes reads only its own floes") {
  // Every floe not owned poisoned (state, mass, inertia, drag, quadrature,
  // the water velocity under it): the owned floes' states after
  // drift_velocities over the rank's list equal the serial drift's bit for
  // bit, and nothing is written to the others.
  const Pack p = moving_pack(5, true);
  const std::size_t n = p.floes.size();
  Floes varied = p.floes;
  for (std::size_t i = 0; i < n; i += 3) varied.ocean_drag[i] = 4e-3 + 1e-5 * static_cast<double>(i % 7);
  const FootprintQuadrature q = build_footprint_quadrature(varied, 1);
  const DriftCase drift = drift_case(n);
  const DriftParams& params = drift.params;
  const Vec2 current = drift.current, wind = drift.wind;
  const double dt = drift.dt;
  const std::vector<Vec2>& water = drift.water;
  for (const bool uniform : {true, false}) {
    CAPTURE(uniform);
    Floes serial = varied;
    drift_velocities(serial, q, params, current, wind, dt, 0, n,
                     uniform ? std::span<const Vec2>{} : std::span<const Vec2>(water));
    for (const int ranks : {2, 3, 7}) {
      CAPTURE(ranks);
      parallel::FloeOwners owners(0, ranks, p.detect.domain);
      owners.assign(varied);
      for (int r = 0; r < ranks; ++r) {
        CAPTURE(r);
        Held held(n, 0);
        for (std::size_t i = 0; i < n; ++i) held[i] = owners.owner()[i] == r ? 1 : 0;
        Floes f = poisoned(varied, held);
        std::vector<Vec2> w = water;
        for (std::size_t i = 0; i < n; ++i)
          if (!held[i]) w[i] = Vec2::Constant(kNaN);
        std::vector<std::uint32_t> mine;
        for (std::size_t i = 0; i < n; ++i)
          if (held[i]) mine.push_back(static_cast<std::uint32_t>(i));
        drift_velocities(f, poisoned(q, held), params, current, wind, dt, mine,
                         uniform ? std::span<const Vec2>{} : std::span<const Vec2>(w));
        bool own = true, others = true;
        for (std::size_t i = 0; i < n; ++i) {
          if (held[i]) own = own && std::memcmp(&f.state[i], &serial.state[i], sizeof(FloeState)) == 0;
          else others = others && all_nan(f.state[i]);
        }
        CHECK(own);
        CHECK(others);
        CHECK(!mine.empty());
      }
    }
  }
}

namespace {

// Communicator::hand_over among simulated ranks: rank r's values[r] hold
// the items with held_by == r; each rank's plan (parallel::plan_hand_over)
// packs its sends in order, the parts are moved as MPI_Alltoallv moves
// them (sender s's part for r, after those of the ranks before s), and
// each rank unpacks what it receives. Returns the items moved.
template <class T>
std::size_t simulated_hand_over(std::vector<std::vector<T>>& values, std::span<const int> held_by,
                                std::span<const int> wanted_by) {
  const int ranks = static_cast<int>(values.size());
  std::vector<parallel::HandOver> plan;
  std::vector<std::vector<std::byte>> out(values.size());
  for (int r = 0; r < ranks; ++r) {
    plan.push_back(parallel::plan_hand_over(held_by, wanted_by, r, ranks, sizeof(T)));
    for (const std::uint32_t i : plan[r].send) {
      const auto* b = reinterpret_cast<const std::byte*>(&values[r][i]);
      out[r].insert(out[r].end(), b, b + sizeof(T));
    }
  }
  std::size_t moved = 0;
  for (int r = 0; r < ranks; ++r) {
    std::vector<std::byte> in;
    for (int s = 0; s < ranks; ++s) {
      std::size_t at = 0;
      for (int q = 0; q < r; ++q) at += plan[s].send_bytes[q];
      REQUIRE(plan[s].send_bytes[r] == plan[r].receive_bytes[s]);
      in.insert(in.end(), out[s].begin() + static_cast<std::ptrdiff_t>(at),
                out[s].begin() + static_cast<std::ptrdiff_t>(at + plan[s].send_bytes[r]));
    }
    REQUIRE(in.size() == plan[r].receive.size() * sizeof(T));
    for (std::size_t k = 0; k < plan[r].receive.size(); ++k)
      std::memcpy(static_cast<void*>(&values[r][plan[r].receive[k]]), in.data() + k * sizeof(T), sizeof(T));
    moved += plan[r].receive.size();
  }
  return moved;
}

}  // namespace

TEST_CASE("the water velocities handed over from the coupling's owners are the drift's own floes' (simulated ranks)") {
  // The coupling's owner of each floe computes its water velocity (the
  // others' are poisoned); Communicator::hand_over's plan gives each floe's
  // to its drift owner when that is another rank; each rank's drift with
  // the water it then holds (and every floe it does not drift poisoned)
  // equals the serial drift bit for bit. The coupling's owners: the drift's
  // (nothing moves, no call), the strips shifted by one rank (as after a
  // move of the slabs the coupling's owners follow one rebuild later), and
  // by index (the implicit step's, a sea not in slabs).
  const Pack p = moving_pack(5, true);
  const std::size_t n = p.floes.size();
  const FootprintQuadrature q = build_footprint_quadrature(p.floes, 1);
  const DriftCase drift = drift_case(n);
  const DriftParams& params = drift.params;
  const Vec2 current = drift.current, wind = drift.wind;
  const double dt = drift.dt;
  const std::vector<Vec2>& water = drift.water;
  Floes serial = p.floes;
  drift_velocities(serial, q, params, current, wind, dt, 0, n, water);
  for (const int ranks : {2, 3, 7}) {
    parallel::FloeOwners owners(0, ranks, p.detect.domain);
    owners.assign(p.floes);
    const std::span<const int> drift_owner = owners.owner();
    for (const int kind : {0, 1, 2}) {
      CAPTURE(ranks);
      CAPTURE(kind);
      std::vector<int> coupling(n);
      for (std::size_t i = 0; i < n; ++i)
        coupling[i] = kind == 0   ? drift_owner[i]
                      : kind == 1 ? (drift_owner[i] + 1) % ranks
                                  : static_cast<int>(i * static_cast<std::size_t>(ranks) / n);
      std::vector<std::vector<Vec2>> held(static_cast<std::size_t>(ranks), std::vector<Vec2>(n, Vec2::Constant(kNaN)));
      for (std::size_t i = 0; i < n; ++i) held[coupling[i]][i] = water[i];
      std::size_t mismatched = 0;
      for (std::size_t i = 0; i < n; ++i) mismatched += coupling[i] != drift_owner[i] ? 1 : 0;
      CHECK(parallel::plan_hand_over(coupling, drift_owner, 0, ranks, sizeof(Vec2)).any == (mismatched > 0));
      CHECK(simulated_hand_over(held, coupling, drift_owner) == mismatched);
      if (kind > 0) CHECK(mismatched > 0);
      for (int r = 0; r < ranks; ++r) {
        CAPTURE(r);
        Held mine_held(n, 0);
        std::vector<std::uint32_t> mine;
        for (std::size_t i = 0; i < n; ++i)
          if (drift_owner[i] == r) {
            mine_held[i] = 1;
            mine.push_back(static_cast<std::uint32_t>(i));
          }
        // Only the floes the rank drifts are read: the rest of what it holds poisoned too.
        std::vector<Vec2> w = held[r];
        for (std::size_t i = 0; i < n; ++i)
          if (!mine_held[i]) w[i] = Vec2::Constant(kNaN);
        Floes f = poisoned(p.floes, mine_held);
        drift_velocities(f, poisoned(q, mine_held), params, current, wind, dt, mine, w);
        bool own = true;
        for (const std::uint32_t i : mine) own = own && std::memcmp(&f.state[i], &serial.state[i], sizeof(FloeState)) == 0;
        CHECK(own);
      }
    }
  }
}

namespace {

// The step-start collisions from each simulated rank's part, each rank
// holding only what the plan gives it: its band for its part of the
// detection and its pairs' edges (compared with the edges on the whole
// state), the owners (`owner`: the strips shifted by `shift` ranks) of its
// band's floes only (-1 elsewhere), which the edges carry; then, for its
// share, the members of its step groups that its band holds and the floes
// the routed pairs carry (W^-, the step's start, mass, inertia: through
// their bytes), every other floe poisoned, and no owner at all. The shares'
// parts combined into W^- (clean) are returned with the counts.
struct PoisonedCollide {
  Floes floes;
  contact::CollisionStats stats;
  std::size_t speculative = 0;
  bool combined = false;
  bool parts_equal = true, edges_equal = true;
  std::size_t held_by_shares = 0;  // the members and obstacles the shares held, summed over the ranks
  std::size_t fetched = 0;         // of those, members beyond the share's band, held from the routed floes
  std::size_t routed = 0;          // floes carried with routed pairs, summed over the receivers
};
PoisonedCollide collide_poisoned(const test::CollideCase& c, int ranks, int shift, contact::ImpulseRecord* merged) {
  PoisonedCollide out;
  const std::size_t n = c.floes.size();
  Pack p;  // the case's detection set-up (test::rows_of_four: reach 6 m)
  p.floes = c.floes;
  p.shapes = contact::build_collision_shapes(c.floes);
  p.detect.domain = c.domain;
  p.detect.horizon = c.dt;
  p.detect.reach.assign(n, 6.0);
  parallel::FloeOwners strips(0, ranks, c.domain);
  strips.assign(c.floes);
  std::vector<int> owner(strips.owner().begin(), strips.owner().end());
  for (int& o : owner) o = (o + shift) % ranks;
  // Each rank: its part and edges from its band (the owners of its band only).
  std::vector<contact::Detection> part(static_cast<std::size_t>(ranks));
  std::vector<Floes> band_floes;
  std::vector<std::vector<FloeState>> band_start;
  std::vector<Held> band;
  std::vector<contact::GroupEdge> edges;
  for (int r = 0; r < ranks; ++r) {
    const contact::Detection whole_part =
        parallel::select_pairs(c.detection, [&](const contact::NearPair& q) { return strips.owner()[q.a] == r; });
    const BandPart b = part_from_band(p, strips, r, false);
    out.parts_equal = out.parts_equal && same_detection(b.part, whole_part);
    part[static_cast<std::size_t>(r)] = b.part;
    band.push_back(b.held);
    band_floes.push_back(poisoned(c.floes, b.held));
    band_start.push_back(poisoned(c.start, b.held));
    std::vector<int> band_owner(n, -1);
    for (std::size_t i = 0; i < n; ++i)
      if (b.held[i]) band_owner[i] = owner[i];
    const std::vector<contact::GroupEdge> e =
        contact::group_edges(band_floes.back(), band_start.back(), b.part, c.dt, c.options, band_owner);
    out.edges_equal =
        out.edges_equal && same_lists(e, contact::group_edges(c.floes, c.start, whole_part, c.dt, c.options, owner));
    edges.insert(edges.end(), e.begin(), e.end());
  }
  const contact::StepGroups groups = contact::step_groups(c.floes, edges, c.options);
  // The pairs each rank sends and the floes they carry, through their bytes.
  std::vector<std::vector<contact::Detection>> to(static_cast<std::size_t>(ranks));
  std::vector<std::vector<parallel::RoutedFloes>> carried(static_cast<std::size_t>(ranks));
  for (int r = 0; r < ranks; ++r) {
    const auto ru = static_cast<std::size_t>(r);
    to[ru] = parallel::pairs_for_groups(band_floes[ru], part[ru], groups, ranks, r, c.options.collision_distance);
    for (const contact::Detection& d : to[ru])
      carried[ru].push_back(parallel::unpack_routed_floes(
          parallel::pack(parallel::routed_floes(band_floes[ru], band_start[ru], d))));
  }
  // Each share on its band's members and the routed floes only.
  std::vector<parallel::CollidePart> parts;
  contact::ImpulseRecord unused;
  contact::ImpulseOptions options = c.options;
  if (merged) options.record = &unused;
  const std::vector<int> no_owner(n, -1);  // with the groups given, the share reads no owner
  for (int s = 0; s < ranks; ++s) {
    const auto su = static_cast<std::size_t>(s);
    std::vector<contact::Detection> held_pairs{part[su]};
    for (int r = 0; r < ranks; ++r)
      if (!to[static_cast<std::size_t>(r)][su].pairs.empty()) held_pairs.push_back(to[static_cast<std::size_t>(r)][su]);
    const contact::Detection local = parallel::merge(std::move(held_pairs));
    Held members(n, 0), held(n, 0);
    for (std::size_t i = 0; i < n; ++i) {
      members[i] = c.floes.is_static[i] || groups.mine(static_cast<std::uint32_t>(i), s) ? 1 : 0;
      held[i] = members[i] && band[su][i];
    }
    Floes mine = poisoned(c.floes, held);
    std::vector<FloeState> start = poisoned(c.start, held);
    Held routed(n, 0);
    for (int r = 0; r < ranks; ++r) {
      const parallel::RoutedFloes& f = carried[static_cast<std::size_t>(r)][su];
      parallel::hold(f, mine, start);
      for (const std::uint32_t i : f.floe) routed[i] = 1;
      out.routed += f.floe.size();
    }
    for (std::size_t i = 0; i < n; ++i) {
      out.held_by_shares += members[i];
      out.fetched += members[i] && !c.floes.is_static[i] && !band[su][i] ? 1 : 0;
    }
    parts.push_back(parallel::unpack_collide_part(
        parallel::pack(parallel::run_collide_share(mine, start, local, c.dt, options, no_owner, s, &groups))));
  }
  out.floes = c.floes;  // W^-, whole and clean: each part's moved floes take its states
  out.combined = parallel::combine_collide_parts(parts, out.floes, out.stats, out.speculative, merged);
  return out;
}

}  // namespace

TEST_CASE("the step-start collisions read the band for the edges and only the members of the rank's step groups") {
  // The rows of four (one step group a row, joined by a speculative
  // contact), with and without the impulse record (jams of two solved at the
  // step's start or not), over 2, 3 and 7 strips, the groups' owners the
  // strips or shifted by one rank (every group's members then lie on other
  // ranks' strips: the owner fetches those beyond its band with the routed
  // pairs). The owners are read from each rank's band only (the edges carry
  // them); a share holds its band's members and the routed floes. The
  // combined states equal the serial solve by memcmp, with the counts, the
  // speculative contacts' count and the record.
  std::size_t fetched = 0;
  for (const bool jams : {false, true}) {
    CAPTURE(jams);
    const test::RecordedRows r = test::recorded_rows_of_four(jams);
    const test::CollideCase& c = r.c;
    for (const int ranks : {2, 3, 7})
      for (const int shift : {0, 1}) {
        CAPTURE(ranks);
        CAPTURE(shift);
        contact::ImpulseRecord merged;
        merged.events = 3;
        const PoisonedCollide p = collide_poisoned(c, ranks, shift, &merged);
        CHECK(p.parts_equal);
        CHECK(p.edges_equal);
        REQUIRE(p.combined);
        CHECK(same_states(p.floes.state, r.floes.state));
        CHECK(test::same_stats(p.stats, r.stats));
        CHECK(test::same_record(merged, r.record));
        // The shares' members and obstacles: the 256 floes of the 64 rows, once.
        CHECK(p.held_by_shares == c.floes.size());
        MESSAGE(std::string(jams ? "jams, " : "") << ranks << " strips, shift " << shift << ": " << p.routed
                                       << " floes routed, " << p.fetched << " members beyond the share's band");
        fetched += p.fetched;
      }
  }
  // Some members lie beyond their share's band and come from the routed floes only.
  CHECK(fetched > 0);
}

TEST_SUITE_END();
