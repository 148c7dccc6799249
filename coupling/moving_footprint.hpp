#pragma once
// Footprints that move with their floes between rebuilds (docs/coupling.md,
// "Footprints that move").
//
// Building a floe's pieces (coupling/footprint.hpp) costs a pass over its
// outline cut at the grid lines and over its bounding box, while a floe
// moves a few millimetres per step. So the pieces are built at a reference
// pose P0 = (G0, theta0) and, while the floe stays near it, moved to first
// order in its displacement (delta, phi) = (G - G0, theta - theta0) with the
// outline integrals the build gives anyway (the edge pieces: N = d a_c / dG,
// T = d a_c / dyaw, Q - a_c I = d m_c / dG, S = d m_c / dyaw, where
// m_c = a_c r_c is the piece's first moment about G):
//     a_c(P) = a_c(P0) + N_c . delta + T_c phi,
//     m_c(P) = m_c(P0) + (Q_c - a_c(P0) I) delta + S_c phi.
// A piece with no edge piece lies inside the floe: its a_c is fixed and
// m_c -= a_c delta (its node is fixed while G moves).
//
// The moved pieces are affine functions of the pose, so a force computed as
// the gradient of an energy built on them (the contact's horizontal forces,
// coupling/floe_sea.hpp, with a_c(P0) where d m_c / dG holds it) is that
// energy's exact gradient: the splitting keeps its energy behaviour while no
// floe is rebuilt. The affine pieces differ from the exact ones by
// O(|delta|^2 + R^2 phi^2) on the floe's boundary (a_c is C^1 in the pose
// with the tent kernel, piecewise smooth with the cell kernel), so a
// rebuild changes a boundary piece by about reach^2 / 2 of a cell's area. A
// piece whose affine area would be negative (a node the floe is leaving)
// gets none and is left out of the forces.
//
// The window: all pieces are rebuilt when any floe's vertices may have moved
// more than `reach` cells along x or y,
//     |delta_x| + R |phi| > reach dx  or  |delta_y| + R |phi| > reach dy,
// R the floe's largest vertex distance from its centroid. reach = 0 rebuilds
// at every placement (the exact pieces). On several ranks each rank tests
// its own floes (mine()) and one reduction agrees on the verdict: "every
// floe inside" is the conjunction over a partition of the floes, so the
// ranks' verdicts combined by a minimum are the serial verdict, on every
// rank alike (every rank must rebuild or move together: the rebuild sets the
// owners and the gathers are collective). A move reads the own floes' poses
// only; a rebuild reads the poses set_owners reads (every floe's).
//
// On several ranks (a parallel::Communicator, docs/parallel.md) each rank
// builds or moves the pieces of the floes it owns (mine()) and receives
// every other floe's area pieces from its owner, so every rank holds all
// area pieces, to the bit as a serial run builds them (each floe's pieces
// depend on that floe alone). The owners are set at each rebuild, from the
// poses it builds at, and kept until the next one (the pieces stay with
// their builder): by index (Communicator::share) by default; by place
// (set_slabs, stage five) the rank whose slab of the sea's rows holds the row
// of the floe's centroid owns it. The edge pieces stay with their floe's
// owner: only the horizontal loads read them, and the owner computes those.
// With set_gather(false) the area pieces are not gathered either: each rank
// holds its own floes' pieces only (the contact evaluated by owner,
// docs/parallel.md, stage three, whose readers of another floe's pieces
// take them per cell, parallel::CellRoutes); the other floes' ranges are
// empty. A reader that needs every floe's pieces once (the static start)
// asks for a gathered copy (every_floe), which it frees after.

#include <cstdint>
#include <span>
#include <utility>
#include <vector>

#include "core/error.hpp"
#include "coupling/footprint.hpp"
#include "parallel/comm.hpp"

namespace floesim {

// Floe i's displacement (delta, phi) from `reference` to `at`, the grid's
// seam crossed the short way (periodic).
FloePose window_displacement(const fluid::SurfaceGrid& grid, const FloePose& reference, const FloePose& at);
// Whether every floe of `floes` with include[i] lies within its window
// (above: reach in cells, radius[i] = R) about reference[i] at poses[i].
// Reads the entries of `floes` only.
bool inside_windows(std::span<const std::uint32_t> floes, std::span<const std::uint8_t> include,
                    std::span<const FloePose> reference, std::span<const FloePose> poses, std::span<const double> radius,
                    const fluid::SurfaceGrid& grid, double reach);

struct FootprintMotionOptions {
  // Cells a floe's vertices may move before its pieces are rebuilt ([coupling]
  // footprint_reach). 0: rebuilt at every placement.
  double reach = 0.0;
  // The pieces' arrays after each rebuild (their layout only: no result
  // reads a capacity). A build appends, each array growing by doubling, and
  // a clear keeps the capacity from one build to the next, so an array
  // would keep up to twice the most pieces any build had. An array whose
  // spare capacity exceeds fit_slack times its size is copied into one with
  // fit_spare times its size spare. The defaults copy at the builds whose
  // count grew or fell by about a tenth, not at every build; with
  // fit_spare > fit_slack every rebuild copies. Both >= 0.
  double fit_slack = 0.25;
  double fit_spare = 0.125;
};

class MovingFootprints {
public:
  MovingFootprints() = default;
  MovingFootprints(const fluid::SurfaceGrid& grid, FootprintKernel kernel, FootprintMotionOptions options);

