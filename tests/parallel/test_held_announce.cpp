// The held sets announced by the owners (docs/parallel.md, "The held sets
// announced by the owners (band18)"; parallel/held.hpp), on simulated ranks
// in one process: each rank computes its strip and part of H from its own
// floes (band_strip), the strips are "gathered" (every rank's, here a
// loop), each rank tests its own floes against them (band_notices) on a
// copy in which every floe it does not own is NaN (state, shape, reach),
// and each rank's held set is its own floes and the notices addressed to
// it (held_from_notices), its reaches written from them on a copy whose
// other reaches are NaN. Checked against the band's rule
// (parallel::held_floes, every floe read, H the pack's largest h_j), mask
// for mask; the reaches received against the whole reach array (set_reach's
// formula, test::moving_pack) bit for bit, the others left NaN; the rank's
// part of the detection from what it received equal to its part from the
// whole state. Named mutations, each seen: H from the receiver's own floes
// only; the owner's test without the nearest image (the box taken open);
// the reaches not sent.
//
// Strips: equal counts, uneven (an empty strip, a cut beyond the pack) and
// the sea's slabs (periodic box), on 2, 3 and 7 ranks, periodic and open,
// at 0.5 and 2 m/s; and the slabs with the pack moved below the grid in an
// open box (floes beyond the grid, owned by the row they wrap to).
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "contact/detection.hpp"
#include "parallel/detect.hpp"
#include "parallel/held.hpp"
#include "parallel/place.hpp"
#include "tests/parallel/halo_case.hpp"
#include "tests/parallel/same_detection.hpp"

TEST_SUITE_BEGIN("mpi");

using namespace floesim;
using namespace floesim::test;

namespace {

Held mask_of(std::span<const std::uint32_t> floes, std::size_t n) {
  Held out(n, 0);
  for (const std::uint32_t j : floes) out[j] = 1;
  return out;
}

// One configuration's announcement, as the ranks make it: every rank's
// strip from its own floes, H their largest, every rank's notices from a
// copy poisoned outside its own floes. `largest_for` (mutation): the H each
// receiver's notices are tested with, if not the one H.
struct Announced {
  std::vector<parallel::BandStrip> strips;
  double largest = 0.0;
  std::vector<std::vector<parallel::BandNotice>> notices;  // [sender][receiver]
};
Announced announce(const Pack& p, const parallel::FloeOwners& owners, bool receivers_h = false,
                   bool no_image = false) {
  const std::size_t n = p.floes.size();
  Announced a;
  for (int r = 0; r < owners.ranks(); ++r) {
    const Held own = mask_of(parallel::own_floes(owners, r), n);
    contact::DetectionOptions d = p.detect;
    d.reach = poisoned(d.reach, own);
    a.strips.push_back(parallel::band_strip(owners, r, poisoned(p.floes, own), poisoned(p.shapes, own), d));
  }
  for (const parallel::BandStrip& s : a.strips) a.largest = std::max(a.largest, s.largest);
  for (int r = 0; r < owners.ranks(); ++r) {
    const Held own = mask_of(parallel::own_floes(owners, r), n);
    const Floes floes = poisoned(p.floes, own);
    const contact::CollisionShapes shapes = poisoned(p.shapes, own);
    contact::DetectionOptions d = p.detect;
    d.reach = poisoned(d.reach, own);
    if (no_image) d.domain.periodic = false;  // the strips were made in the true box
    if (!receivers_h) {
      a.notices.push_back(parallel::band_notices(owners, r, floes, shapes, d, a.strips, a.largest));
      continue;
    }
    std::vector<parallel::BandNotice> out(a.strips.size());
    for (std::size_t s = 0; s < a.strips.size(); ++s)
      out[s] = parallel::band_notices(owners, r, floes, shapes, d, a.strips, a.strips[s].largest)[s];
    a.notices.push_back(std::move(out));
  }
  return a;
}

std::vector<parallel::BandNotice> received_by(const Announced& a, int s) {
  std::vector<parallel::BandNotice> out;
  for (const std::vector<parallel::BandNotice>& from : a.notices) out.push_back(from[static_cast<std::size_t>(s)]);
  return out;
}

struct Count {
  std::size_t configs = 0, parts = 0, held = 0, received = 0, notices_bytes = 0, floes = 0;
  std::size_t receivers_h_differs = 0, no_image_differs = 0, unsent_nan = 0, unsent_lost_parts = 0;
};

void check_case(const Pack& p, int ranks, Strips kind, Count& count) {
  const std::size_t n = p.floes.size();
  const parallel::FloeOwners owners = owners_of(p, ranks, kind);
  const Announced a = announce(p, owners);
  // H: the largest of the ranks' parts is the pack's largest h_j, and the
  // reduction's (largest_half_band) by its bits.
  double pack_largest = 0.0;
  for (std::size_t j = 0; j < n; ++j)
    pack_largest = std::max(pack_largest, parallel::half_band(owners, p.floes, p.shapes, p.detect, j));
  CHECK(bits(a.largest, pack_largest));
  CHECK(bits(a.largest, largest_by_ranks(owners, p.floes, p.shapes, p.detect)));
  const Announced by_receivers_h = announce(p, owners, true);
  const Announced without_image = announce(p, owners, false, true);
  bool receivers_h_differs = false, no_image_differs = false;
  for (int s = 0; s < ranks; ++s) {
    CAPTURE(s);
    const std::vector<std::uint32_t> own = parallel::own_floes(owners, s);
    const Held own_mask = mask_of(own, n);
    std::vector<double> reach = poisoned(p.detect.reach, own_mask);
    const parallel::HeldFloes held = parallel::held_from_notices(own, n, received_by(a, s), a.largest, reach);
    const parallel::HeldFloes rule = parallel::held_floes(owners, s, p.floes, p.shapes, p.detect, a.largest);
    CHECK(held.mask == rule.mask);
    CHECK(held.index == rule.index);
    CHECK(bits(held.largest, rule.largest));
    // The reaches: the held floes' the whole array's bits, the others NaN.
    bool reaches = true;
    for (std::size_t j = 0; j < n; ++j)
      reaches = reaches && (held.holds(j) ? bits(reach[j], p.detect.reach[j]) : std::isnan(reach[j]));
    CHECK(reaches);
    // The rank's part of the detection from what it holds and received.
    contact::DetectionOptions d = p.detect;
    d.reach = reach;
    const contact::Detection whole = parallel::detect_part(owners, s, p.floes, p.shapes, p.detect);
    CHECK(same_detection(
        parallel::detect_part(owners, s, poisoned(p.floes, held.mask), poisoned(p.shapes, held.mask), d, &held), whole));
    // The mutations.
    std::vector<double> ignored(n, 0.0);
    receivers_h_differs = receivers_h_differs ||
                          parallel::held_from_notices(own, n, received_by(by_receivers_h, s), a.largest, ignored).mask != rule.mask;
    no_image_differs = no_image_differs ||
                       parallel::held_from_notices(own, n, received_by(without_image, s), a.largest, ignored).mask != rule.mask;
    std::vector<double> unsent = poisoned(p.detect.reach, own_mask);
    const parallel::HeldFloes held_unsent = parallel::held_from_notices(own, n, received_by(a, s), a.largest, {});
    std::size_t nan = 0;
    for (const std::uint32_t j : held_unsent.index) nan += std::isnan(unsent[j]) ? 1 : 0;
    count.unsent_nan += nan;
    d.reach = unsent;
    if (nan > 0 && !same_detection(parallel::detect_part(owners, s, poisoned(p.floes, held.mask),
                                                          poisoned(p.shapes, held.mask), d, &held_unsent),
                                   whole))
      ++count.unsent_lost_parts;
    ++count.parts;
    count.held += held.index.size();
    count.received += held.index.size() - own.size();
    count.floes += n;
  }
  for (const auto& from : a.notices)
    for (const parallel::BandNotice& notice : from) count.notices_bytes += notice.floe.size() * 12;
  count.receivers_h_differs += receivers_h_differs ? 1 : 0;
  count.no_image_differs += no_image_differs ? 1 : 0;
  ++count.configs;
}

}  // namespace

