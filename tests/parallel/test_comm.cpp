// The communicator layer on one rank, and the pieces of the distributed step
// that can be checked without launching ranks: shares, the agreement's
// rethrow, and that detection by place, merged, is the serial detection
// (what parallel::detect gathers on N ranks).
#include <doctest/doctest.h>

#include <algorithm>
#include <random>

#include "contact/detection.hpp"
#include "contact/shapes.hpp"
#include "core/error.hpp"
#include "core/pack_generator.hpp"
#include "parallel/comm.hpp"
#include "parallel/detect.hpp"
#include "parallel/place.hpp"
#include "tests/parallel/same_detection.hpp"

TEST_SUITE_BEGIN("mpi");

using namespace floesim;
using test::same_lists;

TEST_CASE("shares are contiguous in rank order and cover n with sizes within one") {
  for (int ranks = 1; ranks <= 7; ++ranks)
    for (std::size_t n : {0u, 1u, 5u, 6u, 7u, 100u, 4001u}) {
      std::size_t next = 0, smallest = n, largest = 0;
      for (int r = 0; r < ranks; ++r) {
        const parallel::Range s = parallel::share(n, r, ranks);
        CHECK(s.begin == next);
        CHECK(s.end >= s.begin);
        next = s.end;
        smallest = std::min(smallest, s.size());
        largest = std::max(largest, s.size());
      }
      CHECK(next == n);
      CHECK(largest - smallest <= 1);
    }
}

TEST_CASE("the serial communicator is rank 0 of 1: gathers copy and sums are the value") {
  const parallel::Communicator comm;
  CHECK(comm.rank() == 0);
  CHECK(comm.size() == 1);
  CHECK(comm.writer());
  const std::vector<double> x{1.5, -2.0, 3.25};
  CHECK(comm.allgather(std::span<const double>(x)) == x);
  std::vector<double> y = x;
  comm.complete_shares(y);
  CHECK(y == x);
  CHECK(comm.sum(42) == 42);
  CHECK(comm.any(true));
  CHECK_FALSE(comm.any(false));
  const parallel::Range r = comm.share(9);
  CHECK(r.begin == 0);
  CHECK(r.end == 9);
  // Into a kept buffer: a longer message, then a shorter one, are each
  // copied whole, and nothing of the longer one is left past the shorter.
  std::vector<std::byte> buffer;
  std::vector<std::size_t> counts;
  const std::vector<std::byte> longer(100, std::byte{7}), shorter(3, std::byte{1});
  comm.allgather_bytes(longer, counts, buffer);
  CHECK(buffer == longer);
  CHECK(counts == std::vector<std::size_t>{100});
  comm.allgather_bytes(shorter, counts, buffer);
  CHECK(buffer == shorter);
  CHECK(counts == std::vector<std::size_t>{3});
  comm.allgather_known(longer, {100}, buffer);
  CHECK(buffer == longer);
}

TEST_CASE("together_any on one rank gives the flag, or the error with its type") {
  const parallel::Communicator comm;
  int ran = 0;
  CHECK(comm.together_any([&] { ++ran; }, [] { return true; }));
  CHECK_FALSE(comm.together_any([&] { ++ran; }, [] { return false; }));
  CHECK(ran == 2);
  bool asked = false;
  CHECK_THROWS_AS(comm.together_any([] { throw RunError("diverged"); }, [&] { return asked = true; }), RunError);
  CHECK_FALSE(asked);  // the flag is not asked after a failure
}

TEST_CASE("together on one rank throws the original error with its type") {
  const parallel::Communicator comm;
  bool ran = false;
  comm.together([&] { ran = true; });
  CHECK(ran);
  CHECK_THROWS_AS(comm.together([] { throw InputError("bad key"); }), InputError);
  CHECK_THROWS_AS(comm.together([] { throw RunError("overlap"); }), RunError);
  CHECK_THROWS_WITH(comm.together([] { throw RunError("overlap of floes 3 and 4"); }), "overlap of floes 3 and 4");
}