  // The pieces of every floe with include[i], floe i at poses[i]: moved from
  // the reference poses when every floe is inside its window (and the floes
  // and include are those of the reference), else rebuilt with poses as the
  // new reference. Returns true when rebuilt.
  bool place(const Floes& floes, std::span<const std::uint8_t> include, std::span<const FloePose> poses,
             int threads);
  // The same in two steps, for a caller that poses the floes it needs only:
  // whether the pieces can move to `poses` (the window's test above over
  // this rank's floes, poses[i] read for i in mine() only; on several ranks
  // collective, one reduction of 8 bytes when the window may hold), then
  // the placement with that verdict (moved: poses of mine() read; rebuilt:
  // every floe's, which set_owners reads).
  bool movable(std::span<const std::uint8_t> include, std::span<const FloePose> poses) const;
  // With `owners` (by place: takes_owners; or any rule of the caller's
  // when no slabs are set, e.g. FloeSeaContact's strips of a sea not in
  // slabs), a rebuild takes its owners from them instead of from the poses,
  // and reads the poses of its own floes (owners[i] == rank) only. On
  // several ranks only; the same on every rank. After keep_owners() it
  // keeps owners() (`owners` empty, or owners() itself).
  bool place(const Floes& floes, std::span<const std::uint8_t> include, std::span<const FloePose> poses, int threads,
             bool move, std::span<const int> owners = {});
  // The next rebuild keeps the last rebuild's owners (owners(), mine()) and
  // reads the poses of its own floes only: for a caller whose present
  // owners still hold their floes and that has no newer ones to give
  // (FloeSeaContact::given_owners on a sea not in slabs). On several ranks,
  // with owners() sized for the present floes; the same on every rank.
  // Spent by that rebuild.
  void keep_owners() {
    FLOESIM_ASSERT(!comm_.serial() && !owner_.empty());
    keep_owners_ = true;
  }
  // Whether the next rebuild may take its owners given: the owners by place
  // (set_slabs) on the slabs first_row, which are those its owners follow
  // (the grid's rows, the row of the centroid: parallel::grid_row, the rule
  // parallel::FloeOwners applies with the same slabs, so that owners
  // assigned by it at the poses of the rebuild are the ones set_owners
  // would set, to the bit). The same on every rank.
  bool takes_owners(std::span<const int> first_row) const;
  // Every floe's reference pose (a checkpoint's): as kept here when the
  // last rebuild posed every floe; when it took its owners given (and posed
  // this rank's floes only), each floe's from its owner (collective then:
  // one gather, 24 bytes a floe; every rank calls it alike).
  std::vector<FloePose> whole_reference() const;
  // Builds at `reference` and makes it the reference (a restart).
  void rebuild_at(const Floes& floes, std::span<const std::uint8_t> include, std::span<const FloePose> reference,
                  int threads, std::span<const int> owners = {});
  // Share the work among these ranks (by default the serial run: one rank).
  void set_communicator(const parallel::Communicator& comm) { comm_ = comm; }
  // Whether the next builds and moves send every floe's area pieces to every
  // rank (true by default); false: each rank keeps its own floes' pieces.
  void set_gather(bool all) { gather_ = all; }
  // Every floe's area pieces (offsets, cells, areas, centroids; no edge
  // pieces): pieces() itself when it holds them (one rank, or gathered at
  // each build and move), else every floe's gathered from its owner into
  // `scratch`, in floe order, the same bits as a gathered build (collective
  // then: one gather; every rank calls it alike).
  const Footprints& every_floe(Footprints& scratch) const;
  // Own the floes by place from the next rebuild on: first_row as
  // fluid::Sea::slab_rows gives it (rank r's slab holds rows [first_row[r],
  // first_row[r + 1]) of the grid); empty: by index.
  void set_slabs(std::vector<int> first_row);
  // The sea's slabs moved (issue 21 stage seven). With `owners_follow` the
  // owners follow them from the next rebuild on (the pieces stay with their
  // builder until then); else they stay on the slabs of set_slabs. Until
  // the owners' slabs are the sea's, reach_rows() grows by the largest move
  // of a cut, so that the pieces of a rank's floes still lie within
  // reach_rows() of its slab of the sea.
  void set_sea_slabs(std::vector<int> first_row, bool owners_follow) {
    FLOESIM_ASSERT(first_row.size() == owner_rows_.size());
    if (owners_follow) next_owner_rows_ = first_row;
    sea_rows_ = std::move(first_row);
  }
  // This rank's floes, in floe order, and each floe's owner (the same on
  // every rank), as set by the last rebuild: all floes when serial.
  std::span<const std::uint32_t> mine() const { return mine_; }
  std::span<const int> owners() const { return owner_; }
  bool owns(std::size_t i) const { return owner_[i] == comm_.rank(); }
  // Whether the last rebuild set the owners by place, and then how many rows
  // of the grid a floe's pieces may lie from the row of its centroid there,
  // until the next rebuild: its largest radius, the tent's spread of one
  // node and the window's reach, in rows, rounded up, plus one.
  // When the sea's slabs moved away from the owners' (set_sea_slabs), the
  // largest move of a cut is added: the pieces then lie within that many
  // rows of their owner's slab of the sea.
  bool by_place() const { return by_place_; }
  // The rows a floe's pieces may lie from its centroid's row at the last
  // rebuild (the largest floe's), its window's reach (cells) and, per floe,
  // R (coupling/shared_cells.hpp bounds one floe's rows with them).
  int piece_rows() const { return piece_rows_; }
  double reach() const { return options_.reach; }
  std::span<const double> radius() const { return radius_; }
  // The slabs the owners were set by at the last rebuild (empty: by index).
  std::span<const int> owner_slabs() const { return owner_rows_; }
  int reach_rows() const { return reach_rows_from(sea_rows_); }
  // The same from other slabs (first_row as set_slabs takes it): the rows a
  // floe's pieces may lie from those slabs' slab of its owner.
  int reach_rows_from(std::span<const int> first_row) const;

