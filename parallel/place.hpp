#pragma once
// Stage six of docs/parallel.md: the floes owned by place, for the work that
// is per floe (the drift) and per pair (detection).
//
// The state stays replicated on every rank; what is split by place is the
// work. Rank r owns the floes whose centroid lies in its strip, a band
// [cut[r-1], cut[r]) along y (cut[-1] = -inf, cut[ranks-1] = +inf), y wrapped
// into a periodic box first. Strips run along y because the spectral sea's
// slabs do (stage four), so that a floe's neighbours across a strip boundary
// are few. The owners are recomputed at every step: a floe whose centroid
// crosses a cut "migrates", its owner announcing it (migrate(), leaving();
// docs/parallel.md, update25), so that no rank reads another's floes.
//
// Load balance by measured cost: each rank charges the CPU time of its
// by-place work (its floes' drift, its part of detection: no waits, no
// copies; the thread's CPU time, which leaves out other processes' time
// slices) to its FloeOwners; every
// StripOptions::rebalance_steps steps the ranks all-gather their charged
// times and move the cuts toward those that give every strip an equal share
// of the estimated cost (cut_by_cost), each floe's cost being its owner's
// time per floe over the window. The cost density in y is
// thus estimated as piecewise constant over the old strips; when it is
// steady, one move balances the ranks to within one floe's cost, and a
// window of several steps averages the timing noise. Every rank computes the
// same cuts from the same gathered times (the same code on the same data),
// so the ranks agree on the owners without another message. The answer does
// not depend on the cuts: every phase by place gives the serial result.
//
// Stage seven: with a spectral sea in slabs the strips are the sea's slabs
// (set_slabs): the cuts are whole blocks of the transform's rows, a floe's
// owner is the slab of its centroid's row, and the moves are by the cost of
// the drift, detection, the floe–sea coupling's per-floe work, the fracture
// analyses (charge_fracture, with or without slabs) and the sea's row
// passes, per row (set_slabs' comment).

#include <cstdint>
#include <span>
#include <vector>

#include "contact/detection.hpp"
#include "contact/shapes.hpp"
#include "core/error.hpp"
#include "core/floes.hpp"
#include "parallel/comm.hpp"

namespace floesim::parallel {

struct StripOptions {
  // Steps between two moves of the cuts by measured cost (each move is one
  // collective call of 32 bytes a rank). Ten steps average out the scheduler's
  // noise in a window of a 10 000-floe pack (about 0.1 s of by-place work).
  int rebalance_steps = 10;
  // A floor on a floe's estimated cost, as a fraction of the mean cost per
  // floe: a rank that measured (almost) nothing, e.g. whose floes are all
  // static, would otherwise be given every floe at the next move.
  double cost_floor = 0.01;
  // How far a move goes from the present cuts toward the equal-cost cuts
  // (1: all the way). The estimate of a window is noisy (a rank's time
  // varies by 10 to 20 % from window to window on a shared machine); half
  // way halves the cuts' jitter and still closes a steady imbalance by half
  // at every move.
  double relaxation = 0.5;
};

// The CPU time of the calling thread (s): what a rank charges for its
// by-place work. Unlike the wall clock it leaves out the time the thread was
// not running (another process on the core), which says nothing of the
// work's cost.
double thread_seconds();

// Cuts items at positions y into `ranks` strips of equal total cost: returns
// ranks - 1 ascending cuts; strip r holds the items with
// cut[r-1] <= y < cut[r]. Each cut lies midway between two items adjacent in
// y (or at +-infinity when a strip gets none), placed where the running sum of
// the costs, items taken by ascending y, comes nearest to r/ranks of the
// total: each strip's cost is within one item's cost of total/ranks, items
// with equal y excepted (they stay together).
std::vector<double> cut_by_cost(std::span<const double> y, std::span<const double> cost, int ranks);

// Cuts the rows of a grid into `ranks` slabs of whole blocks of `block` rows
// (the last block may be shorter) of equal total cost: returns the first row
// of each slab then the row count (ranks + 1 values, as
// fluid::Sea::slab_rows). Each cut is the block boundary where the running
// cost, blocks taken in order, comes nearest to r/ranks of the total, so
// that each slab's cost is within one block's cost of the mean; every slab
// holds at least one block (there must be at least `ranks` blocks).
std::vector<int> cut_rows_by_cost(std::span<const double> row_cost, int block, int ranks);

// A floe that leaves its owner's strip, as its owner announces it at the
// detection (FloeOwners::leaving; docs/parallel.md, "The hand-over at a
// move of the cuts and the owners from their own floes (handover25)"): its
// index, its owner at its present place, its place (FloeOwners::place, m)
// and its detection reach (m), which only its old owner computed
// (Simulation::set_reach over the own floes): the new owner's strip is
// widened by that place and half band (announce_held).
struct LeaveNotice {
  std::uint32_t floe = 0;
  std::int32_t owner = 0;
  double place = 0.0;
  double reach = 0.0;
};

// The spectral sea's slabs as the floes' strips (issue 21 stage seven): the
// slabs' first rows (ranks + 1 values), the grid's row height (its first row
// at y = 0) and the transform's block of rows, the unit a cut moves by.
struct RowSlabs {
  std::vector<int> first_row;
  double dy = 1.0;
  int block = 8;
  int rows() const { return first_row.empty() ? 0 : first_row.back(); }
};

class FloeOwners {
public:
  FloeOwners() = default;  // one rank: owns every floe
  FloeOwners(int rank, int ranks, const contact::Domain& domain, StripOptions options = {});

