// The floe–sea contact on several ranks: the owners' loads and water
// velocities to every rank (docs/parallel.md, stage two), and the contact
// evaluated by owner (stage three; FloeSeaContact::by_owner): the sums into
// the cells that the law needs before it (the coverage Phi_c) and that it
// gives after it (the cells' sum of a_k u_k^2 and the pressure).
//
// The serial loop adds a cell's pieces floe by floe in order_ (every dynamic
// floe with pieces, sorted by serial_key: its first cell, then its index),
// each floe's pieces in their order; a floe's pieces are not interleaved
// with another's. A floating-point sum depends on the order of its terms,
// so each rank works in that order: the key is a floe's own (its owner
// computes it from its pieces alone), so each rank sorts its own floes by
// it (order_), and every piece or energy term that leaves the rank carries
// its floe's key, by which the receivers merge every rank's terms into the
// serial order.
//
// Sea in slabs (stages five and eight, routed()). A cell where only this
// rank's floes have pieces is summed here, into cells_ and pressure_
// directly, from zero in order_ (the serial order restricted to this rank's
// floes, which are all of the cell's): the serial loop's sums. Such are the
// cells deeper in a rank's slab than any other rank's floe reaches
// (CellRoutes::interior_rows) and, on the rows between, the cells under no
// other rank's floe's box (parallel::CellBox: the rows and columns of a
// floe's pieces, sent by its owner to the ranks that may have pieces in
// its rows: order_by_owner); if another rank
// owns such a cell (its slab holds the row), the pressure's total goes to
// it (CellRoutes' alone cells: 4 bytes a cell before the law, 8 after).
// Every other cell (under a box of another rank's floe: shared, or nearly)
// travels as its pieces, each with its floe's serial key: before the law
// the cell, its pieces' count, keys and coverage (8 bytes a cell, 16 a
// piece); after it the pieces' a u^2 and pressure (16 bytes a piece).
// With the boxes (boxed()) they go to every rank that needs the cell's
// totals (CellRoutes::open_shared, one all-to-all): the ranks whose
// floes' boxes cover it (all that may have pieces there), the rank whose
// slab holds its row (the pressure, for its sea's kick) and this one; each
// adds every rank's pieces from zero in key order, which is the serial
// loop's order of additions into that cell: the same sum on each, the
// serial one to the bit, whichever rank owns which floe; nothing goes back.
// Without the boxes (grids wider than CellBox::kMaxSide) they go to the
// slab's rank alone, which sums them so and sends the coverage and the
// sums back to the ranks that sent the cell (CellRoutes::open, reply).
// The penalty energy, a running sum over all pieces in the
// serial order, is kept as this rank's terms and summed in that order on
// demand (settle_energy: at records and checkpoints).
//
// Sea not in slabs (BEM seas, a tank, dims = 1: every rank holds the whole
// sea, whose kick reads every cell's pressure; CellRoutes::replicated). The
// same two kinds of cells, every row being a boundary row: the floes are
// owned by place (next_owners_: the drift's owners, strips in y; in a
// flume, shares of its columns; by index until they are known), so the
// cells under several ranks' floes lie near the parts' boundaries, but no
// row is deep in one rank's part. A
// cell no other rank's floe's box covers is summed here from zero in
// order_, the serial sums, and its pressure's total goes to every other
// rank (4 bytes a cell, then 8). Every other cell travels as its pieces to
// every rank (each needs its pressure; those with pieces there, its
// coverage and sum), which adds them from zero in key order: the serial
// sum to the bit on every rank, as on a sea in slabs. The penalty energy
// is settled from the terms likewise.
#include <algorithm>
#include <bit>
#include <cstring>
#include <utility>

#include "coupling/floe_sea.hpp"

#include "core/error.hpp"
#include "parallel/bytes.hpp"