  // The next placement rebuilds (the floes changed; so may their radii).
  void forget() {
    reference_.clear();
    radius_.clear();
  }

  // The calling thread's CPU time (s, parallel::thread_seconds) spent
  // building and moving this rank's floes' pieces since the last take, the
  // gathers excluded (a wait in a collective call may spin): the per-floe
  // work the load balance charges to the owners (parallel::FloeOwners::
  // charge_coupling). Timed on several ranks only.
  double take_owned_seconds() { return std::exchange(owned_seconds_, 0.0); }

  const Footprints& pieces() const { return pieces_; }
  // Each area piece's a_c at the reference pose (m^2).
  std::span<const double> reference_area() const { return area0_; }
  // The reference poses (empty before the first placement): this rank's
  // floes' (mine()); every floe's only when the last rebuild posed every
  // floe (whole_reference()).
  std::span<const FloePose> reference() const { return reference_; }
  long placements() const { return placements_; }
  long rebuilds() const { return rebuilds_; }

  // What this object allocates, against the held floes' entries
  // (core/floe_bytes.hpp; `held` empty: every floe): per floe (reference
  // poses, include, radius, owner; this rank's floes' list), the area
  // pieces (the CSR of Footprints with each piece's reference area and
  // moment) and the edge pieces (their CSR).
  struct Memory {
    FloeBytes per_floe, area_pieces, edge_pieces;
  };
  Memory memory(std::span<const std::uint8_t> held) const;

private:
  void move(std::span<const FloePose> poses, int threads);
  // owner_ and mine_ for floes at `poses` (the rebuild's), or `owners`
  // given by place (takes_owners), or owner_ kept (keep_owners).
  void set_owners(std::span<const FloePose> poses, std::span<const int> owners);
  // Every floe's area pieces from their owners, in floe order, into `full`
  // (its edge pieces left empty), after this rank built its own alone.
  void gather_area_pieces(Footprints& full) const;
  // After this rank built its floes' pieces alone: every floe's area pieces
  // from their owners (gather_area_pieces) into pieces_; the edge pieces are
  // this rank's.
  void gather_built();
  // After this rank moved its floes' pieces: the others' areas and centroids.
  void gather_moved();

  fluid::SurfaceGrid grid_;
  FootprintKernel kernel_ = FootprintKernel::cell;
  FootprintMotionOptions options_;
  Footprints pieces_;
  std::vector<FloePose> reference_;
  std::vector<std::uint8_t> include_;
  std::vector<double> radius_;  // per floe, R (a constant of its outline: made again when the floes change)
  std::vector<double> area0_;   // per area piece, a_c(P0)
  std::vector<Vec2> moment0_;   // per area piece, m_c(P0)
  long placements_ = 0, rebuilds_ = 0;
  double owned_seconds_ = 0.0;  // take_owned_seconds()
  parallel::Communicator comm_;
  bool gather_ = true;
  bool keep_owners_ = false;    // keep_owners(): the next rebuild keeps owner_ and mine_
  std::vector<int> row_owner_;  // by place: per grid row, the rank whose slab holds it; empty: by index
  std::vector<int> owner_;      // per floe
  std::vector<std::uint32_t> mine_;
  bool by_place_ = false;
  bool reference_whole_ = true;  // the last rebuild posed every floe (else mine_ only)
  int piece_rows_ = 0;  // the rows a floe's pieces may lie from its centroid's row (last rebuild)
  // The slabs that gave the owners at the last rebuild, the sea's now
  // (set_sea_slabs), and those the next rebuild's owners follow (empty:
  // owner_rows_).
  std::vector<int> owner_rows_, sea_rows_, next_owner_rows_;
};

}  // namespace floesim
