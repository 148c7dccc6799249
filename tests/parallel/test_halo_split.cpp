// The state held by owner with a halo, piece 4 (docs/parallel.md, "The
// pieces, in landing order"): a split read from the band, and the detection
// after the splits by place. With the poison tool (halo_case.hpp) every floe
// a simulated rank should not hold is NaN:
//
// - a split's decision (Percussion::decide_split), made by the analysing
//   share, the owner of the cracked floe, reads the floe and its neighbours
//   within R_i + R_j + gap: on the copy poisoned outside the owner's band it
//   is the decision on the whole state, bit for bit (verdict and opening);
//   the decisions made so, concluded in floe order as every rank does, give
//   the serial floes and events;
// - a decision taken again when concluding (an earlier split of the step came
//   within reach) reads the owner's band and the pieces of the splits whose
//   parent it holds: each crack's decision at its turn, on that copy, is the
//   decision on the whole state;
// - a split's pieces (Percussion::conclude with the decision) are built from
//   the parent alone: on the owner's poisoned copy they are the pieces made on
//   the whole state, at the same indices with the same ids, and no floe
//   outside the band is written;
// - the detection after the splits by place: each rank's part from its band
//   (the pieces in it) is its part from the whole state, and the parts
//   merged are the serial detection of the split pack.
//
// The mutation, named: decisions made on the strip alone (no band) differ.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include "contact/detection.hpp"
#include "contact/shapes.hpp"
#include "coupling/percussion.hpp"
#include "parallel/detect.hpp"
#include "parallel/place.hpp"
#include "tests/parallel/halo_case.hpp"
#include "tests/parallel/same_detection.hpp"

TEST_SUITE_BEGIN("mpi");

using namespace floesim;
using namespace floesim::test;

namespace {

// The bench's percussion pack's split settings (bench/mpi_pack.py
// --percussion). The opening is wider than a run's (Simulation: 0.1 xi)
// so that the neighbours, a few metres apart in this pack, narrow or refuse
// some openings; the band holds a floe's neighbours for any opening up to
// 2 xi (R_i + R_j + gap <= H + h_j, since reach_i >= xi).
FractureParams split_params() {
  FractureParams f;
  f.enabled = true;
  f.split = true;
  f.mesh_size = 20.0;
  f.min_fragment_area = 400.0;
  return f;
}
double opening(const Pack& p) { return 0.5 * p.detect.collision_distance; }
// Dense, so that the neighbours narrow or refuse some openings.
constexpr double kConcentration = 0.9;

// Through cracks in every third dynamic floe, in floe order: through the
// centroid (two halves, their opening often narrowed or refused by the
// neighbours, min_gap 0.05 m apart) or near an edge (a piece too small).
std::vector<FloeInitiation> cracks(const Floes& floes) {
  std::vector<FloeInitiation> out;
  for (std::size_t i = 0; i < floes.size(); i += 3) {
    if (floes.is_static[i]) continue;
    FloeInitiation fi;
    fi.floe = i;
    fi.through = 1;
    const Vec2 at = i % 2 ? Vec2(0.8 * floes.vertices(i)[0]) : Vec2::Zero();
    fi.point_x = at.x();
    fi.point_y = at.y();
    fi.direction = 0.37 * static_cast<double>(i);
    fi.event.floe = static_cast<double>(floes.id[i]);
    out.push_back(fi);
  }
  return out;
}

template <class T>
bool same_bytes(const std::vector<T>& a, const std::vector<T>& b) {
  return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0);
}
// Every per-floe array, bit for bit.
bool same_floes(const Floes& a, const Floes& b) {
  return a.size() == b.size() && a.ids_issued == b.ids_issued && same_bytes(a.id, b.id) &&
         same_bytes(a.offsets, b.offsets) && same_bytes(a.body, b.body) && same_bytes(a.state, b.state) &&
         same_bytes(a.mass, b.mass) && same_bytes(a.area, b.area) && same_bytes(a.inertia_z, b.inertia_z) &&
         same_bytes(a.thickness, b.thickness) && same_bytes(a.density, b.density) &&
         same_bytes(a.ocean_drag, b.ocean_drag) && same_bytes(a.is_static, b.is_static);
}
// Floe i of a and floe j of b, bit for bit.
bool same_floe(const Floes& a, std::size_t i, const Floes& b, std::size_t j) {
  const auto va = a.vertices(i), vb = b.vertices(j);
  return a.id[i] == b.id[j] && va.size() == vb.size() &&
         std::memcmp(va.data(), vb.data(), va.size() * sizeof(Vec2)) == 0 &&
         std::memcmp(&a.state[i], &b.state[j], sizeof(FloeState)) == 0 && bits(a.mass[i], b.mass[j]) &&
         bits(a.area[i], b.area[j]) && bits(a.inertia_z[i], b.inertia_z[j]);
}
bool same_decision(const SplitDecision& a, const SplitDecision& b) {
  return a.verdict == b.verdict && bits(a.gap, b.gap);
}
bool same_events(const std::vector<FractureEventRow>& a, const std::vector<FractureEventRow>& b) {
  return same_bytes(a, b);
}

