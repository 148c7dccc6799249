// The pieces' values through the sea's cells and back (FloeSeaContact::
// cell_product; docs/parallel.md, "The products' routes (answer30)"): the
// communication of the implicit step's product G_sea u on a sea in slabs.
//
// A product scatters one value a piece into the cells, lets the sea answer
// on its rows, and reads the answer back at each piece's cell. The serial
// rule for a cell's sum is the coverage's (stage eight): from zero, the
// floes in order_ (by first cell), each floe's pieces in order. By owner the
// footprints are the coverage's of the last evaluation, so its routes
// (FloeSeaContact::sum_coverage_by_owner: which cells travel as pieces, to
// which ranks, with which keys) hold for every product of the step; the
// values change, the routes do not. The three kinds of cells of a rank's
// pieces:
// - deep in its slab, or under no other rank's floe's box and in its slab:
//   every piece there is this rank's, summed here in order_, the serial
//   order restricted to the cell's floes;
// - under no other rank's floe's box, in another rank's slab (`alone`):
//   summed here so, the total sent to the slab's rank (CellRoutes::add's
//   alone totals), which responds and sends the cell's response back
//   (CellRoutes::answer);
// - under another rank's floe's box (`cells`, routed): its pieces to the
//   ranks the open named, the slab's rank among them, each summing every
//   rank's pieces of it from zero by key (the floes' serial positions): the
//   serial sum; the slab's rank responds and answers.
// So the slab's rank has each of its cells' serial sum, its response is the
// serial response's (a function of the cells' sums: per cell, or the sea's
// transform of the slab's rows, piece 2), and every piece reads its cell's
// response from the cell's one owner.
#include "coupling/floe_sea.hpp"

#include <utility>

#include "core/error.hpp"

namespace floesim {

void FloeSeaContact::cell_product(std::span<const double> u, double scale, const SlabResponse& respond,
                                  std::span<double> out) {
  const Footprints& fp = footprints_.pieces();
  FLOESIM_ASSERT(u.size() == fp.cell.size() && out.size() == fp.cell.size());
  if (grid_work_.size() != grid_.size()) grid_work_.assign(grid_.size(), 0.0);  // zero between products
  grid_eta_.resize(grid_.size());
  ++product_.stats.products;
  if (!by_owner()) {
    // Every piece here, the whole grid.
    for (const std::uint32_t i : order_)
      for (std::size_t k = fp.offsets[i]; k < fp.offsets[i + 1]; ++k) grid_work_[fp.cell[k]] += u[k] * scale;
    respond(0, grid_work_, grid_eta_);
    for (const std::uint32_t i : order_)
      for (std::size_t k = fp.offsets[i]; k < fp.offsets[i + 1]; ++k) out[k] = grid_eta_[fp.cell[k]];
    for (const std::uint32_t c : fp.cell) grid_work_[c] = 0.0;
    return;
  }
  scatter_to_slab(u, scale);
  // The response on this rank's slab, every cell's value there being the
  // serial sum (zero where no piece lies); then the responses at the
  // cells of this rank's pieces in other slabs, from their ranks.
  const OwnerCells& o = owner_;
  ProductScratch& p = product_;
  const int rank = comm_.rank();
  const std::size_t nx = static_cast<std::size_t>(grid_.nx);
  const std::size_t first = static_cast<std::size_t>(slab_rows_[static_cast<std::size_t>(rank)]) * nx;
  const std::size_t count = static_cast<std::size_t>(slab_rows_[static_cast<std::size_t>(rank) + 1]) * nx - first;
  const std::span<double> slab_eta = std::span(grid_eta_).subspan(first, count);
  respond(slab_rows_[static_cast<std::size_t>(rank)], std::span<const double>(grid_work_).subspan(first, count), slab_eta);
  p.cells_answer.resize(o.cells.size());
  p.alone_answer.resize(o.alone.size());
  routes_.answer(comm_, slab_eta, p.cells_answer, p.alone_answer);
  p.stats.answer_bytes += static_cast<long long>(routes_.received_from_others());
  // (A routed cell of this slab comes back with its own value.)
  for (std::size_t j = 0; j < o.cells.size(); ++j) grid_eta_[o.cells[j]] = p.cells_answer[j];
  for (std::size_t j = 0; j < o.alone.size(); ++j) grid_eta_[o.alone[j]] = p.alone_answer[j];
  for (const std::uint32_t i : order_)
    for (std::size_t k = fp.offsets[i]; k < fp.offsets[i + 1]; ++k) out[k] = grid_eta_[fp.cell[k]];
  scatter_clear();
}

void FloeSeaContact::scatter_to_slab(std::span<const double> u, double scale) {
  FLOESIM_ASSERT(in_slabs() && owner_.routes_footprints == footprint_version());
  const Footprints& fp = footprints_.pieces();
  if (grid_work_.size() != grid_.size()) grid_work_.assign(grid_.size(), 0.0);
  const OwnerCells& o = owner_;
  ProductScratch& p = product_;
  const int rank = comm_.rank();
  // The routed pieces' values listed by the coverage's pass (routed_pieces,
  // in order_'s order as this loop meets them), every other piece added
  // into its cell here.
  p.parts.assign(o.first.back(), 0.0);
  std::size_t next = 0;
  for (const std::uint32_t i : order_)
    for (std::size_t k = fp.offsets[i]; k < fp.offsets[i + 1]; ++k) {
      if (next < o.routed_pieces.size() && o.routed_pieces[next].piece == k) {
        p.parts[o.routed_pieces[next++].at] = u[k] * scale;
        continue;
      }
      grid_work_[fp.cell[k]] += u[k] * scale;
    }
  p.alone_totals.resize(o.alone.size());
  for (std::size_t j = 0; j < o.alone.size(); ++j) p.alone_totals[j] = std::exchange(grid_work_[o.alone[j]], 0.0);
  routes_.add(comm_, p.parts, 1, 0.0, p.alone_totals);
  p.stats.scatter_bytes += static_cast<long long>(routes_.received_from_others());
  const std::span<const std::uint32_t> held = routes_.owned();
  for (std::size_t j = 0; j < held.size(); ++j)
    if (routes_.holds(rank, held[j])) grid_work_[held[j]] = routes_.total(j, 0);
  const std::span<const std::uint32_t> alone_here = routes_.alone_owned();
  for (std::size_t j = 0; j < alone_here.size(); ++j) grid_work_[alone_here[j]] = routes_.alone_total(j);
}

void FloeSeaContact::scatter_clear() {
  // The cells of this rank's pieces and those the routes wrote.
  for (const std::uint32_t c : footprints_.pieces().cell) grid_work_[c] = 0.0;
  for (const std::uint32_t c : routes_.owned()) grid_work_[c] = 0.0;
  for (const std::uint32_t c : routes_.alone_owned()) grid_work_[c] = 0.0;
}

}  // namespace floesim
