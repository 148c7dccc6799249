// The owners from their own floes (docs/parallel.md, "The hand-over at a
// move of the cuts and the owners from their own floes (handover25)";
// parallel::FloeOwners::leaving and take_leaving), on simulated ranks in one
// process. Each rank's owners are assigned at the floes' old places; the
// floes then move (many across a cut, some exactly onto one). Each rank
// tests its own floes on a copy in which every other floe is NaN
// (leaving), the notices are "gathered" in rank order (here a loop, as
// announce_held's allgather), and each rank applies all of them
// (take_leaving). Checked: every rank's owner array and its own floes equal
// FloeOwners::assign's at the new places (which reads every floe), entry
// for entry; and each rank's band strip made from the floes it kept (its
// own notices applied first, every other floe NaN) and widened by the
// notices' places and half bands (widen_by_arrivals) is band_strip's at
// the new owners, bit for bit. The named mutations: the last rank's
// notices lost in the gather, which must change some rank's owners; the
// strips not widened, which must change some strip.
//
// Strips: equal counts, uneven (an empty strip, a cut beyond the pack) and
// the sea's slabs (periodic box), on 2, 3 and 7 ranks, periodic and open,
// at 0.5 and 2 m/s (tests/parallel/halo_case.hpp's cases); and the slabs
// with the pack moved below the grid in an open box (floes beyond the grid,
// owned by the rows they wrap to).
#include <doctest/doctest.h>

#include <cmath>
#include <cstring>
#include <vector>

#include "parallel/held.hpp"
#include "parallel/place.hpp"
#include "tests/parallel/halo_case.hpp"

TEST_SUITE_BEGIN("mpi");

using namespace floesim;
using namespace floesim::test;

namespace {

// Rank `rank`'s owners, as owners_of makes rank 0's: the same strips, its
// own rank number, assigned at the places of `floes`.
parallel::FloeOwners owners_on(const parallel::FloeOwners& like, int rank, const contact::Domain& box,
                               const Floes& floes) {
  parallel::FloeOwners out(rank, like.ranks(), box);
  if (like.has_slabs()) out.set_slabs(like.slabs());
  else out.set_cuts(like.cuts());
  out.assign(floes);
  return out;
}

// The floes moved by dt at their velocities (wrapped into a periodic box as
// Simulation::wrap_periodic does), and floe k of each ten put on a cut
// exactly (the cuts in turn), where round-off would show.
Floes moved(const Pack& p, const parallel::FloeOwners& owners, double dt) {
  Floes out = p.floes;
  const contact::Domain& d = p.detect.domain;
  for (FloeState& s : out.state) {
    s.x += dt * s.vx;
    s.y += dt * s.vy;
    if (!d.periodic) continue;
    s.x = d.xmin + std::fmod(std::fmod(s.x - d.xmin, d.width()) + d.width(), d.width());
    s.y = d.ymin + std::fmod(std::fmod(s.y - d.ymin, d.height()) + d.height(), d.height());
  }
  std::vector<double> cuts;
  for (const double c : owners.cuts())
    if (std::isfinite(c) && (!d.periodic || (c >= d.ymin && c < d.ymax))) cuts.push_back(c);
  if (!cuts.empty())
    for (std::size_t i = 0, k = 0; i < out.size(); i += 10, ++k) out.state[i].y = cuts[k % cuts.size()];
  return out;
}

struct Outcome {
  std::size_t notices = 0, differing_ranks = 0, differing_strips = 0;
};

bool same_strip(const parallel::BandStrip& a, const parallel::BandStrip& b) {
  return std::memcmp(&a, &b, sizeof a) == 0;
}

// One configuration: the owners by leaving/take_leaving on every simulated
// rank against assign at the new places. `lose_last`: the mutation.
Outcome check_case(const Pack& p, const parallel::FloeOwners& like, bool lose_last) {
  const std::size_t n = p.floes.size();
  const int ranks = like.ranks();
  const Floes after = moved(p, like, 60.0);
  std::vector<parallel::FloeOwners> by_own;
  std::vector<std::vector<parallel::LeaveNotice>> sent;
  std::vector<parallel::LeaveNotice> all;
  std::vector<parallel::BandStrip> strips;
  for (int r = 0; r < ranks; ++r) {
    by_own.push_back(owners_on(like, r, p.detect.domain, p.floes));
    parallel::FloeOwners& o = by_own.back();
    Held own(n, 0);
    for (const std::uint32_t j : o.mine()) own[j] = 1;
    std::vector<parallel::LeaveNotice> mine = o.leaving(r, poisoned(after, own));
    for (parallel::LeaveNotice& k : mine) {
      REQUIRE(o.owner()[k.floe] == r);
      k.reach = p.detect.reach[k.floe];  // set_reach's, from the owner
    }
    // The rank's own notices first, then its strip from the floes it kept
    // (announce_held's order), every other floe and reach NaN.
    o.take_leaving(mine);
    Held kept(n, 0);
    for (const std::uint32_t j : o.mine()) kept[j] = 1;
    contact::DetectionOptions d = p.detect;
    d.reach = poisoned(d.reach, kept);
    strips.push_back(parallel::band_strip(o, r, poisoned(after, kept), poisoned(p.shapes, kept), d));
    sent.push_back(mine);
    if (lose_last && r == ranks - 1) continue;
    all.insert(all.end(), mine.begin(), mine.end());
  }
  Outcome out;
  out.notices = all.size();
  if (!lose_last) parallel::widen_by_arrivals(strips, all, p.shapes, p.detect.collision_distance);
  for (int r = 0; r < ranks; ++r) {
    for (int s = 0; s < ranks; ++s)  // the others' notices (its own are applied)
      if (s != r && !(lose_last && s == ranks - 1))
        by_own[static_cast<std::size_t>(r)].take_leaving(sent[static_cast<std::size_t>(s)]);
    const parallel::FloeOwners whole = owners_on(like, r, p.detect.domain, after);
    const parallel::FloeOwners& mine = by_own[static_cast<std::size_t>(r)];
    const bool same = std::equal(mine.owner().begin(), mine.owner().end(), whole.owner().begin(), whole.owner().end()) &&
                      mine.mine() == whole.mine();
    const parallel::BandStrip strip = parallel::band_strip(whole, r, after, p.shapes, p.detect);
    const bool same_band = same_strip(strips[static_cast<std::size_t>(r)], strip);
    if (!lose_last) {
      CAPTURE(r);
      CHECK(same);
      CHECK(same_band);
    }
    out.differing_ranks += same ? 0 : 1;
    out.differing_strips += same_band ? 0 : 1;
  }
  return out;
}

}  // namespace