PercussionAnalyses analyses_of(std::vector<FloeInitiation> initiations) {
  PercussionAnalyses all;
  all.loaded = true;
  all.initiations = std::move(initiations);
  return all;
}

// The pack after the splits as a detection case: its shapes, and the reach
// as moving_pack gives it (dt 10 s, speeds up to 0.5 m/s).
Pack split_pack(const Pack& before, const Floes& floes) {
  Pack p = before;
  p.floes = floes;
  p.shapes = contact::build_collision_shapes(floes);
  p.detect.reach.assign(floes.size(), 0.0);
  for (std::size_t i = 0; i < floes.size(); ++i) {
    const FloeState& s = floes.state[i];
    p.detect.reach[i] = 10.0 * (1.5 * (std::hypot(s.vx, s.vy) + std::abs(s.yaw_rate) * p.shapes.radius[i]) + 0.25) +
                        p.detect.collision_distance;
  }
  return p;
}

}  // namespace

TEST_CASE("a split decided and built by its floe's owner reads only the owner's halo band") {
  // The 400-floe pack, periodic and open, over 2, 3 and 7 strips of equal
  // counts: each crack's decision on the owner's poisoned copy equals the
  // decision on the whole state; concluded in floe order, those decisions
  // give the serial floes (every array, bit for bit: indices, ids, shapes,
  // states) and events; each split's pieces built on the owner's poisoned
  // copy are the pieces built on the whole state, and the copy's floes
  // outside the band stay NaN.
  for (const bool periodic : {true, false}) {
    CAPTURE(periodic);
    const Pack p = moving_pack(11, periodic, 0.5, kConcentration);
    const std::size_t n = p.floes.size();
    const std::vector<FloeInitiation> initiations = cracks(p.floes);
    // The serial run: each split decided against the floes the step ended
    // with (analyse), then concluded in floe order.
    Percussion serial_percussion(split_params(), opening(p));
    std::vector<FloeInitiation> decided = initiations;
    for (FloeInitiation& fi : decided) fi.split = serial_percussion.decide_split(p.floes, fi.floe, fi);
    Floes serial = p.floes;
    REQUIRE(serial_percussion.conclude(serial, analyses_of(decided)));
    const std::vector<FractureEventRow> serial_events = serial_percussion.take_events();
    const PercussionStats& st = serial_percussion.stats();
    MESSAGE(std::string(periodic ? "periodic" : "open") << ": " << initiations.size() << " cracks, " << st.splits << " splits, "
                                             << st.refused_overlap << " refused by a neighbour, " << st.refused_small
                                             << " a piece too small, " << st.splits_redone
                                             << " decided again in conclude; " << serial.size() << " floes after");
    REQUIRE(st.splits > 10);
    REQUIRE(st.refused_small > 0);
    std::size_t narrowed = 0;
    for (const FloeInitiation& fi : decided)
      if (fi.split.verdict == SplitVerdict::refused_overlap ||
          (fi.split.verdict == SplitVerdict::split && fi.split.gap < opening(p)))
        ++narrowed;
    MESSAGE("decisions the neighbours changed (a narrower opening, or refused): " << narrowed);
    REQUIRE(narrowed > 0);
    for (const int ranks : {2, 3, 7}) {
      CAPTURE(ranks);
      parallel::FloeOwners owners(0, ranks, p.detect.domain);
      owners.assign(p.floes);
      std::vector<Held> band;
      std::vector<Floes> held_floes;
      for (int r = 0; r < ranks; ++r) {
        band.push_back(halo_band(owners, r, p.floes, p.shapes, p.detect));
        held_floes.push_back(poisoned(p.floes, band.back()));
      }
      // The decisions by owner, on the band.
      std::vector<FloeInitiation> by_owner = initiations;
      bool decisions = true;
      std::size_t across = 0;  // decisions whose neighbours lie in another strip
      Percussion share(split_params(), opening(p));
      for (std::size_t k = 0; k < by_owner.size(); ++k) {
        FloeInitiation& fi = by_owner[k];
        const int r = owners.owner()[fi.floe];
        fi.split = share.decide_split(held_floes[static_cast<std::size_t>(r)], fi.floe, fi);
        decisions = decisions && same_decision(fi.split, decided[k].split);
        for (std::size_t j = 0; j < n; ++j)
          if (owners.owner()[j] != r &&
              std::hypot(p.floes.state[j].x - p.floes.state[fi.floe].x, p.floes.state[j].y - p.floes.state[fi.floe].y) <=
                  p.shapes.radius[fi.floe] + p.shapes.radius[j] + opening(p)) {
            ++across;
            break;
          }
      }
      CHECK(decisions);
      CHECK(across > 0);
      // Every rank concludes on the gathered initiations, in floe order.
      Percussion concluding(split_params(), opening(p));
      Floes combined = p.floes;
      concluding.conclude(combined, analyses_of(by_owner));
      CHECK(same_floes(combined, serial));
      CHECK(same_events(concluding.take_events(), serial_events));
      // Each split's pieces built where the parent is held: on its owner's
      // copy (a split alone: the pieces at n and the next id).
      bool pieces = true, untouched = true;
      std::size_t built = 0;
      for (const FloeInitiation& fi : by_owner) {
        if (fi.split.verdict != SplitVerdict::split) continue;
        const int r = owners.owner()[fi.floe];
        Floes on_band = held_floes[static_cast<std::size_t>(r)], whole = p.floes;
        Percussion a(split_params(), opening(p)), b(split_params(), opening(p));
        REQUIRE(a.conclude(on_band, analyses_of({fi})));
        REQUIRE(b.conclude(whole, analyses_of({fi})));
        pieces = pieces && on_band.size() == n + 1 && whole.size() == n + 1 && on_band.ids_issued == whole.ids_issued &&
                 same_bytes(on_band.id, whole.id) && same_floe(on_band, fi.floe, whole, fi.floe) &&
                 same_floe(on_band, n, whole, n) && same_events(a.take_events(), b.take_events());
        for (std::size_t j = 0; j < n; ++j)
          if (!band[static_cast<std::size_t>(r)][j]) untouched = untouched && all_nan(on_band.state[j]);
        ++built;
      }
      CHECK(built == static_cast<std::size_t>(st.splits));
      CHECK(pieces);
      CHECK(untouched);
    }
  }
}

