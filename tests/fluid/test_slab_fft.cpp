// The 2D transform in slabs (fluid/slab_fft.hpp) against the whole one
// (fluid/fft2d.hpp): on 1 to 5 ranks, played here by threads that exchange
// through shared memory (the exchange MPI does between processes), each
// rank's slab of the spectrum and of the inverse equals the whole
// transform's to the bit, and the slabs cover the grid. Grids with
// remainder blocks, more ranks than row or column blocks (empty slabs), and
// rows of the benchmark's 2048 cells (column slabs of 1025 / N columns).
#include <doctest/doctest.h>

#include <algorithm>
#include <atomic>
#include <barrier>
#include <cstring>
#include <memory>
#include <thread>
#include <vector>

#include "fluid/slab_fft.hpp"
#include "tests/fluid/slab_check.hpp"

using namespace floesim::fluid;

TEST_SUITE_BEGIN("fluid");

namespace {

// An all-to-all among `ranks` threads: each posts its buffer and counts,
// waits for all, copies its parts out of every rank's buffer, waits again
// (so no buffer is reused before every rank has read it).
struct ThreadExchange {
  explicit ThreadExchange(int ranks) : posted(static_cast<std::size_t>(ranks)), counts(posted.size()), sync(ranks) {}
  SlabFft2d::Exchange of(int rank) {
    return [this, rank](std::span<const std::byte> send, const std::vector<std::size_t>& send_counts,
                        std::span<std::byte> receive, const std::vector<std::size_t>& receive_counts) {
      posted[static_cast<std::size_t>(rank)] = send;
      counts[static_cast<std::size_t>(rank)] = send_counts;
      sync.arrive_and_wait();
      std::size_t at = 0;
      for (std::size_t s = 0; s < posted.size(); ++s) {
        std::size_t offset = 0;
        for (int t = 0; t < rank; ++t) offset += counts[s][static_cast<std::size_t>(t)];
        if (counts[s][static_cast<std::size_t>(rank)] != receive_counts[s]) mismatched = true;
        if (receive_counts[s] > 0) std::memcpy(receive.data() + at, posted[s].data() + offset, receive_counts[s]);
        at += receive_counts[s];
      }
      sync.arrive_and_wait();
    };
  }
  std::vector<std::span<const std::byte>> posted;
  std::vector<std::vector<std::size_t>> counts;
  std::barrier<> sync;
  std::atomic<bool> mismatched{false};  // a rank expected another count than its sender sent (set by any thread, read after join)
};

}  // namespace

TEST_CASE("2D transform in slabs: each rank's slab equals the whole transform's bits, on 1 to 5 ranks") {
  for (auto [nx, ny] : {std::pair{64, 48}, std::pair{30, 21}, std::pair{12, 5}, std::pair{26, 40}, std::pair{2048, 16}}) {
    const testing::WholeTransform whole(nx, ny);
    REQUIRE(whole.fft.valid());
    for (int ranks = 1; ranks <= 5; ++ranks) {
      INFO("nx = " << nx << ", ny = " << ny << ", " << ranks << " ranks");
      ThreadExchange exchange(ranks);
      std::vector<testing::SlabCheck> checks(static_cast<std::size_t>(ranks));
      // The slabs are made here, one after the other: FFTW's planner is not thread-safe.
      std::vector<std::unique_ptr<SlabFft2d>> slabs;
      for (int r = 0; r < ranks; ++r)
        slabs.push_back(
            std::make_unique<SlabFft2d>(whole.fft, nx, ny, r, ranks, ranks > 1 ? exchange.of(r) : SlabFft2d::Exchange{}));
      std::vector<std::thread> threads;
      for (int r = 0; r < ranks; ++r)
        threads.emplace_back([&, r] {
          checks[static_cast<std::size_t>(r)] = testing::check_slab(whole, *slabs[static_cast<std::size_t>(r)]);
        });
      for (std::thread& t : threads) t.join();
      CHECK_FALSE(exchange.mismatched);
      std::vector<int> rows_covered(static_cast<std::size_t>(ny), 0), columns_covered(static_cast<std::size_t>(whole.hx), 0);
      for (int r = 0; r < ranks; ++r) {
        INFO("rank " << r);
        const testing::SlabCheck& check = checks[static_cast<std::size_t>(r)];
        CHECK(check.spectrum_equal);
        CHECK(check.inverse_equal);
        for (int y = check.rows.begin; y < check.rows.end; ++y) rows_covered[static_cast<std::size_t>(y)] += 1;
        for (int x = check.columns.begin; x < check.columns.end; ++x) columns_covered[static_cast<std::size_t>(x)] += 1;
      }
      CHECK(std::all_of(rows_covered.begin(), rows_covered.end(), [](int k) { return k == 1; }));
      CHECK(std::all_of(columns_covered.begin(), columns_covered.end(), [](int k) { return k == 1; }));
    }
  }
}

// Stage seven (docs/parallel.md): the row cuts move during a run
// (SlabFft2d::set_rows, whole blocks of 8 rows, uneven); each rank's slabs
// are still the whole transform's bits, after every move, and the moved
// slabs cover the rows once. Fails if a rank kept the old row scratch or the
// transposes counted the old rows (the exchange's counts then mismatch).
TEST_CASE("2D transform in slabs: moved row cuts keep every rank's bits") {
  const int nx = 64, ny = 48;  // 6 blocks of rows
  const testing::WholeTransform whole(nx, ny);
  REQUIRE(whole.fft.valid());
  const std::vector<std::vector<int>> moves[] = {
      {{0, 8, 48}, {0, 40, 48}, {0, 24, 48}},             // 2 ranks: one block, then five, then equal
      {{0, 8, 16, 48}, {0, 32, 40, 48}, {0, 16, 32, 48}},  // 3 ranks
  };
  for (const auto& cuts : moves) {
    const int ranks = static_cast<int>(cuts.front().size()) - 1;
    ThreadExchange exchange(ranks);
    std::vector<std::unique_ptr<SlabFft2d>> slabs;
    for (int r = 0; r < ranks; ++r)
      slabs.push_back(std::make_unique<SlabFft2d>(whole.fft, nx, ny, r, ranks, exchange.of(r), FFTW_ESTIMATE, cuts.front()));
    for (const std::vector<int>& first_row : cuts) {
      INFO(ranks << " ranks, cut at rows " << first_row[1]);
      std::vector<testing::SlabCheck> checks(static_cast<std::size_t>(ranks));
      std::vector<std::thread> threads;
      for (int r = 0; r < ranks; ++r)
        threads.emplace_back([&, r] {
          SlabFft2d& slab = *slabs[static_cast<std::size_t>(r)];
          slab.set_rows(first_row);
          checks[static_cast<std::size_t>(r)] = testing::check_slab(whole, slab);
        });
      for (std::thread& t : threads) t.join();
      CHECK_FALSE(exchange.mismatched);
      std::vector<int> covered(static_cast<std::size_t>(ny), 0);
      for (int r = 0; r < ranks; ++r) {
        const testing::SlabCheck& check = checks[static_cast<std::size_t>(r)];
        CHECK(check.rows.begin == first_row[static_cast<std::size_t>(r)]);
        CHECK(check.rows.end == first_row[static_cast<std::size_t>(r) + 1]);
        CHECK(check.spectrum_equal);
        CHECK(check.inverse_equal);
        for (int y = check.rows.begin; y < check.rows.end; ++y) covered[static_cast<std::size_t>(y)] += 1;
      }
      CHECK(std::all_of(covered.begin(), covered.end(), [](int k) { return k == 1; }));
    }
  }
}
