// The floe–sea contact on several ranks: the owners' loads and water
// velocities to every rank (docs/parallel.md, stage two), and the contact
// evaluated by owner (stage three; FloeSeaContact::by_owner): the sums into
// the cells that the law needs before it (the coverage Phi_c) and that it
// gives after it (the cells' sum of a_k u_k^2 and the pressure), each rank
// summing its own floes' pieces, then the ranks' parts summed in rank order.
//
// Each rank sends, for the cells its pieces lie in, its part of each sum: the
// cells and their coverage (12 bytes a cell) before the law, the sums and
// pressures (16 bytes a cell, the cells already known) after it. Every rank
// receives every rank's parts and adds them in rank order from zero, so the
// sums do not depend on timing: the pressure in every cell (the sea,
// replicated, needs all of it), the coverage and the sums only in the cells
// of its own pieces (the law and the horizontal loads read no other: an edge
// piece's cell is its area piece's); cells_ elsewhere stays zero. A cell
// where one rank's floes lie gets 0 + that rank's part: the serial sum over
// the same pieces in the same order (order_ is the serial order restricted to
// the rank's floes), to the bit. A cell shared by several ranks' floes gets
// the parts' sum, which groups the pieces by rank: equal to the serial sum up
// to round-off (a few ulps of the cell's value).
//
// When the sea is in slabs (stage five, routed()), a rank's sea reads only
// the pressure of its slab's rows, so each rank sends a cell's parts only to
// the rank whose slab holds the cell's row (parallel::CellRoutes, an
// all-to-all), which sums them in rank order from zero, as above, keeps the
// pressure and sends the coverage and the sums back to the ranks that sent
// the cell: the same totals to the bit, each summed once instead of on every
// rank, and received only by the ranks that have pieces in the cell.
#include <cstring>

#include "coupling/floe_sea.hpp"

#include "core/error.hpp"
#include "parallel/bytes.hpp"