TEST_CASE("a split decided again when concluding reads only its owner's band and the pieces of the parents it holds") {
  // Percussion::conclude decides a split again against the floes as they
  // are at its turn (an earlier split of the step came within reach of
  // it). Each crack's decision at its turn in the serial conclusion (the
  // floes after the splits of the cracks before it, in floe order), made on
  // its owner's copy poisoned outside the owner's band (at the step's end)
  // and the pieces of the splits whose parent the band holds, equals the
  // decision on the whole state, bit for bit.
  for (const bool periodic : {true, false}) {
    CAPTURE(periodic);
    const Pack p = moving_pack(11, periodic, 0.5, kConcentration);
    const std::size_t n = p.floes.size();
    Percussion share(split_params(), opening(p));
    std::vector<FloeInitiation> decided = cracks(p.floes);
    for (FloeInitiation& fi : decided) fi.split = share.decide_split(p.floes, fi.floe, fi);
    // The floes at each crack's turn, and the parents of the splits before
    // it in order (the m-th split's second piece is floe n + m).
    std::vector<Floes> at_turn;
    std::vector<std::size_t> parents;
    std::vector<std::size_t> parents_before;  // per crack: how many of `parents` precede it
    {
      Percussion all(split_params(), opening(p));
      Floes whole = p.floes;
      all.conclude(whole, analyses_of(decided));
      const std::vector<FractureEventRow> events = all.take_events();
      REQUIRE(events.size() == decided.size());
      for (std::size_t k = 0; k < decided.size(); ++k) {
        Percussion prefix(split_params(), opening(p));
        Floes f = p.floes;
        prefix.conclude(f, analyses_of(std::vector<FloeInitiation>(decided.begin(), decided.begin() + static_cast<std::ptrdiff_t>(k))));
        at_turn.push_back(std::move(f));
        parents_before.push_back(parents.size());
        if (events[k].piece_a >= 0.0) parents.push_back(decided[k].floe);
      }
    }
    std::size_t changed = 0;  // decisions at their turn other than at the step's end
    for (std::size_t k = 0; k < decided.size(); ++k)
      if (!same_decision(share.decide_split(at_turn[k], decided[k].floe, decided[k]), decided[k].split)) ++changed;
    MESSAGE(std::string(periodic ? "periodic" : "open") << ": " << changed << " of " << decided.size()
                                                        << " decisions change by the earlier splits of the step");
    REQUIRE(changed > 0);
    for (const int ranks : {2, 3, 7}) {
      CAPTURE(ranks);
      parallel::FloeOwners owners(0, ranks, p.detect.domain);
      owners.assign(p.floes);
      std::vector<Held> band;
      for (int r = 0; r < ranks; ++r) band.push_back(halo_band(owners, r, p.floes, p.shapes, p.detect));
      bool decisions = true;
      for (std::size_t k = 0; k < decided.size(); ++k) {
        const FloeInitiation& fi = decided[k];
        const Held& b = band[static_cast<std::size_t>(owners.owner()[fi.floe])];
        const Floes& f = at_turn[k];
        Held held(f.size(), 0);
        for (std::size_t j = 0; j < n; ++j) held[j] = b[j];
        for (std::size_t m = 0; m < parents_before[k]; ++m) held[n + m] = b[parents[m]];
        decisions = decisions && same_decision(share.decide_split(poisoned(f, held), fi.floe, fi),
                                               share.decide_split(f, fi.floe, fi));
      }
      CHECK(decisions);
    }
  }
}