TEST_CASE("the owners from each rank's own floes and the notices of those leaving its strip are assign's (simulated ranks)") {
  std::size_t cases = 0, notices = 0, mutated_cases = 0, mutated_ranks = 0, ranks_seen = 0, unwidened = 0;
  const auto one = [&](const Pack& p, const parallel::FloeOwners& like, const std::string& name) {
    CAPTURE(name);
    const Outcome o = check_case(p, like, false);
    const Outcome m = check_case(p, like, true);
    ++cases;
    ranks_seen += static_cast<std::size_t>(like.ranks());
    notices += o.notices;
    mutated_ranks += m.differing_ranks;
    mutated_cases += m.differing_ranks > 0 ? 1 : 0;
    unwidened += m.differing_strips;
  };
  for_each_strip_case([&](const Pack& p, const StripCase& c) { one(p, owners_of(p, c.ranks, c.kind), c.name()); });
  // The slabs with the pack 150 m below the grid in an open box.
  Pack below = moving_pack(7, true, 0.5);
  const parallel::FloeOwners slabs = owners_of(below, 3, Strips::slabs);
  below.detect.domain.periodic = false;
  for (FloeState& s : below.floes.state) s.y -= 150.0;
  for (const int ranks : {2, 3, 7}) {
    parallel::FloeOwners like(0, ranks, below.detect.domain);
    like.set_slabs(slabs_of(below, ranks));
    like.assign(below.floes);
    one(below, like, "beyond, " + std::to_string(ranks) + " ranks");
  }
  MESSAGE(cases << " configurations, " << ranks_seen << " simulated ranks, " << notices
                << " notices; the last rank's notices lost: " << mutated_cases << " configurations and "
                << mutated_ranks << " ranks differ; the strips not widened by the notices: " << unwidened
                << " strips differ");
  CHECK(cases == 33);
  CHECK(notices > 0);
  // The mutation bites wherever the last rank had a floe leave: in most.
  CHECK(mutated_cases * 2 > cases);
  CHECK(unwidened > 0);
}
