#pragma once
// The cells a rank's floes may share with other ranks' floes, for the
// contact by owner on a sea in slabs (docs/parallel.md, stage eight, and
// "The coupling's passes over the held floes"): which other floes' boxes of
// cells (parallel::CellBox) a rank reads, and the marking of the cells they
// cover. Plain functions of plain data, so that simulated ranks can be
// tested in one process (tests/parallel/test_halo_coupling.cpp).
//
// Which boxes are enough. Rank r reads, for each cell of its own floes'
// pieces, whether another rank's floe may have pieces there and which
// ranks' (FloeSeaContact::sum_coverage_by_owner). A floe's pieces lie in
// the cells built at its reference pose (the footprints' last rebuild),
// within
//     rows_i = ceil((R_i + (1 + reach) dy) / dy) + 1
// rows of the row of its centroid there (R_i its largest vertex distance
// from the centroid, one cell for the tent's spread, the window's reach;
// MovingFootprints::reach_rows' bound for one floe), so rank r's floes'
// pieces lie within own_rows = max_i rows_i of its slab of the owners (each
// owns the floes whose centroid's row its slab held then). A box covers a
// cell of rank r's pieces only if one of its rows lies within own_rows of
// the slab (on the grid's circle: a superset on a walled grid), so only the
// boxes of the floes j of other ranks with such a row are read: in lengths,
// the boxes reaching within R_max + about two cells and the window's reach
// of the slab. The test reads the boxes themselves (gathered from their
// owners with the serial order), no floe's pose or radius: a rank needs no
// other rank's floe's reference pose.

#include <cstdint>
#include <span>
#include <vector>

#include "coupling/footprint.hpp"
#include "fluid/grid.hpp"
#include "parallel/cell_routes.hpp"

namespace floesim {

// rows_j above: the rows floe j's pieces may lie from its centroid's row.
int piece_rows_of(double radius, double reach, double dy);

// The floes among `candidates` that another rank owns (owner[j] != rank)
// and whose boxes may cover a cell of rank `rank`'s pieces: the criterion
// above, with first_row the owners' slabs (as fluid::Sea::slab_rows gives
// them), box[j] the floes' boxes (read for the candidates only) and
// own_rows the rows the rank's floes' pieces may lie from its slab. In the
// candidates' order.
std::vector<std::uint32_t> box_neighbours(std::span<const std::uint32_t> candidates, std::span<const int> owner, int rank,
                                          std::span<const int> first_row, std::span<const parallel::CellBox> box,
                                          const fluid::SurfaceGrid& grid, int own_rows);

// The sender's side of box_neighbours: the ranks other than `owner` whose
// box_neighbours would keep a floe of `owner` with box b, i.e. the ranks
// whose slab holds a row within own_rows of one of the box's rows (on the
// grid's circle), with row_owner the owners' slabs per row
// (parallel::row_owners(first_row)). Appended to `out` ascending, each
// once. So the owner of a floe sends its box to exactly the ranks that read
// it (FloeSeaContact::order_by_owner), and needs no other rank's floes.
void box_readers(const parallel::CellBox& b, int owner, std::span<const int> row_owner, int columns, int own_rows,
                 std::vector<int>& out);

// Whether two boxes hold a common cell: their rows' ranges and their
// columns' ranges, as CellBox::for_each visits them (the grid's seams
// crossed), both meet. A box empty (first_cell kNone) meets none. On a sea
// not in slabs a floe's box goes to the ranks whose box of all their
// pieces' cells it meets: a cell of that rank's pieces it covers lies in
// both.
bool boxes_meet(const parallel::CellBox& a, const parallel::CellBox& b, int columns, int rows);

// The cells of the boxes of `floes` (each another rank's, owner[j]) in
// rows outside the slab's interior (interior_row[y] == 0): each cell whose
// kind is `open` becomes `shared` (listed in `painted`, numbered in
// shared_at from 1), and every cell gets its floes' owners' bits in
// shared_ranks (rank_words 64-bit words a shared cell). Reads box[j] and
// owner[j] of `floes` only.
struct SharedMarks {
  std::vector<std::uint32_t> painted, shared_at;
  std::vector<std::uint64_t> shared_ranks;
};
void mark_shared_cells(std::span<const std::uint32_t> floes, std::span<const parallel::CellBox> box,
                       std::span<const int> owner, int columns, int rows, std::span<const std::uint8_t> interior_row,
                       std::span<std::uint8_t> kind, std::uint8_t open, std::uint8_t shared, std::size_t rank_words,
                       SharedMarks& marks);

}  // namespace floesim