TEST_CASE("the detection after the splits by place: each rank's part from its band is its part of the serial detection") {
  // The pack split as above (the serial conclude), its reaches as
  // set_reach gives them: over 2, 3 and 7 strips of equal counts, rank r's
  // part from the copy poisoned outside its band equals its part from the
  // whole state, and the parts merged are the serial detection. Pairs with
  // a piece (index n or more, appended by a split) are among them.
  for (const bool periodic : {true, false}) {
    CAPTURE(periodic);
    const Pack before = moving_pack(11, periodic, 0.5, kConcentration);
    Percussion percussion(split_params(), opening(before));
    std::vector<FloeInitiation> decided = cracks(before.floes);
    for (FloeInitiation& fi : decided) fi.split = percussion.decide_split(before.floes, fi.floe, fi);
    Floes split = before.floes;
    REQUIRE(percussion.conclude(split, analyses_of(decided)));
    const Pack p = split_pack(before, split);
    const contact::Detection serial = contact::detect(p.floes, p.shapes, p.detect);
    std::size_t with_piece = 0;
    for (const contact::NearPair& q : serial.pairs)
      with_piece += q.a >= before.floes.size() || q.b >= before.floes.size() ? 1 : 0;
    MESSAGE(std::string(periodic ? "periodic" : "open") << ", after the splits: " << p.floes.size() << " floes, "
                                             << serial.pairs.size() << " pairs, " << with_piece << " with a piece");
    REQUIRE(with_piece > 0);
    for (const int ranks : {2, 3, 7}) {
      CAPTURE(ranks);
      parallel::FloeOwners owners(0, ranks, p.detect.domain);
      owners.assign(p.floes);
      std::vector<contact::Detection> parts;
      for (int r = 0; r < ranks; ++r) {
        CAPTURE(r);
        const contact::Detection whole = parallel::detect_part(owners, r, p.floes, p.shapes, p.detect);
        BandPart b = part_from_band(p, owners, r, false);
        CHECK(same_detection(b.part, whole));
        b.part.reach = serial.reach;  // the merge takes the first part's (poisoned outside its band)
        parts.push_back(std::move(b.part));
      }
      CHECK(same_detection(parallel::merge(std::move(parts)), serial));
    }
  }
}