namespace floesim {

using parallel::at;
using parallel::put;

void FloeSeaContact::set_slabs(std::vector<int> first_row) {
  FLOESIM_ASSERT(!slab_rows_.empty() && first_row.size() == slab_rows_.size());
  if (first_row == slab_rows_) return;
  // The old routes' cells: this rank's sums there are no longer read by
  // its sea, and clear_cells_by_owner() will clear the new routes' cells.
  if (routed() && pressure_.size() == grid_.size())
    for (std::uint32_t c : routes_.owned()) pressure_[c] = 0.0;
  slab_rows_ = std::move(first_row);
  if (!routed()) return;
  routes_ = parallel::CellRoutes(slab_rows_, static_cast<std::size_t>(grid_.nx));
  footprints_.set_sea_slabs(slab_rows_);
  owner_.interior_reach = -1;  // the interior cells are those of the new routes
}

void FloeSeaContact::clear_cells_by_owner() {
  // The pressure where the last evaluation put it: every rank's cells (not
  // routed) or this rank's slab's routed cells; the coverage and sums in
  // this rank's cells; and, routed, the cells deep in its slab, where its
  // last pieces lie.
  for (std::uint32_t c : routed() ? routes_.owned() : std::span<const std::uint32_t>(owner_.touched)) pressure_[c] = 0.0;
  for (std::uint32_t c : owner_.cells) cells_[c] = {};
  if (!routed()) return;
  const Footprints& fp = footprints_.pieces();
  for (std::uint32_t i : order_)
    for (std::size_t k = fp.offsets[i]; k < fp.offsets[i + 1]; ++k)
      if (owner_.piece_slot[k] == kInteriorCell) {
        pressure_[fp.cell[k]] = 0.0;
        cells_[fp.cell[k]] = {};
      }
}

void FloeSeaContact::sum_coverage_by_owner() {
  const Footprints& fp = footprints_.pieces();
  OwnerCells& o = owner_;
  // Routed, the cells deep in this rank's slab (floes owned by place) get
  // no other rank's parts: their sums are made in cells_ and pressure_
  // directly, as the serial loop makes them (the totals are this rank's
  // parts: 0 + its part, what the merge would give), and every other cell
  // goes to its owner. Not routed, no cell is interior.
  const bool routed_cells = routed();
  if (routed_cells) {
    const int reach = footprints_.by_place() ? footprints_.reach_rows() : grid_.ny;
    if (reach != o.interior_reach) {
      const std::vector<std::uint8_t> rows = routes_.interior_rows(reach);
      o.interior.resize(grid_.size());
      for (std::size_t c = 0; c < grid_.size(); ++c) o.interior[c] = rows[c / static_cast<std::size_t>(grid_.nx)];
      o.interior_reach = reach;
    }
  }
  // This rank's other cells, in the order its floes' pieces meet them, and
  // its part of each cell's coverage, summed as the serial loop sums it.
  o.slot.resize(grid_.size(), 0);
  for (std::uint32_t c : o.cells) o.slot[c] = 0;
  o.cells.clear();
  o.coverage.clear();
  o.piece_slot.resize(fp.cell.size());
  const double inv_cell_area = 1.0 / cell_area_;
  for (std::uint32_t i : order_)
    for (std::size_t k = fp.offsets[i]; k < fp.offsets[i + 1]; ++k) {
      const std::uint32_t c = fp.cell[k];
      if (routed_cells && o.interior[c]) {
        o.piece_slot[k] = kInteriorCell;
        cells_[c].coverage += fp.area[k] * inv_cell_area;
        continue;
      }
      if (o.slot[c] == 0) {
        o.cells.push_back(c);
        o.coverage.push_back(0.0);
        o.slot[c] = static_cast<std::uint32_t>(o.cells.size());
      }
      o.piece_slot[k] = o.slot[c] - 1;
      o.coverage[o.piece_slot[k]] += fp.area[k] * inv_cell_area;
    }
  if (routed()) {
    routes_.open(comm_, o.cells, o.coverage, 1);
    routes_.reply(comm_, 0, o.coverage);  // the cells' totals, in place of this rank's parts
    for (std::size_t j = 0; j < o.cells.size(); ++j) cells_[o.cells[j]].coverage = o.coverage[j];
    return;
  }
  // Message: the cells, then their coverage.
  o.message.resize(o.cells.size() * (sizeof(std::uint32_t) + sizeof(double)));
  put(put(o.message.data(), o.cells.data(), o.cells.size()), o.coverage.data(), o.coverage.size());
  std::vector<std::size_t> bytes;
  comm_.allgather_bytes(o.message, bytes, o.received);
  // clear_footprint_cells zeroed the last evaluation's cells; every other
  // cell is zero, so the sums below start from zero.
  constexpr std::size_t kCellBytes = sizeof(std::uint32_t) + sizeof(double);
  o.touched.clear();
  o.counts.assign(bytes.size(), 0);
  const std::byte* in = o.received.data();
  for (std::size_t r = 0; r < bytes.size(); ++r) {
    const std::size_t n = bytes[r] / kCellBytes, first = o.touched.size();
    o.counts[r] = n;
    o.touched.resize(first + n);
    std::memcpy(o.touched.data() + first, in, n * sizeof(std::uint32_t));
    const std::byte* coverage = in + n * sizeof(std::uint32_t);
    for (std::size_t j = 0; j < n; ++j) {
      const std::uint32_t c = o.touched[first + j];
      if (o.slot[c] != 0) cells_[c].coverage += at<double>(coverage, j);
    }
    in += bytes[r];
  }
}

double FloeSeaContact::sum_cells_by_owner(double ks) {
  const Footprints& fp = footprints_.pieces();
  const std::vector<double>& u = eval_.penetration;
  const std::vector<double>& psi = eval_.psi;
  const std::vector<double>& force = eval_.force;
  OwnerCells& o = owner_;
  o.sum.assign(o.cells.size(), 0.0);
  o.pressure.assign(o.cells.size(), 0.0);
  const double inv_cell_area = 1.0 / cell_area_;
  double energy = 0.0;
  for (std::uint32_t i : order_)
    for (std::size_t k = fp.offsets[i]; k < fp.offsets[i + 1]; ++k) {
      if (u[k] <= 0.0) continue;
      const std::uint32_t j = o.piece_slot[k];
      energy += 0.5 * ks * psi[k] * fp.area[k] * u[k] * u[k];
      if (j == kInteriorCell) {
        cells_[fp.cell[k]].sum += fp.area[k] * u[k] * u[k];
        pressure_[fp.cell[k]] += force[k] * inv_cell_area;
        continue;
      }
      o.sum[j] += fp.area[k] * u[k] * u[k];
      o.pressure[j] += force[k] * inv_cell_area;
    }
  if (routed()) {
    o.parts.resize(2 * o.cells.size());
    for (std::size_t j = 0; j < o.cells.size(); ++j) {
      o.parts[2 * j] = o.sum[j];
      o.parts[2 * j + 1] = o.pressure[j];
    }
    const double total = routes_.add(comm_, o.parts, 2, energy);
    const std::span<const std::uint32_t> slab = routes_.owned();
    for (std::size_t j = 0; j < slab.size(); ++j) pressure_[slab[j]] = routes_.total(j, 1);  // zero before: 0 + the total
    routes_.reply(comm_, 0, o.sum);
    for (std::size_t j = 0; j < o.cells.size(); ++j) cells_[o.cells[j]].sum = o.sum[j];
    return total;
  }
  // Message: the energy, then the sums and pressures of the cells sent
  // before (every rank knows how many).
  o.message.resize(sizeof(double) * (1 + 2 * o.cells.size()));
  put(put(put(o.message.data(), &energy, 1), o.sum.data(), o.sum.size()), o.pressure.data(), o.pressure.size());
  std::vector<std::size_t> bytes(o.counts.size());
  for (std::size_t r = 0; r < o.counts.size(); ++r) bytes[r] = sizeof(double) * (1 + 2 * o.counts[r]);
  comm_.allgather_known(o.message, bytes, o.received);
  double total = 0.0;
  const std::byte* in = o.received.data();
  const std::uint32_t* cell = o.touched.data();
  for (std::size_t r = 0; r < o.counts.size(); ++r) {
    const std::size_t n = o.counts[r];
    total += at<double>(in, 0);
    const std::byte* sum = in + sizeof(double);
    const std::byte* pressure = sum + n * sizeof(double);
    for (std::size_t j = 0; j < n; ++j) {
      pressure_[cell[j]] += at<double>(pressure, j);
      if (o.slot[cell[j]] != 0) cells_[cell[j]].sum += at<double>(sum, j);
    }
    cell += n;
    in += bytes[r];
  }
  return total;
}

void FloeSeaContact::share_owned(bool water) {
  if (comm_.serial()) return;
  // The vertical loads too: by owner only the owner has them (replicated,
  // the owner's are every rank's, to the bit).
  struct Owned {
    double fx, fy, torque, u, v, fz, mx, my;
  };
  std::vector<Owned> owned(loads_.size());
  for (std::uint32_t i : footprints_.mine()) {
    const Eigen::Vector3d& f = loads_[i].horizontal;
    const Eigen::Vector3d& v = loads_[i].vertical;
    const Vec2 w = water ? water_[i] : Vec2::Zero();
    owned[i] = {f[0], f[1], f[2], w.x(), w.y(), v[0], v[1], v[2]};
  }
  comm_.complete_owned(owned, footprints_.owners());
  for (std::size_t i = 0; i < owned.size(); ++i) {
    if (footprints_.owns(i)) continue;
    loads_[i].horizontal = {owned[i].fx, owned[i].fy, owned[i].torque};
    loads_[i].vertical = {owned[i].fz, owned[i].mx, owned[i].my};
    if (water) water_[i] = {owned[i].u, owned[i].v};
  }
}

}  // namespace floesim
