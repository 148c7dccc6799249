// The strips of stage six (parallel/place.hpp) without ranks: the cut by
// cost gives every strip an equal share of the cost, within one item's cost,
// and every item to one strip; the owners follow the cuts and wrap a
// periodic box. (Detection by place against the serial detection is in
// test_comm.cpp; the run on real ranks, with the strips moved by measured
// cost, is mpi.ranks_equal_serial.)
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>

#include "parallel/cell_routes.hpp"
#include "parallel/place.hpp"

TEST_SUITE_BEGIN("mpi");

using namespace floesim;

namespace {
// The strip of y for the cuts (the rule FloeOwners::assign applies).
int strip(const std::vector<double>& cuts, double y) {
  return static_cast<int>(std::upper_bound(cuts.begin(), cuts.end(), y) - cuts.begin());
}
}  // namespace

TEST_CASE("the cut by cost gives each strip an equal share of the cost and every item one strip") {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> place(0.0, 1000.0), unit(0.0, 1.0);
  for (const std::size_t n : {0u, 1u, 5u, 200u, 3001u}) {
    // Very unequal costs: most items cost 1, those above y = 800 cost 50,
    // a few cost 0 (static floes), and the items are in no order.
    std::vector<double> y(n), cost(n);
    for (std::size_t i = 0; i < n; ++i) {
      y[i] = place(rng);
      cost[i] = y[i] > 800.0 ? 50.0 : unit(rng) < 0.05 ? 0.0 : 1.0;
    }
    const double total = std::accumulate(cost.begin(), cost.end(), 0.0);
    const double largest = n ? *std::max_element(cost.begin(), cost.end()) : 0.0;
    for (const int ranks : {1, 2, 3, 7, 16}) {
      CAPTURE(n);
      CAPTURE(ranks);
      const std::vector<double> cuts = parallel::cut_by_cost(y, cost, ranks);
      REQUIRE(cuts.size() == static_cast<std::size_t>(ranks - 1));
      CHECK(std::is_sorted(cuts.begin(), cuts.end()));
      std::vector<double> share(static_cast<std::size_t>(ranks), 0.0);
      std::vector<std::size_t> items(static_cast<std::size_t>(ranks), 0);
      for (std::size_t i = 0; i < n; ++i) {
        const int r = strip(cuts, y[i]);
        REQUIRE(r >= 0);
        REQUIRE(r < ranks);
        share[static_cast<std::size_t>(r)] += cost[i];
        ++items[static_cast<std::size_t>(r)];
      }
      CHECK(std::accumulate(items.begin(), items.end(), std::size_t{0}) == n);  // every item, once
      for (const double s : share) CHECK(std::abs(s - total / ranks) <= largest * (1.0 + 1e-12));
      // Not equal counts: with 2 strips and the costly top fifth, the cut lies
      // well below the median (the top fifth holds 50/(50 + 4) of the cost per
      // unit of y).
      if (ranks == 2 && n > 1000) CHECK(cuts[0] > 800.0);
    }
  }
}

