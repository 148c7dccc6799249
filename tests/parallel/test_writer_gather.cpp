// One writer gathers the records' and checkpoints' floe states
// (parallel/writer_gather.hpp) on simulated ranks in one process: each rank
// holds only its floes' states, every other entry of its copy poisoned
// (NaN); the writer's copy assembled from the ranks' messages must be the
// whole state bit for bit.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>

#include "parallel/writer_gather.hpp"

TEST_SUITE_BEGIN("mpi");

using namespace floesim;

namespace {

struct Case {
  std::vector<FloeState> whole;
  std::vector<int> owner;
};

// n floes on [0, 1000) in y, owned by strips of `ranks` (equal, or with an
// empty last strip: `empty_last`).
Case make_case(std::size_t n, int ranks, bool empty_last, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0), y(0.0, 1000.0);
  const int strips = empty_last ? ranks - 1 : ranks;
  Case c;
  for (std::size_t i = 0; i < n; ++i) {
    FloeState s{u(rng), y(rng), u(rng), u(rng), u(rng), u(rng), u(rng), u(rng), u(rng), u(rng), u(rng), u(rng)};
    c.whole.push_back(s);
    c.owner.push_back(std::min(strips - 1, static_cast<int>(s.y / (1000.0 / strips))));
  }
  return c;
}

// Rank r's copy: NaN but the states it owns.
std::vector<FloeState> poisoned(const Case& c, int r) {
  const double nan = std::nan("");
  std::vector<FloeState> s = c.whole;
  for (std::size_t i = 0; i < s.size(); ++i)
    if (c.owner[i] != r) s[i] = FloeState{nan, nan, nan, nan, nan, nan, nan, nan, nan, nan, nan, nan};
  return s;
}

// The writer's copy assembled from every rank's message, each built by the
// owners `sent_owner` from its poisoned copy; empty if the messages do not
// fit the writer's counts.
std::vector<FloeState> gathered(const Case& c, int ranks, int writer, std::span<const int> sent_owner) {
  std::vector<std::byte> all;
  for (int r = 0; r < ranks; ++r) {
    const std::vector<std::byte> m = parallel::writer_message(poisoned(c, r), sent_owner, r, writer);
    all.insert(all.end(), m.begin(), m.end());
  }
  std::vector<FloeState> out = poisoned(c, writer);
  std::size_t total = 0;
  for (const std::size_t k : parallel::writer_counts(c.owner, ranks, writer)) total += k;
  if (total != all.size()) return {};
  parallel::writer_assemble(out, all, c.owner, ranks, writer);
  return out;
}

bool same_bits(const std::vector<FloeState>& a, const std::vector<FloeState>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(FloeState)) == 0;
}

}  // namespace

TEST_CASE("the writer's states gathered from the floes' owners are the whole state bit for bit (simulated ranks)") {
  for (const int ranks : {2, 3, 7})
    for (const bool empty_last : {false, true})
      for (const int writer : {0, ranks - 1}) {
        const Case c = make_case(500, ranks, empty_last, 17u + static_cast<unsigned>(ranks));
        CAPTURE(ranks);
        CAPTURE(empty_last);
        CAPTURE(writer);
        CHECK(same_bits(gathered(c, ranks, writer, c.owner), c.whole));
        // The bytes: 96 B a floe the writer does not own, none from the writer.
        const std::vector<std::size_t> counts = parallel::writer_counts(c.owner, ranks, writer);
        std::size_t total = 0;
        for (const std::size_t k : counts) total += k;
        const auto own = static_cast<std::size_t>(std::count(c.owner.begin(), c.owner.end(), writer));
        CHECK(counts[static_cast<std::size_t>(writer)] == 0);
        CHECK(total == 96 * (c.owner.size() - own));
      }
}

TEST_CASE("the writer's gather by the wrong owners is not the whole state (simulated ranks)") {
  // The mutation: the ranks send by the owners shifted by one rank (as
  // between a move of the cuts and the next assignment), the writer reads
  // by the true ones; with the messages' sizes equal (two ranks, the
  // writer's count the same) the floes come out poisoned or misplaced.
  for (const int ranks : {2, 3, 7}) {
    const Case c = make_case(500, ranks, false, 17u + static_cast<unsigned>(ranks));
    CAPTURE(ranks);
    std::vector<int> shifted(c.owner);
    for (int& o : shifted) o = (o + 1) % ranks;
    CHECK_FALSE(same_bits(gathered(c, ranks, 0, shifted), c.whole));
  }
  // Equal counts on two ranks: the same number of floes in each strip, sent
  // by the other strip's owner; the sizes fit and the values are NaN.
  Case c = make_case(400, 2, false, 5u);
  for (std::size_t i = 0; i < c.owner.size(); ++i) c.owner[i] = i % 2 == 0 ? 0 : 1;
  std::vector<int> swapped(c.owner);
  for (int& o : swapped) o = 1 - o;
  const std::vector<FloeState> out = gathered(c, 2, 0, swapped);
  REQUIRE(out.size() == c.whole.size());
  CHECK(std::isnan(out[1].x));
  CHECK_FALSE(same_bits(out, c.whole));
}

TEST_SUITE_END();
