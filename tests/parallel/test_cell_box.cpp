// The boxes of cells (parallel::CellBox) by which each rank of a coupled run
// on a sea in slabs tells which of its cells no other rank's floe may share
// (FloeSeaContact::sum_coverage_by_owner; docs/parallel.md, stage eight,
// "Fewer pieces"): a box holds every cell of its list, across the grid's
// seams too, and visits each of its cells once; and, with ranks simulated
// in one process, a cell that pieces of floes of several ranks share is
// under another rank's box on every one of those ranks, so that it travels
// as pieces and is summed in the serial order; and that sending such a
// cell's pieces to the ranks whose floes' boxes cover it, its slab's rank
// and the sender (CellRoutes::open_shared, as FloeSeaContact names them)
// gives every rank that needs the cell's total every piece of it, so that
// each sums the serial sum (memcmp). The runs on real ranks are
// mpi.cell_routes_ranks_*, mpi.sea_ranks_equal_serial and
// mpi.slab_moves_equal_serial.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>
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

TEST_CASE("with ranks simulated in one process, the shared cells' pieces reach every rank that sums them, which sums the serial sum") {
  std::mt19937_64 rng(23);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const int nx = 96, ny = 80;
  for (int ranks : {2, 3, 4}) {
    // Floes as above, each on a random rank, one random value per piece;
    // the slabs: equal shares of the rows.
    std::vector<std::vector<std::uint32_t>> floe_cells;
    std::vector<std::vector<double>> floe_values;
    std::vector<int> owner;
    for (int i = 0; i < 60; ++i) {
      floe_cells.push_back(disc(unit(rng) * nx, unit(rng) * ny, 1.0 + 6.0 * unit(rng), nx, ny));
      floe_values.emplace_back();
      for (std::size_t k = 0; k < floe_cells.back().size(); ++k) floe_values.back().push_back((unit(rng) - 0.5) * std::exp(20.0 * unit(rng)));
      owner.push_back(static_cast<int>(rng() % static_cast<unsigned>(ranks)));
    }
    auto slab = [&](std::uint32_t c) { return static_cast<int>(c / static_cast<std::uint32_t>(nx)) * ranks / ny; };
    // The serial sums: floe by floe in floe order (the keys), from zero.
    std::vector<double> serial(static_cast<std::size_t>(nx * ny), 0.0);
    std::vector<std::set<int>> has(serial.size());
    for (std::size_t i = 0; i < floe_cells.size(); ++i)
      for (std::size_t k = 0; k < floe_cells[i].size(); ++k) {
        serial[floe_cells[i][k]] += floe_values[i][k];
        has[floe_cells[i][k]].insert(owner[i]);
      }
    std::vector<parallel::CellBox> boxes;
    for (const auto& cells : floe_cells) boxes.push_back(parallel::CellBox::of(cells, nx, ny));
    // Each rank's messages: per receiver, its pieces of its shared cells
    // (cell, key, value); its alone cells' totals to their slabs' ranks
    // (kept, on its own slab).
    struct Piece {
      std::uint32_t cell, key;
      double value;
    };
    std::vector<std::vector<Piece>> inbox(static_cast<std::size_t>(ranks));
    std::vector<std::map<std::uint32_t, double>> alone_inbox(static_cast<std::size_t>(ranks));
    std::vector<std::set<std::uint32_t>> shared_of(static_cast<std::size_t>(ranks));
    for (int rank = 0; rank < ranks; ++rank) {
      std::vector<std::set<int>> covered(serial.size());  // the other ranks whose floes' boxes cover the cell
      for (std::size_t i = 0; i < boxes.size(); ++i)
        if (owner[i] != rank)
          boxes[i].for_each(nx, ny, [](int) { return true; }, [&](std::uint32_t c) { covered[c].insert(owner[i]); });
      std::map<std::uint32_t, double> alone;
      for (std::size_t i = 0; i < floe_cells.size(); ++i) {
        if (owner[i] != rank) continue;
        for (std::size_t k = 0; k < floe_cells[i].size(); ++k) {
          const std::uint32_t c = floe_cells[i][k];
          if (covered[c].empty()) {
            alone[c] += floe_values[i][k];  // summed here, in floe order: the serial sum
            continue;
          }
          shared_of[static_cast<std::size_t>(rank)].insert(c);
          std::set<int> to = covered[c];
          to.insert(slab(c));
          to.insert(rank);
          for (int r : to) inbox[static_cast<std::size_t>(r)].push_back({c, static_cast<std::uint32_t>(i), floe_values[i][k]});
        }
      }
      for (const auto& [c, total] : alone) alone_inbox[static_cast<std::size_t>(slab(c))][c] = total;  // kept, or sent
    }
    // Each receiver sums its pieces of a cell from zero in key order; every
    // rank's shared cells and every slab's cells with pieces must get the
    // serial sum, to the bit.
    std::size_t checked = 0, mixed = 0;
    for (int rank = 0; rank < ranks; ++rank) {
      std::vector<Piece>& pieces = inbox[static_cast<std::size_t>(rank)];
      std::stable_sort(pieces.begin(), pieces.end(), [](const Piece& a, const Piece& b) { return a.key < b.key; });
      std::map<std::uint32_t, double> total;
      for (const Piece& p : pieces) total[p.cell] += p.value;
      for (std::uint32_t c : shared_of[static_cast<std::size_t>(rank)]) {
        REQUIRE(total.count(c) == 1);
        CHECK(std::memcmp(&total[c], &serial[c], sizeof(double)) == 0);
        ++checked;
        mixed += has[c].size() > 1 ? 1 : 0;
      }
      for (std::uint32_t c = 0; c < serial.size(); ++c) {
        if (slab(c) != rank || has[c].empty()) continue;
        const double got = total.count(c) ? total[c] : alone_inbox[static_cast<std::size_t>(rank)].at(c);
        CHECK(std::memcmp(&got, &serial[c], sizeof(double)) == 0);
      }
    }
    // Cells of several ranks' floes occur, whose sums in rank order differ
    // from the serial ones: the checks above could fail.
    std::size_t differs = 0;
    for (std::uint32_t c = 0; c < serial.size(); ++c) {
      if (has[c].size() < 2) continue;
      double by_rank = 0.0;
      for (int r = 0; r < ranks; ++r) {
        double part = 0.0;
        for (std::size_t i = 0; i < floe_cells.size(); ++i)
          if (owner[i] == r)
            for (std::size_t k = 0; k < floe_cells[i].size(); ++k)
              if (floe_cells[i][k] == c) part += floe_values[i][k];
        by_rank += part;
      }
      differs += std::memcmp(&by_rank, &serial[c], sizeof(double)) != 0 ? 1 : 0;
    }
    CHECK(mixed > 20);
    CHECK(differs > 0);
    CHECK(checked > mixed);
  }
}