  // The strips are the sea's slabs from now on (stage seven): rank r owns
  // the floes whose centroid's row (parallel::grid_row, the rule the
  // coupling's owners use) lies in its slab, and the moves by measured cost
  // move the slabs' cuts by whole blocks (update()). The cost model: a row
  // costs the sea's row work, the same for every row (the transforms' row
  // passes: the ranks' charged row seconds summed, over the rows), plus the
  // by-place cost (drift, detection, the coupling's per-floe work, the
  // fracture analyses) of the floes whose centroid lies in it, each floe
  // costing its owner's charged seconds over its owner's floe count (a density
  // piecewise constant over the old slabs, floored as without slabs). The
  // columns, and so the sea's modes, do not move.
  void set_slabs(RowSlabs slabs);
  bool has_slabs() const { return !slabs_.first_row.empty(); }
  const RowSlabs& slabs() const { return slabs_; }

  int rank() const { return rank_; }
  int ranks() const { return ranks_; }

  // The owners of the floes at their present places. Until cuts are set
  // (set_cuts, update), the strips hold equal numbers of floes. Reads every
  // floe's place.
  void assign(const Floes& floes);
  // The same owners from the owners' own floes (the cuts set, owners
  // assigned for these floes): each rank tests only the floes it owns
  // against the cuts, leaving() (its floes that now lie in another strip,
  // ascending, with their places; their reaches left 0 for the caller), and
  // every rank applies every rank's notices, take_leaving() (in any order,
  // in parts: a floe has one owner, so one notice; announce_held carries
  // them). A floe's owner is a function of its place alone
  // (owner_at), evaluated by its owner on the same doubles as assign()
  // evaluates it on every rank: the same owners, bit for bit, without
  // reading another rank's floes. `rank`: this object's rank, or a
  // simulated rank (tests: its floes from the owner array).
  std::vector<LeaveNotice> leaving(int rank, const Floes& floes) const;
  void take_leaving(std::span<const LeaveNotice> notices);
  // Whether leaving() may replace assign() for `floes`: cuts set and an
  // owner for each floe (not at the start or after a restore; after a
  // split once place_pieces has owned its pieces).
  bool assigned_for(const Floes& floes) const { return (cut_ || has_slabs()) && owner_.size() == floes.size(); }
  // The owners of a step's split pieces (docs/parallel.md, "The split
  // step's owners and gather by holder (split28)"): each split replaces its
  // parent at the parent's index (`replaced`, any order) by its first piece
  // and appends its second (indices owner().size() and on). Each piece's
  // owner is owner_at of its state, which every rank builds alike from the
  // parent's (Percussion::conclude): the owner assign() gives it, without
  // reading any other floe. The other floes keep their owners: with the
  // cuts set and the owners assigned for the floes before the split,
  // leaving()/take_leaving() (or migrate()) then give assign()'s owners for
  // every floe from the owners' own floes.
  void place_pieces(const Floes& floes, std::span<const std::uint32_t> replaced);
  // The rank whose strip holds a floe in state s (the one rule of assign and
  // leaving): the owner of its key (with slabs its centroid's grid row, a
  // whole number held exactly in a double; else its place), which the cuts'
  // move gathers from the owners (update).
  int owner_at(const FloeState& s) const { return owner_of_key(key(s)); }
  double key(const FloeState& s) const;
  int owner_of_key(double key) const;
  // Collective (every rank at the same `step`): every options.rebalance_steps
  // steps, the cuts move by the ranks' charged times (above). First the
  // owners at the floes' present places: with the owners assigned for these
  // floes on several ranks, migrate() (from the owners' own floes), else
  // assign() (the start, after a split, serially). A move then gathers each
  // floe's key (key(): its row or place, 8 B a floe) from its owner with
  // the charges (one call), and every rank computes the new cuts and owners
  // from the gathered keys: no floe's copy but the rank's own is read. A step
  // redone after an overlap calls it again with the same `step`: no second
  // move (the migration then gives the owners at the restored places).
  // Returns whether the cuts moved (with slabs: the slabs, which the sea and
  // the coupling must then be given, on every rank alike).
  bool update(const Communicator& comm, const Floes& floes, std::size_t step);
  // Collective (assigned_for(floes), `comm` this object's ranks): the
  // owners at the floes' present places, assign()'s entry for entry, read
  // from the floes each rank owns only. Each rank announces its leaving()
  // floes, the notices are gathered in rank order (an allgather of 24 B a
  // notice: its counts' call, and the bytes' call only when some rank has
  // one) and every rank applies all of them (take_leaving: one owner a
  // floe, so any order). The other floes' copies are not read: they may be
  // stale or unwrapped (the halo exchange of piece 8).
  void migrate(const Communicator& comm, const Floes& floes);
  // Whether update(step) closes a window, and so may move the cuts (the
  // same on every rank).
  bool may_move(std::size_t step) const { return started_ && step >= next_move_; }
  // Charges this rank's CPU time (s, thread_seconds()) in by-place work since the last move.
  void charge(double seconds) { charged_ += seconds; }
  // With slabs: charges this rank's CPU time in the sea's row work.
  void charge_rows(double seconds) { row_charged_ += seconds; }
  // With slabs: charges this rank's CPU time in the floe–sea coupling's
  // per-floe work (FloeSeaContact::take_owned_seconds) as by-place work, as
  // charge() does: the coupling's owners follow the slabs (stage eight, the
  // same rule, grid_row, as assign()), so its work on a floe is done by the
  // floe's owner here, and it lands on the floe's row as the drift's does. It
  // is not row cost: that is spread evenly over every row (the transforms'
  // passes cost the same in each), while the coupling's follows the floes'
  // pieces. Kept apart too for the summary (coupling_seconds()).
  void charge_coupling(double seconds) {
    FLOESIM_ASSERT(has_slabs());
    charged_ += seconds;
    coupling_charged_ += seconds;
  }
  // Charges this rank's CPU time in the fracture analyses of the loaded
  // floes it owns (Percussion::analyse with the owners of owner()) as
  // by-place work, as charge() does: a floe's analyses are done by its owner
  // here, so their cost lands on the floe's place (on its row, with slabs).
  // Kept apart for the summary (fracture_seconds()).
  void charge_fracture(double seconds) {
    charged_ += seconds;
    fracture_charged_ += seconds;
  }

