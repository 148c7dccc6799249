#pragma once
// Sums per grid cell over the ranks, made by each cell's owner
// (docs/parallel.md, stages five and eight). The rows of the grid are shared
// among the ranks in slabs (the spectral sea's: rank r holds rows
// [first_row[r], first_row[r + 1])), and the rank whose slab holds a cell's
// row owns the cell. Each rank has, for a list of distinct cells, pieces:
// numbers to be summed over the ranks, each with an order key. The owner
// receives every rank's pieces of its cells and adds them from zero in the
// order of their keys (equal keys in rank order, then in the sender's
// order). So a total does not depend on timing, nor on which rank sent which
// piece: with keys that order the pieces as a serial loop meets them, it is
// that loop's sum to the bit (a floating-point sum depends on its order, and
// the order is the serial one whatever the ranks). With one piece a cell and
// equal keys (the per-cell overloads) it is stage three's merge: each rank's
// part added in rank order. The totals go back only to the ranks that sent
// pieces of the cell.
//
// One round of sums (one contact evaluation), every call collective:
//   open(cells, pieces)  this rank's cells with their pieces' keys and a
//                        first set of values, each cell to its owner: two
//                        calls (the counts, then the lists)
//   reply(w, out)        the owners' totals of value w back to the senders,
//                        in the order of their cells: one call
//   add(values, extra)   new values for the same pieces, and one number from
//                        every rank summed over all ranks: one call
// Between the calls, owned() and total() give the owner's cells and totals.

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "parallel/comm.hpp"

namespace floesim::parallel {

// Per row of the grid, the rank whose slab holds it, for slabs given by
// their first rows (ranks + 1 values, the last the row count): rank r's slab
// is rows [first_row[r], first_row[r + 1]).
std::vector<int> row_owners(std::span<const int> first_row);

// The row of a periodic grid of `rows` rows of height dy (its first row at
// y = 0) that holds y, the grid's seam crossed: floor(y / dy) modulo rows.
// The one rule that places a floe's centroid in a slab, for the coupling's
// owners (MovingFootprints) and the drift's and detection's
// (FloeOwners with slabs), so that the two agree to the bit.
inline int grid_row(double y, double dy, int rows) {
  const double row = std::floor(y / dy);
  const double wrapped = row - static_cast<double>(rows) * std::floor(row / rows);
  return std::min(static_cast<int>(wrapped), rows - 1);
}

class CellRoutes {
public:
  CellRoutes() = default;
  // first_row: ranks + 1 values, rank r's slab holds rows [first_row[r],
  // first_row[r + 1]); cell c lies in row c / columns.
  CellRoutes(std::vector<int> first_row, std::size_t columns);
  bool empty() const { return first_row_.empty(); }
  // The rank whose slab holds `cell`.
  int owner(std::uint32_t cell) const { return row_owner_[cell / columns_]; }
  // Per row: whether every row within `reach` rows of it (the grid's seam
  // crossed) lies in its slab. When every rank's cells lie within `reach`
  // rows of its own slab, a cell in such a row gets parts from its owner
  // alone: its total is the owner's part, with nothing to route.
  std::vector<std::uint8_t> interior_rows(int reach) const;

  // Sends each of `cells` (distinct) with its pieces to its owner: cell
  // cells[j] has the pieces p in [first[j], first[j + 1]), each with the
  // order key keys[p] and `width` values parts[p * width + w]; the owner sums
  // every rank's pieces of a cell from zero in key order (total()).
  void open(const Communicator& comm, std::span<const std::uint32_t> cells, std::span<const std::uint32_t> first,
            std::span<const std::uint32_t> keys, std::span<const double> parts, int width);
  // One piece a cell, all keys equal: the parts summed in rank order
  // (parts[k * width + w] for cells[k]).
  void open(const Communicator& comm, std::span<const std::uint32_t> cells, std::span<const double> parts, int width);
  // The owners' totals of value w back to the ranks that sent the cells:
  // out[k] for this rank's cells[k] of the last open().
  void reply(const Communicator& comm, int w, std::span<double> out);
  // New values (`width` a piece) for the last open()'s pieces, summed by
  // their owners in the order open() sums them; returns the sum of `extra`
  // over the ranks, in rank order from zero (the same on every rank).
  double add(const Communicator& comm, std::span<const double> parts, int width, double extra);
  // The cells this rank owns that some rank sent parts for in the last open(),
  // in the order they first arrived (rank order), and their totals.
  std::span<const std::uint32_t> owned() const { return owned_; }
  double total(std::size_t j, int w) const { return totals_[j * static_cast<std::size_t>(width_) + static_cast<std::size_t>(w)]; }

private:
  std::vector<int> first_row_, row_owner_;
  std::size_t columns_ = 1;
  // This rank's cells grouped by owner (route_[k]: the index in open()'s
  // cells of the k-th sent), their pieces' offsets (first_), and the counts
  // each way: cells (sent_, received_) and pieces (sent_pieces_,
  // received_pieces_).
  std::vector<std::uint32_t> route_, first_;
  std::vector<std::size_t> sent_, received_, sent_pieces_, received_pieces_;
  std::vector<std::uint32_t> from_;   // per received cell, in rank order: its index in owned_
  std::vector<std::uint32_t> owned_;
  std::vector<std::uint32_t> slot_;   // per grid cell: 1 + its index in owned_, 0: none
  // The received pieces (in rank order, then the senders' order) in the
  // order they are summed: owned cell j's are order_[order_first_[j]] up to
  // order_[order_first_[j + 1]], by key.
  std::vector<std::uint32_t> order_, order_first_;
  std::vector<double> values_;        // per received piece, `width_` values
  std::vector<double> totals_;
  int width_ = 0;
  // Sums owned cell j's values w from zero in key order, into totals_.
  void sum_pieces();
  std::vector<std::byte> send_, receive_;  // kept from one round to the next
};

}  // namespace floesim::parallel