TEST_CASE("a split decided on the strip alone (no band) reads floes it does not hold") {
  // The mutation: the owner holds its strip's floes only. A crack near a cut
  // then misses its neighbours across it (NaN places compare false), and its
  // decision differs from the decision on the whole state.
  std::size_t differ = 0, decided = 0;
  for (const bool periodic : {true, false}) {
    const Pack p = moving_pack(11, periodic, 0.5, kConcentration);
    Percussion percussion(split_params(), opening(p));
    for (const int ranks : {2, 3, 7}) {
      parallel::FloeOwners owners(0, ranks, p.detect.domain);
      owners.assign(p.floes);
      std::vector<Floes> strip_floes;
      for (int r = 0; r < ranks; ++r) {
        Held strip(p.floes.size(), 0);
        for (std::size_t i = 0; i < p.floes.size(); ++i) strip[i] = owners.owner()[i] == r ? 1 : 0;
        strip_floes.push_back(poisoned(p.floes, strip));
      }
      for (const FloeInitiation& fi : cracks(p.floes)) {
        const int r = owners.owner()[fi.floe];
        ++decided;
        if (!same_decision(percussion.decide_split(strip_floes[static_cast<std::size_t>(r)], fi.floe, fi),
                           percussion.decide_split(p.floes, fi.floe, fi)))
          ++differ;
      }
    }
  }
  MESSAGE("the strip alone: " << differ << " of " << decided << " decisions differ");
  CHECK(differ > 0);
}

