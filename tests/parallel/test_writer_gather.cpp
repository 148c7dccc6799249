// One writer gathers the records' and checkpoints' floe states
// (parallel/writer_gather.hpp) on simulated ranks in one process: each rank
// holds only its floes' states and the vertical DOFs it drifted, every
// other entry of its copy poisoned (NaN); the writer's copy assembled from
// the ranks' messages must be the whole state bit for bit.
#include <doctest/doctest.h>

#include <cmath>
#include <cstring>
#include <random>

#include "parallel/writer_gather.hpp"

TEST_SUITE_BEGIN("mpi");

using namespace floesim;

namespace {

struct Case {
  std::vector<FloeState> whole;
  std::vector<int> owner, vertical_owner;
};

// n floes on [0, 1000) in y, owned by equal strips of `ranks`; the vertical
// DOFs owned by the strips the floes were in 30 m earlier (the coupling's
// owners, one rebuild behind the drift's): they differ near the cuts.
Case make_case(std::size_t n, int ranks, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0), y(0.0, 1000.0);
  Case c;
  auto strip = [&](double at) {
    const double wrapped = at - 1000.0 * std::floor(at / 1000.0);
    return std::min(ranks - 1, static_cast<int>(wrapped / (1000.0 / ranks)));
  };
  for (std::size_t i = 0; i < n; ++i) {
    FloeState s{u(rng), y(rng), u(rng), u(rng), u(rng), u(rng), u(rng), u(rng), u(rng), u(rng), u(rng), u(rng)};
    c.whole.push_back(s);
    c.owner.push_back(strip(s.y));
    c.vertical_owner.push_back(strip(s.y - 30.0));
  }
  return c;
}

// Rank r's copy: NaN but the states it owns and the vertical DOFs it holds.
std::vector<FloeState> poisoned(const Case& c, std::span<const int> vertical_owner, int r) {
  const double nan = std::nan("");
  std::vector<FloeState> s = c.whole;
  for (std::size_t i = 0; i < s.size(); ++i) {
    const int v = vertical_owner.empty() ? c.owner[i] : vertical_owner[i];
    if (c.owner[i] != r) {
      const FloeState kept = s[i];
      s[i] = FloeState{nan, nan, nan, nan, nan, nan, nan, nan, nan, nan, nan, nan};
      if (v == r) {
        s[i].heave = kept.heave;
        s[i].pitch = kept.pitch;
        s[i].roll = kept.roll;
      }
    } else if (v != r) {
      s[i].heave = s[i].pitch = s[i].roll = nan;
    }
  }
  return s;
}

// The writer's copy assembled from every rank's message, each built with
// `sent_owner` (the owners the ranks send by) from its poisoned copy.
std::vector<FloeState> gathered(const Case& c, std::span<const int> vertical_owner, int ranks, int writer,
                                std::span<const int> sent_owner) {
  std::vector<std::byte> all;
  for (int r = 0; r < ranks; ++r) {
    const std::vector<std::byte> m =
        parallel::writer_message(poisoned(c, vertical_owner, r), sent_owner, vertical_owner, r, writer);
    all.insert(all.end(), m.begin(), m.end());
  }
  std::vector<FloeState> out = poisoned(c, vertical_owner, writer);
  const std::vector<std::size_t> counts = parallel::writer_counts(c.owner, vertical_owner, ranks, writer);
  std::size_t total = 0;
  for (const std::size_t k : counts) total += k;
  if (total != all.size()) return {};  // the messages do not fit the writer's counts
  parallel::writer_assemble(out, all, c.owner, vertical_owner, ranks, writer);
  return out;
}

bool same_bits(const std::vector<FloeState>& a, const std::vector<FloeState>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(FloeState)) == 0;
}

}  // namespace

TEST_CASE("the writer's states gathered from the floes' holders are the whole state bit for bit (simulated ranks)") {
  for (const int ranks : {2, 3, 7})
    for (const int writer : {0, ranks - 1}) {
      const Case c = make_case(500, ranks, 17u + static_cast<unsigned>(ranks));
      std::size_t differ = 0;
      for (std::size_t i = 0; i < c.owner.size(); ++i) differ += c.owner[i] != c.vertical_owner[i];
      CAPTURE(ranks);
      CAPTURE(writer);
      REQUIRE(differ > 0);  // the coupling's owners differ from the drift's for some floes
      // The vertical DOFs from the coupling's owners, and with no separate owners.
      CHECK(same_bits(gathered(c, c.vertical_owner, ranks, writer, c.owner), c.whole));
      CHECK(same_bits(gathered(c, {}, ranks, writer, c.owner), c.whole));
      // The bytes: 96 B a floe the writer does not own, 24 B a floe whose
      // vertical DOFs another rank than its owner holds, none from the writer.
      const std::vector<std::size_t> counts = parallel::writer_counts(c.owner, c.vertical_owner, ranks, writer);
      std::size_t expected = 0, total = 0;
      for (std::size_t i = 0; i < c.owner.size(); ++i) {
        if (c.owner[i] != writer) expected += 96;
        if (c.vertical_owner[i] != c.owner[i] && c.vertical_owner[i] != writer) expected += 24;
      }
      for (const std::size_t k : counts) total += k;
      CHECK(counts[static_cast<std::size_t>(writer)] == 0);
      CHECK(total == expected);
      MESSAGE(ranks << " ranks, writer " << writer << ": " << differ << " of 500 floes with two owners, "
                    << total << " bytes to the writer");
    }
}

TEST_CASE("the writer's gather from the wrong owners, or the vertical DOFs from the drift's, is not the whole state") {
  for (const int ranks : {2, 3, 7}) {
    const Case c = make_case(500, ranks, 17u + static_cast<unsigned>(ranks));
    CAPTURE(ranks);
    // Mutation 1: the ranks send by the owners shifted by one rank (as
    // between a move of the cuts and the next assignment).
    std::vector<int> shifted(c.owner);
    for (int& o : shifted) o = (o + 1) % ranks;
    CHECK_FALSE(same_bits(gathered(c, c.vertical_owner, ranks, 0, shifted), c.whole));
    // Mutation 2: the vertical DOFs taken from the drift's owners although
    // the coupling's hold them: the floes whose two owners differ read NaN.
    std::vector<std::byte> all;
    for (int r = 0; r < ranks; ++r) {
      const std::vector<std::byte> m = parallel::writer_message(poisoned(c, c.vertical_owner, r), c.owner, {}, r, 0);
      all.insert(all.end(), m.begin(), m.end());
    }
    std::vector<FloeState> out = poisoned(c, c.vertical_owner, 0);
    parallel::writer_assemble(out, all, c.owner, {}, ranks, 0);
    CHECK_FALSE(same_bits(out, c.whole));
  }
}

TEST_SUITE_END();
