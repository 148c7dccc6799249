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
// A cell whose pieces all lie on one rank (the caller knows it: no other
// rank has pieces there) needs no pieces sent: that rank sums them itself,
// from zero in key order, which is the owner's sum of the same pieces to the
// bit, and sends the owner the total of the value it needs (`alone` cells:
// their cells with open(), one total each with add()).
//
// A cell's total can also be made by every rank that needs it, from the
// pieces themselves (open_shared): each sender names the cell's receivers
// (the ranks with pieces there, itself included, and the cell's owner), each
// of which receives every sender's pieces of the cell and sums them from
// zero in key order, as the owner would: the same terms in the same order,
// the same bits on every receiver. No totals go back (no reply()): one round
// trip less, for the bytes of the pieces sent to more than one rank.
//
// On a grid that every rank holds whole (a sea not in slabs, replicated on
// every rank: replicated()), every rank needs every cell's total: a cell's
// receivers are then every rank (the caller names them), and an alone
// cell goes to every other rank (4 bytes a cell, then its total with add(),
// 8 bytes), where alone_owned() lists it. The sums are made by the same
// code (sum_pieces), so a total is the serial sum to the bit there too.
//
// One round of sums (one contact evaluation), every call collective:
//   open(cells, pieces, alone)  this rank's cells with their pieces' keys
//                        and a first set of values, each cell to its
//                        owner, and the cells it sums alone: two calls (the
//                        counts, then the lists)
//   or open_shared(cells, pieces, receivers, alone)  each cell to its
//                        receivers: the same two calls
//   reply(w, out)        after open(), the owners' totals of value w back
//                        to the senders, in the order of their cells: one call
//   add(values, extra, alone totals)  new values for the same pieces, one
//                        number from every rank summed over all ranks, and
//                        the alone cells' totals: one call
//   answer(slab values, out, alone out)  in slabs, after open() or
//                        open_shared(): per cell a value its owner computed
//                        (from the totals: a response), back along the
//                        open's routes to every rank that sent the cell,
//                        pieces or alone: one call
// The routes hold for any number of add() and answer() calls until the next
// open: the implicit step's products (the footprints fixed for a solve) open
// them once, then send a product 8 bytes a piece (add(), width 1) and 8
// bytes a cell back (answer()).
// Between the calls, owned() and total() give the cells received and their
// totals (index() finds a cell there), after add() alone_owned() and
// alone_total() the alone cells'.

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "parallel/comm.hpp"

namespace floesim::parallel {

// A piece's order key: the pieces of a cell are summed in ascending keys.
// 64 bits, so that a key can be a pair each sender computes alone (the
// contact's (first cell, floe index), FloeSeaContact::serial_key).
using PieceKey = std::uint64_t;

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

// Where a list of cells lies on a periodic grid, coarsely: a box of rows
// and columns, each range taken from the first cell's row and column
// (offsets lo to hi, the grid's seam crossed: modulo the row or column
// count), that holds every cell of the list. 12 bytes, sent as they are:
// every rank learns where every floe's pieces lie (FloeSeaContact), and
// a cell outside every other rank's floes' boxes holds this rank's pieces
// alone. Grids of at most kMaxSide rows and columns (offsets in 16 bits).
struct CellBox {
  static constexpr std::uint32_t kNone = 0xffffffffu;
  static constexpr int kMaxSide = 32768;
  std::uint32_t first_cell = kNone;  // the list's first cell; kNone: an empty list
  std::int16_t row_lo = 0, row_hi = -1, column_lo = 0, column_hi = -1;
  // The box of `cells` (any order, the first one first) on a grid of
  // `columns` x `rows` cells (each at most kMaxSide).
  static CellBox of(std::span<const std::uint32_t> cells, int columns, int rows);
  // Calls visit(cell) for every cell of the box in rows where
  // keep_row(row) is true, each cell once.
  template <class KeepRow, class Visit>
  void for_each(int columns, int rows, KeepRow keep_row, Visit visit) const {
    if (first_cell == kNone) return;
    const int row0 = static_cast<int>(first_cell / static_cast<std::uint32_t>(columns));
    const int column0 = static_cast<int>(first_cell % static_cast<std::uint32_t>(columns));
    const int row_count = std::min(row_hi - row_lo + 1, rows), column_count = std::min(column_hi - column_lo + 1, columns);
    // The first column wrapped once; the others step from it (at most one
    // seam crossed: column_count <= columns), with no division a cell.
    const int x0 = ((column0 + column_lo) % columns + columns) % columns;
    for (int dy = 0; dy < row_count; ++dy) {
      const int y = ((row0 + row_lo + dy) % rows + rows) % rows;
      if (!keep_row(y)) continue;
      const std::size_t base = static_cast<std::size_t>(y) * static_cast<std::size_t>(columns);
      for (int dx = 0, x = x0; dx < column_count; ++dx, x = x + 1 == columns ? 0 : x + 1)
        visit(static_cast<std::uint32_t>(base + static_cast<std::size_t>(x)));
    }
  }
};

class CellRoutes {
public:
  CellRoutes() = default;
  // first_row: ranks + 1 values, rank r's slab holds rows [first_row[r],
  // first_row[r + 1]); cell c lies in row c / columns.
  CellRoutes(std::vector<int> first_row, std::size_t columns);
  // Every one of `ranks` ranks holds every cell of a grid of `columns` x
  // `rows` cells (no slabs): open_shared() only, no open() or reply().
  static CellRoutes replicated(int ranks, std::size_t columns, std::size_t rows);
  bool empty() const { return first_row_.empty() && !replicated_; }
  // Every key of the next opens is below `bound` (the same on every rank):
  // when bound <= 2^32 the keys travel as 4 bytes, else 8 (the default).
  void set_largest_key(PieceKey bound) { key_bytes_ = bound <= (PieceKey{1} << 32) ? 4 : 8; }
  bool replicated() const { return replicated_; }
  // The rank whose slab holds `cell` (in slabs).
  int owner(std::uint32_t cell) const { return row_owner_[cell / columns_]; }
  // Whether `rank` holds `cell`: the cell's owner does, in slabs; every
  // rank does, replicated.
  bool holds(int rank, std::uint32_t cell) const { return replicated_ || owner(cell) == rank; }
  // Per row: whether every row within `reach` rows of it (the grid's seam
  // crossed) lies in its slab (replicated: none, no rank's cells being its
  // alone). When every rank's cells lie within `reach`
  // rows of its own slab, a cell in such a row gets parts from its owner
  // alone: its total is the owner's part, with nothing to route.
  std::vector<std::uint8_t> interior_rows(int reach) const;

