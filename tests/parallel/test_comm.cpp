// The communicator layer on one rank, and the pieces of the distributed step
// that can be checked without launching ranks: shares, the agreement's
// rethrow, and that detection measured in parts and concatenated is the
// serial detection (what parallel::detect gathers on N ranks).
#include <doctest/doctest.h>

#include <random>

#include "contact/detection.hpp"
#include "contact/shapes.hpp"
#include "core/error.hpp"
#include "core/pack_generator.hpp"
#include "parallel/comm.hpp"
#include "parallel/detect.hpp"

TEST_SUITE_BEGIN("mpi");

using namespace floesim;

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

namespace {
// Field by field (structs' padding bytes are not values), doubles compared with == (bit for bit but for -0).
bool same(const contact::NearPair& x, const contact::NearPair& y) {
  return x.a == y.a && x.b == y.b && x.shift == y.shift && x.distance == y.distance && x.normal == y.normal &&
         x.pa == y.pa && x.pb == y.pb && x.exact == y.exact && x.overlap == y.overlap &&
         x.axis_distance == y.axis_distance && x.axis_normal == y.axis_normal && x.axis_any == y.axis_any &&
         x.far_distance == y.far_distance && x.first_witness == y.first_witness &&
         x.witness_count == y.witness_count && x.first_contact == y.first_contact && x.contact_count == y.contact_count;
}
bool same(const contact::ContactPoint& x, const contact::ContactPoint& y) {
  return x.a == y.a && x.b == y.b && x.point == y.point && x.normal == y.normal && x.gap == y.gap &&
         x.shift == y.shift && x.speculative == y.speculative && x.vertex_of_b == y.vertex_of_b && x.turning == y.turning;
}
bool same(const contact::Witness& x, const contact::Witness& y) {
  return x.pa == y.pa && x.pb == y.pb && x.normal == y.normal && x.distance == y.distance &&
         x.vertex_of_b == y.vertex_of_b;
}
template <class T>
bool same_lists(const std::vector<T>& a, const std::vector<T>& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t k = 0; k < a.size(); ++k)
    if (!same(a[k], b[k])) return false;
  return true;
}
}  // namespace

TEST_CASE("detection in parts and concatenated is the serial detection bit for bit") {
  // A dense periodic pack with floes moved towards their neighbours, so that
  // some pairs have contact points and witnesses (offsets to rebase).
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
  contact::DetectionOptions d;
  d.collision_distance = 20.0;  // m: wide, so that many pairs have contact points
  d.horizon = 10.0;
  d.domain = {true, g.window[0], g.window[1], g.window[2], g.window[3]};
  d.reach.assign(g.floes.size(), 10.0);
  const contact::Detection serial = contact::detect(g.floes, shapes, d);
  MESSAGE("serial: " << serial.pairs.size() << " pairs, " << serial.contacts.size() << " contacts, "
                     << serial.witnesses.size() << " witnesses");
  REQUIRE(serial.pairs.size() > 100);
  REQUIRE(serial.contacts.size() > 10);
  REQUIRE(serial.witnesses.size() > 10);
  for (std::size_t parts : {1u, 2u, 3u, 7u}) {
    CAPTURE(parts);
    std::vector<contact::Detection> pieces;
    for (std::size_t p = 0; p < parts; ++p) {
      d.part = p;
      d.parts = parts;
      pieces.push_back(contact::detect(g.floes, shapes, d));
    }
    if (parts > 1) CHECK(pieces[1].pairs.size() < serial.pairs.size());  // the parts do share the work
    const contact::Detection joined = parallel::concatenate(std::move(pieces));
    CHECK(same_lists(joined.pairs, serial.pairs));
    CHECK(same_lists(joined.contacts, serial.contacts));
    CHECK(same_lists(joined.witnesses, serial.witnesses));
    CHECK(joined.reach == serial.reach);
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
  const contact::Detection a = parallel::detect(parallel::Communicator{}, g.floes, shapes, d);
  const contact::Detection b = contact::detect(g.floes, shapes, d);
  CHECK(same_lists(a.pairs, b.pairs));
  CHECK(same_lists(a.contacts, b.contacts));
}
TEST_SUITE_END();