TEST_CASE("floe owners: equal counts at the start, the cuts' strips after, wrapped in a periodic box") {
  Floes floes;
  const double ys[] = {-150.0, 10.0, 20.0, 30.0, 40.0, 260.0};  // the first and last wrap into [0, 200)
  for (const double y : ys) {
    FloeState s{};
    s.y = y;
    floes.state.push_back(s);
    floes.thickness.push_back(1.0);  // Floes::size() counts these
  }
  contact::Domain box{true, 0.0, 200.0, 0.0, 200.0};
  parallel::FloeOwners owners(1, 2, box);
  CHECK(owners.place(floes.state[0]) == 50.0);
  CHECK(owners.place(floes.state[5]) == 60.0);
  owners.assign(floes);  // equal counts: {10, 20, 30} and {40, 50, 60}
  CHECK(std::vector<int>(owners.owner().begin(), owners.owner().end()) == std::vector<int>{1, 0, 0, 0, 1, 1});
  CHECK(owners.mine() == std::vector<std::uint32_t>{0, 4, 5});
  owners.set_cuts({25.0});
  owners.assign(floes);
  CHECK(std::vector<int>(owners.owner().begin(), owners.owner().end()) == std::vector<int>{1, 0, 0, 1, 1, 1});
  floes.state[1].y = 199.0;  // a floe crosses the cut: it migrates to rank 1
  owners.assign(floes);
  CHECK(owners.owner()[1] == 1);
  CHECK(owners.mine() == std::vector<std::uint32_t>{0, 1, 3, 4, 5});
}
// Stage seven: the rows cut in whole blocks by cost (parallel::cut_rows_by_cost).
TEST_CASE("the rows cut in blocks by cost: whole blocks, every block once, one block at least a rank, equal within a block") {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (const int rows : {16, 45, 128, 512}) {
    // A uniform cost a row (the sea) plus a heavy band (floes packed there).
    std::vector<double> cost(static_cast<std::size_t>(rows));
    for (int y = 0; y < rows; ++y) cost[static_cast<std::size_t>(y)] = 1.0 + (y < rows / 3 ? 6.0 * unit(rng) : 0.0);
    const int blocks = (rows + 7) / 8;
    for (const int ranks : {1, 2, 3, 5}) {
      if (ranks > blocks) continue;
      INFO(rows << " rows, " << ranks << " ranks");
      const std::vector<int> first = parallel::cut_rows_by_cost(cost, 8, ranks);
      REQUIRE(first.size() == static_cast<std::size_t>(ranks) + 1);
      CHECK(first.front() == 0);
      CHECK(first.back() == rows);
      double total = 0.0, block_cost = 0.0;
      for (int b = 0; b < blocks; ++b) {
        double c = 0.0;
        for (int y = 8 * b; y < std::min(rows, 8 * b + 8); ++y) c += cost[static_cast<std::size_t>(y)];
        block_cost = std::max(block_cost, c);
        total += c;
      }
      for (int r = 0; r < ranks; ++r) {
        const int a = first[static_cast<std::size_t>(r)], e = first[static_cast<std::size_t>(r) + 1];
        CHECK(e - a >= std::min(8, rows - a));  // one block at least
        if (r > 0) CHECK(a % 8 == 0);           // whole blocks
        const double slab = std::accumulate(cost.begin() + a, cost.begin() + e, 0.0);
        CHECK(std::abs(slab - total / ranks) <= block_cost);
      }
      // The heavy third holds more than its share of the rows on 2 ranks:
      // the first slab is narrower than half.
      if (ranks == 2 && rows >= 128) CHECK(first[1] < rows / 2);
    }
  }
  // All the cost in one block: every slab still gets a block.
  std::vector<double> spike(64, 0.0);
  spike[20] = 1.0;
  const std::vector<int> first = parallel::cut_rows_by_cost(spike, 8, 4);
  REQUIRE(first.size() == 5);
  for (std::size_t r = 0; r < 4; ++r) {
    CHECK(first[r] % 8 == 0);
    CHECK(first[r + 1] - first[r] >= 8);
  }
  CHECK(first.back() == 64);
}

// Stage seven: with slabs, a floe's owner is its centroid's row's slab
// (parallel::grid_row, the rule MovingFootprints::set_owners applies for the
// coupling, so the two agree on every floe), and the strips' cuts in y are
// the slabs' boundaries.
TEST_CASE("floe owners with slabs: the owner is the slab of the centroid's row, the cuts its boundaries") {
  Floes floes;
  // Grid: 32 rows of 6.25 m (200 m, periodic); slabs {0, 8, 24, 32}.
  const double ys[] = {0.0, 49.999, 50.0, 149.99, 150.0, 199.99, -1.0, 201.0, 55.0};
  for (const double y : ys) {
    FloeState s{};
    s.y = y;
    floes.state.push_back(s);
    floes.thickness.push_back(1.0);
  }
  contact::Domain box{true, 0.0, 200.0, 0.0, 200.0};
  parallel::FloeOwners owners(1, 3, box);
  owners.set_slabs({{0, 8, 24, 32}, 6.25, 8});
  CHECK(owners.cuts() == std::vector<double>{50.0, 150.0});
  owners.assign(floes);
  const std::vector<int> rows = parallel::row_owners(std::vector<int>{0, 8, 24, 32});
  for (std::size_t i = 0; i < floes.size(); ++i) {
    INFO("y = " << ys[i]);
    CHECK(owners.owner()[i] == rows[static_cast<std::size_t>(parallel::grid_row(ys[i], 6.25, 32))]);
    // The same as the strip of the wrapped y between the cuts.
    CHECK(owners.owner()[i] == strip(owners.cuts(), owners.place(floes.state[i])));
  }
  CHECK(std::vector<int>(owners.owner().begin(), owners.owner().end()) == std::vector<int>{0, 0, 1, 1, 2, 2, 2, 0, 1});
  CHECK(owners.mine() == std::vector<std::uint32_t>{2, 3, 8});
}
TEST_SUITE_END();
