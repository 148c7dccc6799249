// The boxes of cells (parallel::CellBox) by which each rank of a coupled run
// on a sea in slabs tells which of its cells no other rank's floe may share
// (FloeSeaContact::sum_coverage_by_owner; docs/parallel.md, stage eight,
// "Fewer pieces"): a box holds every cell of its list, across the grid's
// seams too, and visits each of its cells once; and, with ranks simulated
// in one process, a cell that pieces of floes of several ranks share is
// under another rank's box on every one of those ranks, so that it travels
// as pieces and is summed in the serial order. The runs on real ranks are
// mpi.sea_ranks_equal_serial and mpi.slab_moves_equal_serial.
#include <doctest/doctest.h>

#include <algorithm>
#include <random>
#include <set>
#include <vector>

#include "parallel/cell_routes.hpp"

TEST_SUITE_BEGIN("mpi");

using namespace floesim;

namespace {

// The cells of a disc of radius r (cells) about (x, y) on a periodic grid,
// in increasing cell order (as a floe's pieces are).
std::vector<std::uint32_t> disc(double x, double y, double r, int nx, int ny) {
  std::set<std::uint32_t> cells;
  for (int dy = -static_cast<int>(r) - 1; dy <= static_cast<int>(r) + 1; ++dy)
    for (int dx = -static_cast<int>(r) - 1; dx <= static_cast<int>(r) + 1; ++dx) {
      if (dx * dx + dy * dy > r * r) continue;
      const int cx = ((static_cast<int>(x) + dx) % nx + nx) % nx, cy = ((static_cast<int>(y) + dy) % ny + ny) % ny;
      cells.insert(static_cast<std::uint32_t>(cy * nx + cx));
    }
  return {cells.begin(), cells.end()};
}

std::vector<std::uint32_t> visited(const parallel::CellBox& box, int nx, int ny) {
  std::vector<std::uint32_t> out;
  box.for_each(nx, ny, [](int) { return true; }, [&](std::uint32_t c) { out.push_back(c); });
  return out;
}

}  // namespace

TEST_CASE("a cell box holds every cell of its list, across the grid's seams, each visited once") {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (auto [nx, ny] : {std::pair{37, 23}, std::pair{64, 64}, std::pair{5, 300}}) {
    int crossing = 0;
    for (int trial = 0; trial < 200; ++trial) {
      const double r = 0.5 + unit(rng) * std::min(nx, ny) / 3.0;
      const std::vector<std::uint32_t> cells = disc(unit(rng) * nx, unit(rng) * ny, r, nx, ny);
      const parallel::CellBox box = parallel::CellBox::of(cells, nx, ny);
      CHECK(box.first_cell == cells.front());
      std::vector<std::uint32_t> seen = visited(box, nx, ny);
      const std::size_t count = seen.size();
      std::sort(seen.begin(), seen.end());
      CHECK(std::unique(seen.begin(), seen.end()) == seen.end());  // each cell once
      CHECK(count <= static_cast<std::size_t>(nx) * static_cast<std::size_t>(ny));
      for (std::uint32_t c : cells) CHECK(std::binary_search(seen.begin(), seen.end(), c));
      // Across a seam the box is the short way round, not the whole grid.
      const bool wraps = box.row_lo < 0 || box.column_lo < 0;
      if (wraps && count < static_cast<std::size_t>(nx) * static_cast<std::size_t>(ny) / 2) ++crossing;
    }
    CHECK(crossing > 10);
  }
  // An empty list has no box; a list in any order has the box of its cells.
  CHECK(visited(parallel::CellBox::of({}, 8, 8), 8, 8).empty());
  const std::vector<std::uint32_t> scattered{63, 0, 7, 56};  // the four corners of an 8 x 8 grid
  const std::vector<std::uint32_t> corners = visited(parallel::CellBox::of(scattered, 8, 8), 8, 8);
  CHECK(corners.size() == 4);
}

TEST_CASE("with ranks simulated in one process, a cell shared by floes of several ranks is under another rank's box on each") {
  std::mt19937_64 rng(17);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const int nx = 96, ny = 80;
  for (int ranks : {2, 3}) {
    // Floes: discs at random places (some across the seams), each on a
    // random rank; every cell's ranks with pieces there (the truth).
    std::vector<std::vector<std::uint32_t>> floe_cells;
    std::vector<int> owner;
    for (int i = 0; i < 60; ++i) {
      floe_cells.push_back(disc(unit(rng) * nx, unit(rng) * ny, 1.0 + 6.0 * unit(rng), nx, ny));
      owner.push_back(static_cast<int>(rng() % static_cast<unsigned>(ranks)));
    }
    std::vector<std::set<int>> has(static_cast<std::size_t>(nx * ny));
    for (std::size_t i = 0; i < floe_cells.size(); ++i)
      for (std::uint32_t c : floe_cells[i]) has[c].insert(owner[i]);
    std::vector<parallel::CellBox> boxes;
    for (const auto& cells : floe_cells) boxes.push_back(parallel::CellBox::of(cells, nx, ny));
    std::size_t shared = 0, alone = 0;
    for (int rank = 0; rank < ranks; ++rank) {
      // What rank `rank` paints: the other ranks' floes' boxes.
      std::vector<std::uint8_t> painted(static_cast<std::size_t>(nx * ny), 0);
      for (std::size_t i = 0; i < boxes.size(); ++i)
        if (owner[i] != rank) boxes[i].for_each(nx, ny, [](int) { return true; }, [&](std::uint32_t c) { painted[c] = 1; });
      for (std::size_t c = 0; c < has.size(); ++c) {
        if (!has[c].count(rank)) continue;
        if (has[c].size() > 1) {
          CHECK(painted[c] == 1);  // truly shared: sent as pieces
          ++shared;
        } else if (!painted[c]) {
          ++alone;  // this rank's alone: summed by it
        }
      }
    }
    // Both kinds occur, so the check above could fail.
    CHECK(shared > 20);
    CHECK(alone > 1000);
  }
}