TEST_CASE("the owners after the splits, the pieces' from their places and the others' from their owners, are assign's") {
  // Simulation::percussion and detect_in_place on several ranks (docs/
  // parallel.md, "The split step's owners and gather by holder (split28)"),
  // on simulated ranks. Each rank's owners are assigned at the last
  // detection's places (the pack); the floes then split (the serial
  // conclude) and move (60 s at their velocities, so that some leave their
  // strips and some pieces land in another strip than their parent's). Each rank owns the pieces (FloeOwners::place_pieces) on a
  // copy in which only the split parents' indices and the appended pieces
  // are not NaN, then announces its own floes leaving its strip from a copy
  // in which only its own floes are not NaN (leaving), and every rank
  // applies every rank's notices (take_leaving, as migrate). Checked: every
  // rank's owner array and own floes are assign()'s over every floe's place
  // after the splits, entry for entry. Strips of equal counts, uneven, and
  // the sea's slabs (periodic box), on 2, 3 and 7 ranks.
  // Counted, that the case reaches both rules: the pieces whose owner by
  // place is another rank than their parent's (the leave notices would
  // carry them if they kept their parent's owner) and the unsplit floes'
  // notices. The mutation it names: place_pieces setting the owners but
  // leaving the own floes (mine()) as they were.
  std::size_t across = 0, notices = 0;
  for (const bool periodic : {true, false}) {
    CAPTURE(periodic);
    const Pack p = moving_pack(11, periodic, 0.5, kConcentration);
    const std::size_t n = p.floes.size();
    const contact::Domain& box = p.detect.domain;
    Floes after = p.floes;
    Percussion percussion(split_params(), opening(p));
    std::vector<FloeInitiation> decided = cracks(after);
    for (FloeInitiation& fi : decided) fi.split = percussion.decide_split(after, fi.floe, fi);
    std::vector<std::uint32_t> parents;
    REQUIRE(percussion.conclude(after, analyses_of(decided), &parents));
    for (FloeState& s : after.state) {
      s.x += 60.0 * s.vx;
      s.y += 60.0 * s.vy;
      if (!box.periodic) continue;
      s.x = box.xmin + std::fmod(std::fmod(s.x - box.xmin, box.width()) + box.width(), box.width());
      s.y = box.ymin + std::fmod(std::fmod(s.y - box.ymin, box.height()) + box.height(), box.height());
    }
    REQUIRE(after.size() == n + parents.size());
    REQUIRE(std::is_sorted(parents.begin(), parents.end()));
    Held pieces(after.size(), 0);
    for (const std::uint32_t i : parents) pieces[i] = 1;
    for (std::size_t j = n; j < after.size(); ++j) pieces[j] = 1;
    const Floes only_pieces = poisoned(after, pieces);
    for (const Strips kind : {Strips::equal, Strips::uneven, Strips::slabs}) {
      if (kind == Strips::slabs && !(periodic && p.window[2] == 0.0)) continue;
      for (const int ranks : {2, 3, 7}) {
        CAPTURE(strips_name(kind));
        CAPTURE(ranks);
        const parallel::FloeOwners like = owners_of(p, ranks, kind);
        const auto owners_on = [&](int rank, const Floes& floes) {
          parallel::FloeOwners o(rank, ranks, box);
          if (like.has_slabs()) o.set_slabs(like.slabs());
          else o.set_cuts(like.cuts());
          o.assign(floes);
          return o;
        };
        std::vector<parallel::FloeOwners> by_own;
        std::vector<std::vector<parallel::LeaveNotice>> sent;
        for (int r = 0; r < ranks; ++r) {
          parallel::FloeOwners o = owners_on(r, p.floes);
          o.place_pieces(only_pieces, parents);
          REQUIRE(o.assigned_for(after));
          Held own(after.size(), 0);
          for (const std::uint32_t j : o.mine()) own[j] = 1;
          sent.push_back(o.leaving(r, poisoned(after, own)));
          notices += sent.back().size();
          by_own.push_back(std::move(o));
        }
        for (int r = 0; r < ranks; ++r) {
          CAPTURE(r);
          parallel::FloeOwners& o = by_own[static_cast<std::size_t>(r)];
          for (int s = 0; s < ranks; ++s) o.take_leaving(sent[static_cast<std::size_t>(s)]);
          const parallel::FloeOwners whole = owners_on(r, after);
          CHECK(std::ranges::equal(o.owner(), whole.owner()));
          CHECK(o.mine() == whole.mine());
        }
        const parallel::FloeOwners whole = owners_on(0, after);
        for (std::size_t m = 0; m < parents.size(); ++m) {
          const int parent = like.owner()[parents[m]];
          across += (whole.owner()[parents[m]] != parent ? 1 : 0) + (whole.owner()[n + m] != parent ? 1 : 0);
        }
      }
    }
  }
  MESSAGE("the pieces owned by another rank than their parent's: " << across << "; notices: " << notices);
  CHECK(across > 0);
  CHECK(notices > 0);
}