namespace floesim {

using parallel::at;
using parallel::put;

namespace {
// The loops over a floe's pieces read and write the grid-sized cells_ and
// pressure_ at the pieces' cells, a new cache line at each row of the floe:
// the line of the piece this many ahead is asked for early.
constexpr std::size_t kPrefetchPieces = 16;
}  // namespace

void FloeSeaContact::set_slabs(std::vector<int> first_row) {
  FLOESIM_ASSERT(!slab_rows_.empty() && first_row.size() == slab_rows_.size());
  if (first_row == slab_rows_) return;
  // The old routes' cells: this rank's sums there are no longer read by
  // its sea, and clear_cells_by_owner() will clear the new routes' cells.
  if (in_slabs() && pressure_.size() == grid_.size()) {
    for (std::uint32_t c : routes_.owned()) pressure_[c] = 0.0;
    for (std::uint32_t c : routes_.alone_owned()) pressure_[c] = 0.0;
  }
  slab_rows_ = std::move(first_row);
  if (!in_slabs()) return;
  routes_ = parallel::CellRoutes(slab_rows_, static_cast<std::size_t>(grid_.nx));
  footprints_.set_sea_slabs(slab_rows_, true);
  owner_.interior_reach = -1;  // the interior cells are those of the new routes
}

void FloeSeaContact::set_place_owners() {
  next_owners_ = {};
  if (!routes_.replicated() || grid_.dims != 1) return;
  // A flume: its columns in equal shares (its cells span its width).
  std::vector<int> first(static_cast<std::size_t>(comm_.size()) + 1, grid_.nx);
  for (int r = 0; r < comm_.size(); ++r)
    first[static_cast<std::size_t>(r)] =
        static_cast<int>(parallel::share(static_cast<std::size_t>(grid_.nx), r, comm_.size()).begin);
  next_owners_.column = parallel::row_owners(first);
}

void FloeSeaContact::set_next_owners(std::span<const int> owner) {
  NextOwners& next = next_owners_;
  next.owner.assign(owner.begin(), owner.end());
  next.mine.clear();
  next.held.clear();
  const std::span<const std::uint32_t> mine = footprints_.mine();
  for (std::size_t i = 0, m = 0; i < owner.size(); ++i) {
    const bool now_mine = m < mine.size() && mine[m] == i;
    if (now_mine) ++m;
    if (owner[i] == comm_.rank()) next.mine.push_back(static_cast<std::uint32_t>(i));
    if (owner[i] == comm_.rank() || now_mine) next.held.push_back(static_cast<std::uint32_t>(i));
  }
  next.current = false;
  next.drifted = false;
}

int FloeSeaContact::column_owner(const FloePose& p) const {
  const int columns = static_cast<int>(next_owners_.column.size());
  // Periodic: the column that holds x, the seam crossed (grid_row's rule);
  // walled: a place beyond a wall is owned by the column at that wall.
  const int column = grid_.edge == fluid::GridEdge::periodic
                         ? parallel::grid_row(p.x, grid_.dx(), columns)
                         : static_cast<int>(std::clamp(std::floor(p.x / grid_.dx()), 0.0, columns - 1.0));
  return next_owners_.column[static_cast<std::size_t>(column)];
}

FloeSeaContact::GivenOwners FloeSeaContact::given_owners(std::size_t floes) {
  // The drift's owners on the sea's slabs (take_place_owners)...
  if (place_owner_.size() == floes && footprints_.takes_owners(place_rows_)) return {place_owner_, place_mine_};
  // ...or by place on a sea not in slabs, once their new owners hold
  // their floes' current states (next_owners_): after the vertical drift
  // of the floes they hold; with the implicit step (whose vertical DOFs
  // every rank holds, next_owners_) from the drift's exchange on...
  const NextOwners& next = next_owners_;
  if (next.owner.size() == floes && (next.drifted || (implicit_whole() && next.current))) return {next.owner, next.mine};
  // ...or, not in slabs, the last rebuild's owners kept: each holds its
  // floes current (own_floes()), so a rebuild before the new owners hold
  // theirs (a first half kick with stale loads, a redone try) poses only
  // floes its rank holds. The footprints are told to keep them
  // (keep_owners), and their arrays are returned for the poses.
  // None given (by index, every floe posed) only when no rebuild owns these
  // floes yet: the start and a restore, where every copy is the file's (a
  // split hands the owners by place as next owners: floes_changed).
  if (routes_.replicated() && footprints_.owners().size() == floes) {
    footprints_.keep_owners();
    return {footprints_.owners(), footprints_.mine()};
  }
  return {};
}

void FloeSeaContact::order_by_owner(std::size_t floes) {
  const Footprints& fp = footprints_.pieces();
  OwnerCells& o = owner_;
  const bool boxes = boxed();
  fit_floes(o.places, floes);
  for (const std::uint32_t i : o.known)
    if (i < floes) o.places.box[i] = parallel::CellBox{};
  o.known.clear();
  o.near.clear();
  // This rank's floes in the serial order (place_footprints' rule, on its
  // floes alone), with, when boxed, the box of each one's cells, which tells
  // the ranks that receive it where its pieces may share a cell.
  order_.clear();
  for (const std::uint32_t i : footprints_.mine())
    if (i < fp.floes() && constants_.dynamic[i] && fp.offsets[i] < fp.offsets[i + 1]) {
      order_.push_back(i);
      if (boxes) {
        const std::span<const std::uint32_t> cells(fp.cell.data() + fp.offsets[i], fp.offsets[i + 1] - fp.offsets[i]);
        o.places.box[i] = parallel::CellBox::of(cells, grid_.nx, grid_.ny);
        o.known.push_back(i);
      }
    }
  std::sort(order_.begin(), order_.end(), [&](std::uint32_t x, std::uint32_t y) { return serial_key(x) < serial_key(y); });
  routes_.set_largest_key(parallel::PieceKey{grid_.size()} * floes);
  if (!next_owners_.column.empty()) {
    // A flume: the rank of the share of columns of each floe's present
    // place (evaluated_.poses holds this rank's floes' present poses:
    // evaluate posed them), from its owner to every rank.
    std::vector<int> owner(floes, 0);
    for (const std::uint32_t i : footprints_.mine()) owner[i] = column_owner(evaluated_.poses[i]);
    comm_.complete_owned(owner, footprints_.owners());
    set_next_owners(owner);
  }
  if (!boxes) return;
  // Each box to the ranks that read it (sum_coverage_by_owner marks the
  // cells other ranks' boxes cover among its pieces' cells): a box that
  // covers a cell of rank r's pieces reaches within the rows of r's pieces
  // (with slabs) or meets r's box of its pieces' cells (not in slabs), so
  // r gets every box it needs, from the box's owner alone.
  const std::size_t ranks = static_cast<std::size_t>(comm_.size());
  std::vector<std::vector<std::uint32_t>> to(ranks);
  if (footprints_.by_place()) {
    const std::span<const int> slabs = footprints_.owner_slabs();
    if (!std::equal(slabs.begin(), slabs.end(), o.owner_slabs.begin(), o.owner_slabs.end())) {
      o.owner_slabs.assign(slabs.begin(), slabs.end());
      o.row_owner = parallel::row_owners(slabs);
    }
    std::vector<int> readers;
    for (const std::uint32_t i : order_) {
      readers.clear();
      box_readers(o.places.box[i], comm_.rank(), o.row_owner, grid_.nx, footprints_.piece_rows(), readers);
      for (const int r : readers) to[static_cast<std::size_t>(r)].push_back(i);
    }
  } else {
    const parallel::CellBox mine =
        order_.empty() ? parallel::CellBox{} : parallel::CellBox::of(fp.cell, grid_.nx, grid_.ny);
    // (Every rank's box: one call, the counts known.)
    const std::vector<std::size_t> counts(ranks, sizeof(parallel::CellBox));
    const std::vector<std::byte> all = comm_.allgather_known(std::as_bytes(std::span(&mine, 1)), counts);
    o.rank_box.resize(ranks);
    std::memcpy(static_cast<void*>(o.rank_box.data()), all.data(), all.size());
    for (const std::uint32_t i : order_)
      for (std::size_t r = 0; r < ranks; ++r)
        if (static_cast<int>(r) != comm_.rank() && boxes_meet(o.places.box[i], o.rank_box[r], grid_.nx, grid_.ny))
          to[r].push_back(i);
  }
  o.near = comm_.send_items(o.places.box, to);
  o.known.insert(o.known.end(), o.near.begin(), o.near.end());
  for (const std::vector<std::uint32_t>& t : to) o.routed_counts.boxes_sent += static_cast<long>(t.size());
  o.routed_counts.boxes_received += static_cast<long>(o.near.size());
}

void FloeSeaContact::settle_energy() const {
  // Every rank's terms, then summed from zero floe by floe in the serial
  // order (each floe's terms in their order), as evaluate() sums them.
  const OwnerCells& o = owner_;
  std::vector<std::byte> message(sizeof(std::uint64_t) +
                                 o.energy_keys.size() * (sizeof(parallel::PieceKey) + sizeof(std::uint32_t)) +
                                 o.energy_terms.size() * sizeof(double));
  const std::uint64_t n = o.energy_keys.size();
  put(put(put(put(message.data(), &n, 1), o.energy_keys.data(), o.energy_keys.size()), o.energy_counts.data(),
          o.energy_counts.size()),
      o.energy_terms.data(), o.energy_terms.size());
  std::vector<std::size_t> bytes;
  std::vector<std::byte> all;
  comm_.allgather_bytes(message, bytes, all);
  struct Floe {
    parallel::PieceKey key;
    std::uint32_t count;
    const std::byte* terms;
  };
  std::vector<Floe> floes;
  const std::byte* in = all.data();
  for (std::size_t b : bytes) {
    const std::size_t m = static_cast<std::size_t>(at<std::uint64_t>(in, 0));
    const std::byte* keys = in + sizeof(std::uint64_t);
    const std::byte* counts = keys + m * sizeof(parallel::PieceKey);
    const std::byte* terms = counts + m * sizeof(std::uint32_t);
    for (std::size_t j = 0; j < m; ++j) {
      const std::uint32_t count = at<std::uint32_t>(counts, j);
      floes.push_back({at<parallel::PieceKey>(keys, j), count, terms});
      terms += count * sizeof(double);
    }
    in += b;
  }
  std::sort(floes.begin(), floes.end(), [](const Floe& x, const Floe& y) { return x.key < y.key; });
  double energy = 0.0;
  for (const Floe& f : floes)
    for (std::size_t k = 0; k < f.count; ++k) energy += at<double>(f.terms, k);
  penalty_energy_ = energy;
  energy_pending_ = false;
}

void FloeSeaContact::clear_cells_by_owner() {
  // The pressure where the last evaluation put it: the cells received as
  // pieces and the alone cells received as totals (this rank's slab's, or
  // every other rank's not in slabs); the coverage and sums in this rank's
  // cells; and the cells of its last pieces, where it summed alone.
  FLOESIM_ASSERT(routed());
  for (std::uint32_t c : routes_.owned()) pressure_[c] = 0.0;
  for (std::uint32_t c : routes_.alone_owned()) pressure_[c] = 0.0;
  // Every cell of this rank's pieces, as the serial clear_footprint_cells:
  // the cells summed here alone and those of owner_.cells. One pass over
  // the pieces' cells as stored (no per-piece kind or slot read); zeroing
  // a cell this rank did not write changes nothing, every sum of the next
  // evaluation being made after this clear.
  for (std::uint32_t c : footprints_.pieces().cell) {
    pressure_[c] = 0.0;
    cells_[c] = {};
  }
}

void FloeSeaContact::sum_coverage_by_owner() {
  const Footprints& fp = footprints_.pieces();
  OwnerCells& o = owner_;
  // A cell where this rank's floes' pieces lie alone gets no other rank's:
  // its sums are made in cells_ and pressure_ directly, as the serial loop
  // makes them (its pieces are all of the cell's, in order_, the serial
  // order). Such are the cells deep in this rank's slab (no other rank's
  // floe reaches them; none when not in slabs) and, with the floes' boxes
  // (boxed()), every cell no other rank's floe's box covers; the pressure
  // of those another rank holds goes to it as a total (`alone`). Every
  // other cell goes as pieces to the ranks that sum it.
  FLOESIM_ASSERT(routed());
  const bool boxes = boxed();
  const std::size_t nx = static_cast<std::size_t>(grid_.nx);
  const std::size_t rank_words = (static_cast<std::size_t>(comm_.size()) + 63) / 64;
  const int reach = footprints_.by_place() ? footprints_.reach_rows() : grid_.ny;
  if (reach != o.interior_reach) {
    o.interior_row = routes_.interior_rows(reach);
    o.kind.resize(grid_.size());
    for (std::size_t y = 0; y < o.interior_row.size(); ++y)
      std::fill_n(o.kind.begin() + static_cast<std::ptrdiff_t>(y * nx), nx,
                  o.interior_row[y] ? OwnerCells::kInteriorRow : OwnerCells::kRoutedRow);
    o.interior_reach = reach;
  }
  // The cells other ranks' floes may have pieces in, outside the slabs'
  // interiors (where no other rank's floe reaches).
  // With each such cell, the ranks of those floes: each sums the cell
  // too.
  if (boxes) {
    // The boxes of the other ranks' floes that may cover a cell of this
    // rank's pieces, which their owners sent here (order_by_owner; with
    // slabs, coupling/shared_cells.hpp: a row within R_max and about two
    // cells of its slab of the owners; not in slabs, meeting its box).
    mark_shared_cells(o.near, o.places.box, footprints_.owners(), grid_.nx, grid_.ny, o.interior_row, o.kind,
                      OwnerCells::kRoutedRow, OwnerCells::kShared, rank_words, o.marks);
  } else {
    o.marks.painted.clear();
    o.marks.shared_ranks.clear();
  }
  // This rank's other cells, in the order its floes' pieces meet them, and
  // its part of each cell's coverage, summed as the serial loop sums it.
  o.slot.resize(grid_.size(), 0);
  for (std::uint32_t c : o.cells) o.slot[c] = 0;
  o.cells.clear();
  o.coverage.clear();
  o.alone.clear();
  o.first.assign(1, 0);  // then each cell's piece count, made offsets below
  o.routed_pieces.clear();
  FLOESIM_ASSERT(fp.cell.size() <= 0xffffffffu);  // RoutedPiece::piece
  const double inv_cell_area = 1.0 / cell_area_;
  const int rank = comm_.rank();
  std::size_t alone_here = 0;
  // A new cell of `cells`: its slot.
  auto listed = [&](std::uint32_t c) {
    if (o.slot[c] == 0) {
      o.cells.push_back(c);
      o.coverage.push_back(0.0);
      o.first.push_back(0);
      o.slot[c] = static_cast<std::uint32_t>(o.cells.size());
    }
    return o.slot[c] - 1;
  };
  for (std::uint32_t i : order_) {
    // The row of a piece's cell, found by a division only when it
    // changes (a floe's cells come row by row); in an interior row the
    // cell is this rank's alone and its kind is not read.
    std::size_t row_base = grid_.size();
    bool interior = false;
    const std::size_t end = fp.offsets[i + 1];
    for (std::size_t k = fp.offsets[i]; k < end; ++k) {
      if (k + kPrefetchPieces < end) __builtin_prefetch(&cells_[fp.cell[k + kPrefetchPieces]], 1);
      const std::uint32_t c = fp.cell[k];
      if (c < row_base || c - row_base >= nx) {
        const std::size_t row = c / nx;
        row_base = row * nx;
        interior = o.interior_row[row] != 0;
      }
      const std::uint8_t kind = interior ? std::uint8_t{OwnerCells::kInteriorRow} : o.kind[c];
      if (kind == OwnerCells::kInteriorRow || (boxes && kind != OwnerCells::kShared)) {
        cells_[c].coverage += fp.area[k] * inv_cell_area;
        if (kind == OwnerCells::kRoutedRow) {  // first met: listed, and its total sent if another rank holds it
          o.kind[c] = OwnerCells::kAloneListed;
          o.marks.painted.push_back(c);
          if (routes_.replicated() || routes_.owner(c) != rank) o.alone.push_back(c);
          else ++alone_here;
        }
        continue;
      }
      // The cell's receivers sum the pieces (the total replaces this
      // rank's part below): only counted here, and the piece listed with
      // its floe's key, in order_ (the serial order) as this loop meets it.
      const std::uint32_t j = listed(c);
      ++o.first[j + 1];
      o.routed_pieces.push_back({serial_key(i), static_cast<std::uint32_t>(k), j, 0});
    }
  }
  // The kinds back to the rows' (the boxes move with the floes).
  for (std::uint32_t c : o.marks.painted) o.kind[c] = OwnerCells::kRoutedRow;
  // The routed cells' pieces grouped by cell, in the serial order within
  // each (order_ is), with their floes' positions.
  for (std::size_t j = 0; j < o.cells.size(); ++j) o.first[j + 1] += o.first[j];
  o.keys.resize(o.first.back());
  o.values.resize(o.first.back());
  // (From the list of the routed pieces made above, in the same order:
  // the few routed pieces, not a second pass over all of them.)
  std::vector<std::uint32_t> next(o.first.begin(), o.first.end() - 1);
  for (OwnerCells::RoutedPiece& r : o.routed_pieces) {
    r.at = next[r.cell]++;
    o.keys[r.at] = r.key;
    o.values[r.at] = fp.area[r.piece] * inv_cell_area;
  }
  o.routed_counts.shared += static_cast<long>(o.cells.size());
  o.routed_counts.pieces += static_cast<long>(o.first.back());
  o.routed_counts.alone_here += static_cast<long>(alone_here);
  o.routed_counts.alone_sent += static_cast<long>(o.alone.size());
  o.routes_footprints = footprint_version();
  if (!one_round()) {
    // Each cell to its slab's rank, which sends the total back.
    routes_.open(comm_, o.cells, o.first, o.keys, o.values, 1, o.alone);
    routes_.reply(comm_, 0, o.coverage);  // the cells' totals, in place of this rank's parts
    for (std::size_t j = 0; j < o.cells.size(); ++j) cells_[o.cells[j]].coverage = o.coverage[j];
    return;
  }
  // Each shared cell to every rank that needs its total: the ranks whose
  // floes' boxes cover it (all that may have pieces there), its slab's
  // rank and this one; not in slabs, every rank (each sea reads every
  // cell's pressure). Each sums every rank's pieces in the serial order.
  o.receivers_first.assign(1, 0);
  o.receivers.clear();
  for (const std::uint32_t c : o.cells) {
    const auto first = static_cast<std::ptrdiff_t>(o.receivers.size());
    if (routes_.replicated()) {
      for (int r = 0; r < comm_.size(); ++r) o.receivers.push_back(r);
    } else {
      // (Ascending, each once: the covering ranks' bits, with this rank and
      // the slab's; a cell's cost is its covering ranks', not every rank's.)
      const std::uint64_t* ranks = o.marks.shared_ranks.data() + (o.marks.shared_at[c] - 1) * rank_words;
      o.receivers.push_back(rank);
      o.receivers.push_back(routes_.owner(c));
      for (std::size_t w = 0; w < rank_words; ++w)
        for (std::uint64_t bits = ranks[w]; bits != 0; bits &= bits - 1)
          o.receivers.push_back(static_cast<int>(64 * w) + std::countr_zero(bits));
      std::sort(o.receivers.begin() + first, o.receivers.end());
      o.receivers.erase(std::unique(o.receivers.begin() + first, o.receivers.end()), o.receivers.end());
    }
    o.receivers_first.push_back(static_cast<std::uint32_t>(o.receivers.size()));
  }
  for (const std::uint32_t c : o.marks.painted) o.marks.shared_at[c] = 0;
  routes_.open_shared(comm_, o.cells, o.first, o.keys, o.values, 1, o.receivers_first, o.receivers, o.alone);
  for (const std::uint32_t c : o.cells) cells_[c].coverage = routes_.total(routes_.index(c), 0);
}

double FloeSeaContact::sum_cells_by_owner(double ks) {
  const Footprints& fp = footprints_.pieces();
  const std::vector<double>& u = eval_.penetration;
  const std::vector<double>& psi = eval_.psi;
  const std::vector<double>& force = eval_.force;
  OwnerCells& o = owner_;
  const double inv_cell_area = 1.0 / cell_area_;
  const int rank = comm_.rank();
  double energy = 0.0;
  FLOESIM_ASSERT(routed());
  // The routed pieces' a u^2 and pressure (zero where u <= 0, which the
  // serial loop skips: adding +0 changes no sum that starts from +0), the
  // interior cells' sums made here, and this rank's energy terms.
  o.parts.assign(2 * o.first.back(), 0.0);
  o.energy_keys.clear();
  o.energy_counts.clear();
  o.energy_terms.clear();
  // The routed pieces come listed in this loop's order (the coverage's
  // pass met them so): the next one listed is this piece or a later one.
  const std::span<const OwnerCells::RoutedPiece> routed_pieces = o.routed_pieces;
  std::size_t next = 0;
  for (std::uint32_t i : order_) {
    const std::size_t terms = o.energy_terms.size();
    const std::size_t end = fp.offsets[i + 1];
    for (std::size_t k = fp.offsets[i]; k < end; ++k) {
      if (k + kPrefetchPieces < end) {
        __builtin_prefetch(&cells_[fp.cell[k + kPrefetchPieces]], 1);
        __builtin_prefetch(&pressure_[fp.cell[k + kPrefetchPieces]], 1);
      }
      const bool routed_piece = next < routed_pieces.size() && routed_pieces[next].piece == k;
      const std::uint32_t at = routed_piece ? routed_pieces[next++].at : 0;
      if (u[k] <= 0.0) continue;
      const double term = 0.5 * ks * psi[k] * fp.area[k] * u[k] * u[k];
      energy += term;
      o.energy_terms.push_back(term);
      if (!routed_piece) {
        cells_[fp.cell[k]].sum += fp.area[k] * u[k] * u[k];
        pressure_[fp.cell[k]] += force[k] * inv_cell_area;
        continue;
      }
      o.parts[2 * at] = fp.area[k] * u[k] * u[k];
      o.parts[2 * at + 1] = force[k] * inv_cell_area;
    }
    if (o.energy_terms.size() > terms) {
      o.energy_keys.push_back(serial_key(i));
      o.energy_counts.push_back(static_cast<std::uint32_t>(o.energy_terms.size() - terms));
    }
  }
  // The pressure of the cells summed here alone that another rank holds:
  // their totals to it (in slabs this rank's sea does not read them; not in
  // slabs it does, and keeps them).
  o.alone_totals.resize(o.alone.size());
  for (std::size_t j = 0; j < o.alone.size(); ++j)
    o.alone_totals[j] = routes_.replicated() ? pressure_[o.alone[j]] : std::exchange(pressure_[o.alone[j]], 0.0);
  const double total = routes_.add(comm_, o.parts, 2, energy, o.alone_totals);
  // The pressure of this rank's slab's cells, or of every cell not in
  // slabs (zero before: 0 + the total; in slabs with the boxes some
  // received cells are other slabs', summed here for their sums), then the sums of this rank's cells: with the boxes
  // summed here, else sent back by the cells' slabs' ranks.
  const std::span<const std::uint32_t> held = routes_.owned();
  for (std::size_t j = 0; j < held.size(); ++j)
    if (routes_.holds(rank, held[j])) pressure_[held[j]] = routes_.total(j, 1);
  const std::span<const std::uint32_t> alone = routes_.alone_owned();
  for (std::size_t j = 0; j < alone.size(); ++j) pressure_[alone[j]] = routes_.alone_total(j);  // the sender's sum from zero
  if (one_round()) {
    for (const std::uint32_t c : o.cells) cells_[c].sum = routes_.total(routes_.index(c), 0);
  } else {
    o.sum.resize(o.cells.size());
    routes_.reply(comm_, 0, o.sum);
    for (std::size_t j = 0; j < o.cells.size(); ++j) cells_[o.cells[j]].sum = o.sum[j];
  }
  energy_pending_ = true;  // the ranks' parts summed in rank order until settled
  return total;
}

void FloeSeaContact::share_owned(std::span<const std::uint8_t> kicked) {
  if (comm_.serial()) return;
  // The vertical loads too: by owner only the owner has them (replicated,
  // the owner's are every rank's, to the bit).
  struct Owned {
    double fx, fy, torque, fz, mx, my;
  };
  const auto pack = [&](std::uint32_t i) {
    const Eigen::Vector3d& f = kicks_.loads[i].horizontal;
    const Eigen::Vector3d& v = kicks_.loads[i].vertical;
    return Owned{f[0], f[1], f[2], v[0], v[1], v[2]};
  };
  const auto unpack = [&](std::size_t i, const Owned& o) {
    kicks_.loads[i].horizontal = {o.fx, o.fy, o.torque};
    kicks_.loads[i].vertical = {o.fz, o.mx, o.my};
  };
  const std::span<const int> owner = footprints_.owners();
  if (kicked.empty() || implicit_) {
    // Every floe's loads to every rank (the implicit step: the header's
    // "The kick by its holders").
    std::vector<Owned> owned(kicks_.loads.size());
    for (std::uint32_t i : footprints_.mine()) owned[i] = pack(i);
    comm_.complete_owned(owned, owner);
    ++shared_loads_.whole;
    for (std::size_t i = 0; i < owned.size(); ++i)
      if (!footprints_.owns(i)) {
        unpack(i, owned[i]);
        ++shared_loads_.whole_floes;
      }
    return;
  }
  // By request: only the rank that kicks a floe knows it holds it (its band
  // is its owner's announcement, Simulation::held_now), so each rank asks
  // each coupling owner for the dynamic floes it kicks and does not own
  // (4 B a floe, one alltoall_bytes: two calls), and the owner answers in
  // the order asked (48 B a floe, one alltoall: both sides know the counts).
  FLOESIM_ASSERT(kicked.size() == kicks_.loads.size() && owner.size() == kicks_.loads.size());
  const std::size_t ranks = static_cast<std::size_t>(comm_.size());
  std::vector<std::vector<std::uint32_t>> ask(ranks);
  for (std::size_t i = 0; i < kicked.size(); ++i)
    if (kicked[i] && constants_.dynamic[i] && owner[i] != comm_.rank())
      ask[static_cast<std::size_t>(owner[i])].push_back(static_cast<std::uint32_t>(i));
  std::vector<std::size_t> ask_bytes(ranks), asked_bytes;
  std::vector<std::uint32_t> asks;
  for (std::size_t r = 0; r < ranks; ++r) {
    asks.insert(asks.end(), ask[r].begin(), ask[r].end());
    ask_bytes[r] = ask[r].size() * sizeof(std::uint32_t);
  }
  std::vector<std::byte> asked;
  comm_.alltoall_bytes(std::as_bytes(std::span<const std::uint32_t>(asks)), ask_bytes, asked, asked_bytes);
  std::vector<Owned> answer(asked.size() / sizeof(std::uint32_t)), answered(asks.size());
  for (std::size_t k = 0; k < answer.size(); ++k) {
    std::uint32_t i = 0;
    std::memcpy(&i, asked.data() + k * sizeof(i), sizeof(i));
    FLOESIM_ASSERT(i < owner.size() && owner[i] == comm_.rank());
    answer[k] = pack(i);
  }
  std::vector<std::size_t> answer_bytes(ranks), answered_bytes(ranks);
  for (std::size_t r = 0; r < ranks; ++r) {
    answer_bytes[r] = asked_bytes[r] / sizeof(std::uint32_t) * sizeof(Owned);
    answered_bytes[r] = ask[r].size() * sizeof(Owned);
  }
  comm_.alltoall(std::as_bytes(std::span<const Owned>(answer)), answer_bytes,
                 std::as_writable_bytes(std::span<Owned>(answered)), answered_bytes);
  for (std::size_t k = 0; k < asks.size(); ++k) unpack(asks[k], answered[k]);
  ++shared_loads_.asked;
  shared_loads_.asked_floes += static_cast<long>(asks.size());
}

void FloeSeaContact::hand_water_over(std::span<const int> drift_owner) {
  // Only the drift reads the water velocity, and each rank drifts its floes
  // by place (parallel::FloeOwners); the coupling's owner of a floe is
  // mostly the same rank (both by place on the same slabs), but not always:
  // the coupling's owners are set at the footprints' last rebuild and follow
  // a move of the slabs only at the next one; without a sea in slabs (the
  // implicit step's sea too) they are these owners from the next rebuild on
  // (next_owners_), but in a flume with the explicit kicks (shares of its
  // columns).
  if ((routes_.replicated() || implicit_whole()) && next_owners_.column.empty() &&
      drift_owner.size() == constants_.dynamic.size())
    set_next_owners(drift_owner);
  // The drift's exchange that follows sends each floe's state to its next
  // owner too (Simulation::send_to_holders): from here on they hold them.
  next_owners_.current = true;
  if (comm_.serial() || !water_by_owner_) return;
  FLOESIM_ASSERT(drift_owner.size() == evaluated_.water.size() &&
                 footprints_.owners().size() == evaluated_.water.size());
  comm_.hand_over(evaluated_.water, footprints_.owners(), drift_owner);
}

}  // namespace floesim