TEST_CASE("the held sets announced by the owners are the band's rule, with the owners' reaches") {
  Count count;
  std::size_t periodic_configs = 0;
  for_each_strip_case([&](const Pack& p, const StripCase& c) {
    const std::string where = c.name();
    CAPTURE(where);
    check_case(p, c.ranks, c.kind, count);
    periodic_configs += c.periodic ? 1 : 0;
  });
  // The sea's slabs in an open box, the pack moved 150 m below the grid:
  // the floes there are owned by the last slab's rows (the grid's wrap).
  std::size_t beyond = 0;
  for (const double speed : {0.5, 2.0}) {
    Pack p = moving_pack(7, false, speed);
    for (FloeState& s : p.floes.state) s.y -= 150.0;
    for (const FloeState& s : p.floes.state) beyond += s.y < 0.0;
    for (const int ranks : {2, 3, 7}) {
      CAPTURE(speed);
      CAPTURE(ranks);
      check_case(p, ranks, Strips::beyond, count);
    }
  }
  MESSAGE(count.configs << " configurations, " << count.parts << " ranks: " << count.held << " floes held of "
                        << count.floes << ", " << count.received << " announced (" << count.notices_bytes
                        << " bytes of notices); " << beyond << " floes below the grid. Mutations: H from the "
                        << "receiver's own floes changes the held sets of " << count.receivers_h_differs
                        << " configurations, the test without the nearest image " << count.no_image_differs << " of "
                        << periodic_configs << " periodic ones; the reaches not sent leave " << count.unsent_nan
                        << " held floes without a reach, and " << count.unsent_lost_parts
                        << " ranks' parts of the detection differ");
  CHECK(beyond > 0);
  CHECK(count.receivers_h_differs > 0);
  CHECK(count.no_image_differs > 0);
  CHECK(count.unsent_nan > 0);
  CHECK(count.unsent_lost_parts > 0);
}

TEST_SUITE_END();