TEST_CASE("a split step concluded on every rank reads only the states the owners' split_readers send") {
  // Simulation::percussion's limited gather (docs/parallel.md, "The split
  // step's owners and gather by holder (split28)"), on simulated ranks:
  // each owner lists, against its held floes (its band, poisoned outside),
  // its through cracks' parents that may split or be decided again and
  // their neighbours (Percussion::split_readers); a rank that concludes on
  // a copy in which only every owner's listed floes are not NaN, with that
  // mask (`readable`), makes the serial splits and events: the same floe
  // count and ids, every listed floe and every piece bit for bit. Strips of
  // equal counts on 2, 3 and 7 ranks, periodic and open.
  // The mutation it names: the parents alone sent (no neighbours); a
  // decision taken again then misses its neighbours (NaN places compare
  // false), and some conclusion differs (counted: > 0).
  std::size_t listed = 0, differ_parents_only = 0;
  for (const bool periodic : {true, false}) {
    CAPTURE(periodic);
    const Pack p = moving_pack(11, periodic, 0.5, kConcentration);
    const std::size_t n = p.floes.size();
    Percussion serial_percussion(split_params(), opening(p));
    std::vector<FloeInitiation> decided = cracks(p.floes);
    for (FloeInitiation& fi : decided) fi.split = serial_percussion.decide_split(p.floes, fi.floe, fi);
    Floes serial = p.floes;
    REQUIRE(serial_percussion.conclude(serial, analyses_of(decided)));
    const std::vector<FractureEventRow> serial_events = serial_percussion.take_events();
    REQUIRE(serial_percussion.stats().splits_redone > 0);
    for (const int ranks : {2, 3, 7}) {
      CAPTURE(ranks);
      parallel::FloeOwners owners(0, ranks, p.detect.domain);
      owners.assign(p.floes);
      Held readable(n, 0), parents_only(n, 0);
      for (int r = 0; r < ranks; ++r) {
        const Held band = halo_band(owners, r, p.floes, p.shapes, p.detect);
        PercussionAnalyses mine;
        for (const FloeInitiation& fi : decided)
          if (owners.owner()[fi.floe] == r) mine.initiations.push_back(fi);
        Percussion share(split_params(), opening(p));
        for (const std::uint32_t j : share.split_readers(poisoned(p.floes, band), mine, band)) {
          REQUIRE(band[j]);
          readable[j] = 1;
        }
        for (const FloeInitiation& fi : mine.initiations)
          if (decided_against_neighbours(fi.split.verdict)) parents_only[fi.floe] = 1;
      }
      listed += count_held(readable);
      const auto conclude_on = [&](const Held& mask, bool check) {
        Percussion every(split_params(), opening(p));
        Floes f = poisoned(p.floes, mask);
        every.conclude(f, analyses_of(decided), nullptr, mask);
        bool same = f.size() == serial.size() && f.ids_issued == serial.ids_issued && same_bytes(f.id, serial.id) &&
                    same_events(every.take_events(), serial_events);
        for (std::size_t j = 0; same && j < f.size(); ++j)
          if (j >= n || mask[j]) same = same_floe(f, j, serial, j);
        if (check) CHECK(same);
        return same;
      };
      conclude_on(readable, true);
      if (!conclude_on(parents_only, false)) ++differ_parents_only;
    }
  }
  MESSAGE("floes listed: " << listed << "; the parents alone: " << differ_parents_only << " of 6 conclusions differ");
  CHECK(differ_parents_only > 0);
}

TEST_SUITE_END();