TEST_CASE("detection by place over 1, 2, 3 and 7 strips, merged, is the serial detection field by field") {
  // A dense pack with floes moved towards their neighbours, so that some
  // pairs have contact points and witnesses (offsets to rebase), in a
  // periodic box (pairs across the seam) and in the open plane.
  PackOptions o;
  o.floes = 300;
  o.concentration = 0.8;
  o.min_gap = 0.05;  // m: neighbours close enough to have contact points within xi
  o.width = o.height = 2000.0;
  o.seed = 7;
  GeneratedPack g = generate_pack(o);
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-0.3, 0.3);
  for (FloeState& s : g.floes.state) {
    s.vx = u(rng);
    s.vy = u(rng);
  }
  const contact::CollisionShapes shapes = contact::build_collision_shapes(g.floes);
  const std::size_t n = g.floes.size();
  for (const bool periodic : {true, false}) {
    CAPTURE(periodic);
    contact::DetectionOptions d;
    d.collision_distance = 20.0;  // m: wide, so that many pairs have contact points
    d.horizon = 10.0;
    d.domain = {periodic, g.window[0], g.window[1], g.window[2], g.window[3]};
    d.reach.assign(n, 10.0);
    const contact::Detection serial = contact::detect(g.floes, shapes, d);
    MESSAGE("serial: " << serial.pairs.size() << " pairs, " << serial.contacts.size() << " contacts, "
                       << serial.witnesses.size() << " witnesses");
    REQUIRE(serial.pairs.size() > 100);
    REQUIRE(serial.contacts.size() > 10);
    REQUIRE(serial.witnesses.size() > 10);
    std::size_t seam = 0;
    for (const contact::NearPair& p : serial.pairs) seam += p.shift.y() != 0.0 ? 1 : 0;
    if (periodic) REQUIRE(seam > 0);  // pairs across the seam in y, which the strips cut
    // Strips of equal counts (as a run starts), and uneven ones with an
    // empty strip (two equal cuts) and one beyond the pack.
    const double y0 = g.window[2], h = g.window[3] - g.window[2];
    const std::vector<std::vector<double>> uneven = {
        {}, {y0 + 0.2 * h}, {y0 + 0.3 * h, y0 + 0.3 * h}, {y0 + 0.1 * h, y0 + 0.15 * h, y0 + 0.5 * h, y0 + 0.5 * h,
                                                           y0 + 0.9 * h, y0 + 2.0 * h}};
    for (const bool equal : {true, false}) {
      std::size_t layout = 0;
      for (const int ranks : {1, 2, 3, 7}) {
        CAPTURE(ranks);
        CAPTURE(equal);
        parallel::FloeOwners owners(0, ranks, d.domain);
        if (!equal) owners.set_cuts(uneven[layout]);
        ++layout;
        owners.assign(g.floes);
        std::vector<contact::Detection> parts;
        std::size_t across = 0, empty = 0;
        for (int r = 0; r < ranks; ++r) {
          const contact::DetectionSubset subset = parallel::detection_subset(owners, r, g.floes, shapes, d);
          if (ranks > 1) CHECK(subset.posed.size() < n);  // a strip poses its floes and a halo only
          if (std::count(subset.keep.begin(), subset.keep.end(), 1) == 0) ++empty;
          parts.push_back(parallel::detect_part(owners, r, g.floes, shapes, d));
        }
        for (const contact::NearPair& p : serial.pairs) across += owners.owner()[p.a] != owners.owner()[p.b] ? 1 : 0;
        if (ranks > 1) CHECK(across > 0);  // pairs whose floes lie in different strips
        if (!equal && ranks > 2) CHECK(empty > 0);
        const contact::Detection merged = parallel::merge(std::move(parts));
        CHECK(same_lists(merged.pairs, serial.pairs));
        CHECK(same_lists(merged.contacts, serial.contacts));
        CHECK(same_lists(merged.witnesses, serial.witnesses));
        CHECK(merged.reach == serial.reach);
      }
    }
  }
}

TEST_CASE("parallel::detect on one rank is contact::detect") {
  PackOptions o;
  o.floes = 50;
  o.seed = 2;
  const GeneratedPack g = generate_pack(o);
  const contact::CollisionShapes shapes = contact::build_collision_shapes(g.floes);
  contact::DetectionOptions d;
  d.reach.assign(g.floes.size(), 5.0);
  parallel::FloeOwners owners;
  owners.assign(g.floes);
  const contact::Detection a = parallel::detect(parallel::Communicator{}, owners, g.floes, shapes, d);
  const contact::Detection b = contact::detect(g.floes, shapes, d);
  CHECK(same_lists(a.pairs, b.pairs));
  CHECK(same_lists(a.contacts, b.contacts));
}
TEST_SUITE_END();