  // Sends each of `cells` (distinct) with its pieces to its owner: cell
  // cells[j] has the pieces p in [first[j], first[j + 1]), each with the
  // order key keys[p] and `width` values parts[p * width + w]; the owner sums
  // every rank's pieces of a cell from zero in key order (total()). A
  // sender's pieces of a cell come in key order (the owner merges the
  // senders' runs). `alone`: cells (distinct, none of them in `cells` of
  // any rank) where this rank alone has pieces, summed by itself; their
  // owners (replicated: every other rank) receive them now and their
  // totals with the next add().
  void open(const Communicator& comm, std::span<const std::uint32_t> cells, std::span<const std::uint32_t> first,
            std::span<const PieceKey> keys, std::span<const double> parts, int width,
            std::span<const std::uint32_t> alone = {});
  // As open(), but cell cells[j] goes to the ranks receivers[q] for q in
  // [receivers_first[j], receivers_first[j + 1]) (distinct; this rank among
  // them if it needs the total) instead of its owner, and each of them sums
  // every sender's pieces of it in key order (total(index(cell), w)). Every
  // rank with pieces of a cell must name, for that cell, every rank that
  // needs its total: then each of them gets every piece. No reply(); add()
  // sends the new values along the same routes.
  void open_shared(const Communicator& comm, std::span<const std::uint32_t> cells, std::span<const std::uint32_t> first,
                   std::span<const PieceKey> keys, std::span<const double> parts, int width,
                   std::span<const std::uint32_t> receivers_first, std::span<const int> receivers,
                   std::span<const std::uint32_t> alone = {});
  // One piece a cell, all keys equal: the parts summed in rank order
  // (parts[k * width + w] for cells[k]).
  void open(const Communicator& comm, std::span<const std::uint32_t> cells, std::span<const double> parts, int width);
  // The owners' totals of value w back to the ranks that sent the cells:
  // out[k] for this rank's cells[k] of the last open() (not open_shared()).
  void reply(const Communicator& comm, int w, std::span<double> out);
  // New values (`width` a piece) for the last open()'s pieces, summed by
  // their owners in the order open() sums them, and one total for each of
  // its `alone` cells (alone_totals[k] for alone[k]) to their owners;
  // returns the sum of `extra` over the ranks, in rank order from zero (the
  // same on every rank).
  double add(const Communicator& comm, std::span<const double> parts, int width, double extra,
             std::span<const double> alone_totals = {});
  // In slabs, after open() or open_shared() (whose every cell names its
  // owner among its receivers): each owner's values of its slab's cells
  // back to the ranks that sent them in the open, pieces or alone.
  // `slab`: this rank's slab's rows of a per-cell field, from its first row
  // (rows x columns values, x fastest), of which the cells other ranks sent
  // here are read. out[k] gets the owner's value of this rank's cells[k] of
  // the open, alone_out[j] of its alone[j] (a cell this rank owns comes from
  // its own `slab`, by the same route). One collective call (its sizes known
  // from the open): 8 bytes a cell from another rank's slab.
  void answer(const Communicator& comm, std::span<const double> slab, std::span<double> out,
              std::span<double> alone_out);
  // The bytes this rank received from the other ranks in the last open(),
  // open_shared(), reply(), add() or answer() (its own part not counted).
  std::size_t received_from_others() const;
  // The cells some rank sent this rank pieces of in the last open() (those
  // it owns) or open_shared() (those it was named a receiver of), in the
  // order they first arrived (rank order), and their totals.
  std::span<const std::uint32_t> owned() const { return owned_; }
  double total(std::size_t j, int w) const { return totals_[j * static_cast<std::size_t>(width_) + static_cast<std::size_t>(w)]; }
  // The place of `cell` in owned(); kNotHeld if no rank sent it here.
  static constexpr std::size_t kNotHeld = static_cast<std::size_t>(-1);
  std::size_t index(std::uint32_t cell) const { return slot_[cell] == 0 ? kNotHeld : slot_[cell] - 1; }
  // The cells this rank owns that some rank summed alone in the last open()
  // (in rank order, then the sender's), and after add() their totals.
  std::span<const std::uint32_t> alone_owned() const { return alone_owned_; }
  double alone_total(std::size_t j) const { return alone_totals_[j]; }

private:
  std::vector<int> first_row_, row_owner_;
  std::size_t columns_ = 1, rows_ = 0;
  int ranks_ = 0;
  bool replicated_ = false;
  // This rank's cells grouped by receiver (route_[k]: the index in open()'s
  // cells of the k-th sent; alone_route_ the same for its alone cells, by
  // owner, replicated by every other rank),
  // their pieces' offsets (first_), and the counts each way: cells (sent_,
  // received_), pieces (sent_pieces_, received_pieces_) and alone cells
  // (sent_alone_, received_alone_).
  std::vector<std::uint32_t> route_, alone_route_, first_;
  // Per entry of route_, whether its receiver is the cell's owner (in
  // slabs: then answer() brings the owner's value back along it); per rank,
  // the values answer() receives from it (this rank's cells it owns and its
  // alone cells there) and sends to it (the cells it sent here that this
  // rank owns, and its alone cells here).
  std::vector<std::uint8_t> route_to_owner_;
  std::vector<std::size_t> answers_in_, answers_out_;
  int rank_ = 0;  // this rank, at the last open
  std::size_t alone_count_ = 0;  // the last open's alone cells
  std::vector<std::size_t> sent_, received_, sent_pieces_, received_pieces_, sent_alone_, received_alone_;
  std::vector<std::uint32_t> from_;   // per received cell, in rank order: its index in owned_
  std::vector<std::uint32_t> count_;  // per received cell: its pieces' count
  std::vector<std::uint32_t> owned_, alone_owned_;
  std::vector<std::uint32_t> slot_;   // per grid cell: 1 + its index in owned_, 0: none
  // The received pieces (in rank order, then the senders' order) in the
  // order they are summed: owned cell j's are order_[order_first_[j]] up to
  // order_[order_first_[j + 1]], by key; keys_ per received piece.
  std::vector<std::uint32_t> order_, order_first_;
  std::vector<PieceKey> keys_;
  std::vector<double> values_;        // per received piece, `width_` values
  std::vector<double> totals_, alone_totals_;
  int width_ = 0;
  std::size_t key_bytes_ = sizeof(PieceKey);  // a key's bytes on the wire (set_largest_key)
  // Sums owned cell j's values w from zero in key order, into totals_.
  void sum_pieces();
  // open() and open_shared(): cells[k] to receivers[receivers_first[k]...].
  void send_pieces(const Communicator& comm, std::span<const std::uint32_t> cells, std::span<const std::uint32_t> first,
                   std::span<const PieceKey> keys, std::span<const double> parts, int width,
                   std::span<const std::uint32_t> receivers_first, std::span<const int> receivers,
                   std::span<const std::uint32_t> alone);
  bool to_owners_ = true;  // the last open was open(): reply() may follow
  std::vector<std::uint32_t> owner_first_;  // open()'s receivers: each cell's owner
  std::vector<int> owner_list_;
  std::vector<std::byte> send_, receive_;  // kept from one round to the next
  std::vector<std::size_t> bytes_, receive_bytes_;
};

}  // namespace floesim::parallel
