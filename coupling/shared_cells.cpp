#include "coupling/shared_cells.hpp"

#include <algorithm>
#include <cmath>

#include "core/error.hpp"

namespace floesim {

int piece_rows_of(double radius, double reach, double dy) {
  return static_cast<int>(std::ceil((radius + (1.0 + reach) * dy) / dy)) + 1;
}

std::vector<std::uint32_t> box_neighbours(std::span<const std::uint32_t> candidates, std::span<const int> owner, int rank,
                                          std::span<const int> first_row, std::span<const parallel::CellBox> box,
                                          const fluid::SurfaceGrid& grid, int own_rows) {
  FLOESIM_ASSERT(static_cast<std::size_t>(rank) + 1 < first_row.size());
  const int rows = grid.ny, lo = first_row[static_cast<std::size_t>(rank)],
            hi = first_row[static_cast<std::size_t>(rank) + 1];
  const auto columns = static_cast<std::uint32_t>(grid.nx);
  // The distance in rows from row y to the slab [lo, hi), on the circle.
  const auto distance = [&](int y) {
    if (lo >= hi) return rows;  // an empty slab: no pieces of its own
    if (y >= lo && y < hi) return 0;
    const int below = ((lo - y) % rows + rows) % rows, above = ((y - (hi - 1)) % rows + rows) % rows;
    return std::min(below, above);
  };
  std::vector<std::uint32_t> out;
  for (const std::uint32_t j : candidates) {
    const parallel::CellBox& b = box[j];
    if (owner[j] == rank || b.first_cell == parallel::CellBox::kNone) continue;
    // The box's rows as CellBox::for_each visits them: from the first
    // cell's row, offsets row_lo to row_hi, the seam crossed.
    const int row0 = static_cast<int>(b.first_cell / columns), count = std::min(b.row_hi - b.row_lo + 1, rows);
    for (int k = 0; k < count; ++k)
      if (distance(((row0 + b.row_lo + k) % rows + rows) % rows) <= own_rows) {
        out.push_back(j);
        break;
      }
  }
  return out;
}

void box_readers(const parallel::CellBox& b, int owner, std::span<const int> row_owner, int columns, int own_rows,
                 std::vector<int>& out) {
  if (b.first_cell == parallel::CellBox::kNone) return;
  const int rows = static_cast<int>(row_owner.size());
  // The box's rows widened by own_rows each way (box_neighbours' distance
  // <= own_rows from one of them), at most the whole circle; the owners of
  // those rows, which come in runs (the slabs are contiguous).
  const int row0 = static_cast<int>(b.first_cell / static_cast<std::uint32_t>(columns));
  const int count = std::min(std::min(b.row_hi - b.row_lo + 1, rows) + 2 * own_rows, rows);
  const int start = row0 + b.row_lo - own_rows;
  const std::size_t before = out.size();
  for (int k = 0; k < count; ++k) {
    const int r = row_owner[static_cast<std::size_t>(((start + k) % rows + rows) % rows)];
    if (r != owner && (out.size() == before || out.back() != r)) out.push_back(r);
  }
  std::sort(out.begin() + static_cast<std::ptrdiff_t>(before), out.end());
  out.erase(std::unique(out.begin() + static_cast<std::ptrdiff_t>(before), out.end()), out.end());
}

bool boxes_meet(const parallel::CellBox& a, const parallel::CellBox& b, int columns, int rows) {
  if (a.first_cell == parallel::CellBox::kNone || b.first_cell == parallel::CellBox::kNone) return false;
  // Two arcs [a0, a0 + la) and [b0, b0 + lb) of a circle of n meet when
  // one starts within the other.
  const auto meet = [](int a0, int la, int b0, int lb, int n) {
    if (la >= n || lb >= n) return true;
    const int d = ((b0 - a0) % n + n) % n;
    return d < la || (n - d) % n < lb;
  };
  const auto nx = static_cast<std::uint32_t>(columns);
  const int ay = static_cast<int>(a.first_cell / nx) + a.row_lo, by = static_cast<int>(b.first_cell / nx) + b.row_lo;
  const int ax = static_cast<int>(a.first_cell % nx) + a.column_lo, bx = static_cast<int>(b.first_cell % nx) + b.column_lo;
  return meet(ay, a.row_hi - a.row_lo + 1, by, b.row_hi - b.row_lo + 1, rows) &&
         meet(ax, a.column_hi - a.column_lo + 1, bx, b.column_hi - b.column_lo + 1, columns);
}

void mark_shared_cells(std::span<const std::uint32_t> floes, std::span<const parallel::CellBox> box,
                       std::span<const int> owner, int columns, int rows, std::span<const std::uint8_t> interior_row,
                       std::span<std::uint8_t> kind, std::uint8_t open, std::uint8_t shared, std::size_t rank_words,
                       SharedMarks& marks) {
  marks.painted.clear();
  marks.shared_ranks.clear();
  marks.shared_at.resize(static_cast<std::size_t>(columns) * static_cast<std::size_t>(rows), 0);
  std::uint32_t count = 0;
  for (const std::uint32_t j : floes) {
    const std::size_t word = static_cast<std::size_t>(owner[j]) / 64;
    const std::uint64_t bit = std::uint64_t{1} << (static_cast<unsigned>(owner[j]) % 64);
    box[j].for_each(
        columns, rows, [&](int y) { return interior_row[static_cast<std::size_t>(y)] == 0; },
        [&](std::uint32_t c) {
          if (kind[c] == open) {
            kind[c] = shared;
            marks.painted.push_back(c);
            marks.shared_at[c] = ++count;
            marks.shared_ranks.resize(count * rank_words, 0);
          }
          marks.shared_ranks[(marks.shared_at[c] - 1) * rank_words + word] |= bit;
        });
  }
}

}  // namespace floesim