  std::span<const int> owner() const { return owner_; }  // per floe, after assign()
  // The owner array's and this rank's list's bytes (core/floe_bytes.hpp),
  // against `held` floes' entries of the owner array (the list is held).
  FloeBytes memory(std::size_t held) const {
    FloeBytes m = per_floe_bytes(owner_, held);
    m += {capacity_bytes(mine_), capacity_bytes(mine_)};
    return m;
  }
  const std::vector<std::uint32_t>& mine() const { return mine_; }  // this rank's floes, ascending
  // A floe's place: its centroid's y, wrapped into the box when periodic.
  double place(const FloeState& s) const;

  const std::vector<double>& cuts() const { return cuts_; }
  void set_cuts(std::vector<double> cuts);  // ranks - 1 ascending values
  // The moves so far, each rank's charged seconds over the last window, and
  // over every window so far.
  int moves() const { return moves_; }
  const std::vector<double>& window_seconds() const { return window_seconds_; }
  const std::vector<double>& charged_seconds() const { return total_seconds_; }
  // With slabs: each rank's coupling seconds (charge_coupling) over every
  // window so far, which charged_seconds() include.
  const std::vector<double>& coupling_seconds() const { return coupling_seconds_; }
  // Each rank's fracture seconds (charge_fracture) over every window so
  // far, which charged_seconds() include.
  const std::vector<double>& fracture_seconds() const { return fracture_seconds_; }

private:
  int rank_ = 0, ranks_ = 1;
  contact::Domain domain_;
  StripOptions options_;
  std::vector<double> cuts_;
  bool cut_ = false;  // cuts_ set (else equal counts at the next assign)
  std::vector<int> owner_;
  std::vector<std::uint32_t> mine_;
  double charged_ = 0.0, row_charged_ = 0.0, coupling_charged_ = 0.0, fracture_charged_ = 0.0;
  RowSlabs slabs_;                 // empty: free cuts in y
  std::vector<int> row_owner_;     // with slabs: per grid row, its slab's rank
  // A window's charged seconds, gathered (one collective call): per rank
  // its by-place seconds (the coupling's and the fracture analyses'
  // included), and the ranks' row seconds summed.
  struct WindowCharges {
    std::vector<double> floe;
    double rows = 0.0;
  };
  // The charges and every floe's key (n values, each from its owner; owners
  // assigned for these floes).
  WindowCharges close_window(const Communicator& comm, const Floes& floes, std::vector<double>& keys);
  void assign_keys(std::span<const double> keys);  // the owners from every floe's key
  std::vector<double> floe_costs(std::span<const double> floe_seconds) const;  // per floe, after assign()
  bool move_slabs(const Communicator& comm, const Floes& floes);
  bool move_cuts(const Communicator& comm, const Floes& floes);
  std::size_t next_move_ = 0;
  bool started_ = false;
  int moves_ = 0;
  std::vector<double> window_seconds_, total_seconds_, coupling_seconds_, fracture_seconds_;
};

// ---- The halo band (docs/parallel.md, "The state held by owner with a
// halo", "The band") ----
//
// Floe j's half band h_j = R_j + reach_j + xi/2 (R_j its bounding radius
// about the centroid, reach_j its detection reach, xi the collision
// distance): the y extent of its padded box lies within [y_j - h_j, y_j +
// h_j] about its place y_j (FloeOwners::place). H = max_j h_j over the pack.
// Rank r's halo band B_r: the floes j it does not own with
//
//     dist(y_j, S_r) <= H + h_j,
//
// S_r = [c_{r-1}, c_r) its strip (cut[-1] = -inf, cut[ranks-1] = +inf; the
// box's edges for the end strips of a periodic box), widened to the places
// of the floes r owns where one lies outside it (round-off at a cut, or a
// floe beyond the sea's grid in an open box, owned by the row it wraps to),
// the distance taken on the circle in a periodic box (the nearest image). Rank r holds its floes
// and B_r. Why that is enough for its part of the detection: a pair is a
// candidate only when its padded boxes overlap, so |y_a - y_b| <= h_a + h_b
// (nearest image), and rank r keeps the pairs whose floe a it owns, y_a in
// S_r: dist(y_b, S_r) <= h_a + h_b <= H + h_b. The strip widened by H alone
// is too thin (b may lie h_a + h_b beyond the cut). detection_subset poses
// only held floes (its hull of the owned floes' bands lies within S_r
// widened by H).
//
// Every h_j carries detection_subset's round-off margin, 1e-9 (1 + |y_j| +
// h_j), the same bits in both.
double half_band(const FloeOwners& owners, const Floes& floes, const contact::CollisionShapes& shapes,
                 const contact::DetectionOptions& options, std::size_t j);
// h_j from its parts: place y (m), bounding radius R_j, reach_j and the
// collision distance xi (the one formula of half_band and the band's passes).
double half_band_for(double y, double radius, double reach, double collision_distance);
// This rank's part of H: the largest h_j of the floes `rank` owns (owners
// assigned for these floes), 0 if it owns none. H is its largest over the
// ranks, one reduction (Communicator::max): every floe is owned by one rank,
// so that is max_j h_j over the pack.
double largest_half_band(const FloeOwners& owners, int rank, const Floes& floes,
                         const contact::CollisionShapes& shapes, const contact::DetectionOptions& options);

// Rank r's strip as its band's rule reads it: S_r = [lo, hi] widened to
// the places of the floes r owns (above), and r's part of H, the largest
// h_j of its own floes (0 if it owns none; largest_half_band's bits). A
// pass over r's own floes (owners assigned for these floes).
struct BandStrip {
  double lo = 0.0, hi = 0.0;  // m
  double largest = 0.0;       // m
};
BandStrip band_strip(const FloeOwners& owners, int rank, const Floes& floes, const contact::CollisionShapes& shapes,
                     const contact::DetectionOptions& options);
// dist(y, strip) along y, on the circle in a periodic box (the nearest of
// y's images y - L, y, y + L: every place lies in the box, so no other
// image is nearer); 0 inside.
double strip_distance(double y, const BandStrip& strip, const contact::Domain& box);

// The floes a rank holds: its own and its band.
struct HeldFloes {
  std::vector<std::uint32_t> index;  // ascending
  std::vector<std::uint8_t> mask;    // per floe: 1 if held
  double largest = 0.0;              // H (m), the band's largest half band
  bool holds(std::size_t i) const { return mask[i] != 0; }
};
// Rank `rank`'s held floes for the owners assigned at the floes' present
// places, their reaches in options, and H = `largest` (the ranks' largest
// largest_half_band). A pass over every floe's place: with the state held by
// owner each owner would test its own floes against the strips instead
// (the halo exchange, piece 8 of the plan).
HeldFloes held_floes(const FloeOwners& owners, int rank, const Floes& floes, const contact::CollisionShapes& shapes,
                     const contact::DetectionOptions& options, double largest);
// Every floe held (one rank, or the serial reference).
HeldFloes every_floe(std::size_t n);

// The halo rule: the part of the detection that `rank` makes. It keeps the
// pairs whose floe a it owns, and poses its floes and every floe whose padded
// box can reach one of theirs: the floes whose band
// [y - R - p, y + R + p] (R: the bounding radius about the centroid, p =
// reach + xi/2, the broad phase's pad) meets the union of the owned floes'
// bands, across the periodic seam too. A pair is a candidate only when its
// padded boxes overlap, so both floes of every kept pair are posed, and the
// kept pairs are the serial detection's pairs of the owned floes.
//
// With `held` (rank's held_floes, for the same floes, owners and reaches)
// only the held floes are read: every floe it poses is held (the band's
// rule, above), so the subset is the one from every floe, and the floes
// outside the band may hold anything (stale, or nothing at all).
contact::DetectionSubset detection_subset(const FloeOwners& owners, int rank, const Floes& floes,
                                          const contact::CollisionShapes& shapes,
                                          const contact::DetectionOptions& options,
                                          const HeldFloes* held = nullptr);

}  // namespace floesim::parallel
