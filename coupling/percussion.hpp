#pragma once
// The percussion phase of a run step (MODEL.md §5 step 5 and §6): after the
// step's collisions, each floe they loaded is checked for fracture initiation
// with its elastic model (contact/fracture), and with [fracture] split = true
// a floe cracked through is replaced by its two pieces
// (contact/fracture/split.hpp), which carry on in the run.
//
// Loads. Every collision solve of the step (at its start, in its sub-steps,
// in a jam's time steps) appends its impulses to a contact::ImpulseRecord, in
// each floe's body frame. Contact j between floes a and b (normal N from a to
// b, tangent T = k x N) gave J = lambda N + beta T to b and -J to a.
//
// The load rule (docs/fracture.md). A floe's loads of a step are of two kinds:
//  * impacts: the impulses of contacts that were not resting, one collision
//    instant (event) at a time. Each event's impulses are a percussion, spread
//    over `duration` (response.hpp): the dynamic response, rigid motion
//    removed.
//  * sustained contact: the impulses of resting contacts (their points
//    approached no faster than [contact] rest_speed before the solve:
//    a jam's contacts, a floe pushed against a coast; contact/impulse.hpp,
//    ImpulseRecord). Their sum
//    over the step of length dt is the mean contact force F = sum J / dt, a
//    quasi-static load: the static response to F with the rigid motion
//    removed (inertia relief: the forces that accelerate the floe as a whole,
//    wind and drag included, balance F as body forces). A jam's impulses are
//    its floes' forces times dt, not blows: judged as percussions over 10 ms
//    they would be dt/tau times too strong.
// The model is linear, so an event's percussion is judged with the
// sustained forces superposed, and the sustained forces alone when no event
// needs an analysis. Both meet the same criterion and strength.
//
// Screening. An analysis costs a solve per floe, so a floe is analysed only
// when a stress scale of its loads reaches `screen` times the stress the
// criterion needs (the strength; for griffith the stress sqrt(E G_c / (pi s))
// that would open a flaw of one mesh size s):
//   impacts:    p = (pi |J|max / (2 tau)) / (h 2 r)   (peak force over
//               thickness x patch width, r the load radius)
//   sustained:  the larger of the contact pressure |F|max / (h 2 r) and the
//               bending of the floe as a beam of span D (its diameter) and
//               depth w = A / D under the forces: 3 (sum |F|) D / (4 h w^2)
//               (a simply supported beam under a uniform load; exact for a
//               long floe between two supports);
// the two add when an event has sustained forces beside it. The tests'
// largest tensile stresses stay below these scales (docs/fracture.md), so
// the default screen of 0.1 leaves a wide margin.
//
// Stress bound. Past the screen, a stress-criterion case whose exact upper
// bound (fracture::Responder::stress_bound) is below the strength is not
// analysed (PercussionCounts::bounded): it could not initiate. A case that is
// analysed stops its time loop as soon as the same bound, taken on the
// energy the response holds, shows that no later step can reach the
// strength (FloeFracture::decide; PercussionCounts::cut_short).
//
// Models are built on a floe's first case past the screen (meshing and factorisations)
// and kept for its later ones; a floe that splits drops its model, and its
// pieces are not checked again in the step that made them.
//
// Two parts. Each loaded floe's analyses are independent of the others':
// they read the floe's outline, material and loads only, and a split
// replaces the split floe and appends a piece, leaving every other floe's
// index and data as they were. So check() is (1) analyse(): the loaded
// floes of a share, each to its verdict (the counts, and the initiation if
// one of its cases initiated, with its split decided against the floes the
// step ended with), and (2) conclude(): in floe order, the initiations
// become events and splits. A split's decision reads its floe and the floes
// within reach of it (the pieces must not overlap them), so conclude keeps
// it unless an earlier split of the step was within reach (before or after
// it), and decides that one again against the floes as they then are: the
// serial loop's decision either way. On several ranks each rank analyses
// the floes it owns, the ranks exchange the verdicts (the Simulation's
// percussion phase, docs/parallel.md "The fracture checks by owner"), and
// every rank concludes on all of them: the serial events and splits. The
// serial run is the share that owns every floe.

#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <type_traits>
#include <unordered_map>
#include <unordered_set>
#include <vector>

#include "contact/detection.hpp"
#include "contact/impulse.hpp"
#include "core/params.hpp"
#include "core/run_file.hpp"

namespace floesim {

namespace fracture { class FloeFracture; }

// The step's collisions as rows of /events/collisions, from the loads of
// `record` (floes at the end of the step, t): one row per solve and pair of
// floes, the pair's contacts summed (normal impulse; point weighted by it).
// Rows are in the order of the solves, then of the floe numbers.
std::vector<CollisionEventRow> collision_rows(const Floes& floes, const contact::ImpulseRecord& record, double t);

// The counts an analysis makes (its floes' verdicts): summed over the
// shares, they are the serial run's.
struct PercussionCounts {
  long checks = 0;      // floes analysed (again when a step is redone)
  long screened = 0;    // floes loaded but below the screen
  long bounded = 0;     // load cases past the screen whose stress bound is below the strength (not analysed)
  long sustained = 0;   // of checks, of sustained forces alone (static)
  long cut_short = 0;   // of checks, time loops stopped once they could no longer initiate (Response::cut_short)
  long loop_steps = 0;  // time steps run by the checks' responses
  PercussionCounts& operator+=(const PercussionCounts& o) {
    checks += o.checks;
    screened += o.screened;
    bounded += o.bounded;
    sustained += o.sustained;
    cut_short += o.cut_short;
    loop_steps += o.loop_steps;
    return *this;
  }
};

// On several ranks the counts are the serial run's (every rank adds every
// rank's, Percussion::conclude); models and the seconds are this rank's own
// (the models it built, the time it spent).
struct PercussionStats {
  PercussionCounts counts;  // the analyses' verdicts
  long initiations = 0;   // events (a crack whose line leaves the floe at once, from a corner, is not split)
  long splits = 0;
  long failed_splits = 0;  // cracked through but not split (sliver, or the pieces would overlap)
  long refused_small = 0;    // of failed_splits, a piece below min_fragment_area
  long refused_overlap = 0;  // of failed_splits, a piece would overlap a neighbour however narrow the opening
                             // (the rest: the chord does not cut two valid polygons)
  double seconds = 0.0;    // wall time in analyses and bounds, models included
  long models = 0;         // floe models built (mesh, elastic model), on a floe's first case past the screen
  double model_seconds = 0.0;  // of seconds, wall time building them
  long splits_redone = 0;    // of the splits decided by the analysing share and needing the neighbours (split or
                             // refused_overlap), those decided again when concluding: an earlier split of the
                             // step was within reach of the floe (its neighbours had changed)
  double split_seconds = 0.0;  // wall time in splits (cut, overlap checks), without the rebuild after them
  // Where the time of the phase goes (docs/fracture.md, "In packs"):
  double phase_seconds = 0.0;   // the whole phase (check), screen and splits included
  double mesh_seconds = 0.0;    // of model_seconds, meshing the floes
  double bound_seconds = 0.0;   // of seconds, the stress bounds (factorisations they start included)
  double factor_seconds = 0.0;  // of seconds, assembling K and factorising (in bounds or analyses)
  long lattice_meshes = 0;      // of models, meshed by the lattice mesher (the rest by CGAL)
};

// One share of the analyses: per floe the rank that analyses it, and this
// share's rank (numbers, as contact::ClusterShare). A floe past the end of
// `owner` (added by a split since the owners were made; every floe when it
// is empty) is rank 0's: so every floe has one rank, and the default share,
// rank 0 with no owners, is the serial run's.
struct PercussionShare {
  std::span<const int> owner;
  int rank = 0;
  // Per floe, 1 if this rank holds it (its own floes and its halo band;
  // empty: every floe): the splits' neighbours are looked for among those
  // only. With the state held by owner (the halo exchange) the other
  // copies are stale, and a stale floe's place must not make a neighbour.
  std::span<const std::uint8_t> held;
  bool mine(std::size_t i) const { return (i < owner.size() ? owner[i] : 0) == rank; }
};

// What becomes of a floe cracked through ([fracture] split = true): split
// with an opening, or refused, and why (PercussionStats).
enum class SplitVerdict : std::uint64_t {
  undecided = 0,    // not decided yet (conclude decides it), or not asked (no through crack, split = false)
  split = 1,        // two pieces, opened by SplitDecision::gap
  refused_small,    // a piece below min_fragment_area at the full opening
  refused_overlap,  // two valid pieces, but at every opening a piece would overlap a neighbour
  refused_chord,    // the chord does not cut two valid polygons
};
// The verdicts Percussion::conclude takes again, and those it applies on
// their own; one place, as Percussion::may_split reasons from them:
//   - a verdict taken against the floe's neighbours (split, refused_overlap)
//     is taken again when a split made earlier in the step reached them;
//     the others (refused_small, refused_chord) stand whatever the others;
//   - so a floe splits without an earlier split near it only on a split
//     verdict or none yet (undecided: decided in conclude), and a step with
//     neither among its through cracks splits nothing (by induction in floe
//     order: a refused_overlap is taken again only near a split made).
inline bool decided_against_neighbours(SplitVerdict v) {
  return v == SplitVerdict::split || v == SplitVerdict::refused_overlap;
}
inline bool may_split_alone(SplitVerdict v) { return v == SplitVerdict::split || v == SplitVerdict::undecided; }

// A split worked out against given floes (Percussion::decide_split): the
// verdict and, for a split, the opening (m). A split is the same when its
// floe and its neighbours (the floes within reach of it) are.
struct SplitDecision {
  SplitVerdict verdict = SplitVerdict::undecided;
  double gap = 0.0;
};

// A loaded floe's initiation (one case of its step initiated): the event
// row (without the pieces) and what a split needs, with the split's
// decision as its analysing share worked it out against the floes the step
// ended with. Plain numbers, trivially copyable, so that ranks exchange them
// as bytes.
struct FloeInitiation {
  std::uint64_t floe = 0;     // index in the floes the step ended with (before the step's splits)
  std::uint64_t through = 0;  // 1: the crack reaches the outline at both ends (Initiation::through)
  double point_x = 0.0, point_y = 0.0;  // m, the floe's mesh (body) frame: where the crack starts
  double direction = 0.0;               // rad, mesh frame: the crack's line
  FractureEventRow event;               // piece_a, piece_b: -1 (set by the split)
  SplitDecision split;                  // undecided unless split = true and through
};
static_assert(std::is_trivially_copyable_v<FloeInitiation> && std::is_trivially_copyable_v<PercussionCounts>);

// One share's analyses of a step.
struct PercussionAnalyses {
  bool loaded = false;      // some floe was loaded: the same on every share (the record and floes are)
  PercussionCounts counts;  // of this share's floes
  double seconds = 0.0;     // wall time of this share's analyses (screens, bounds, models, time loops, splits decided)
  std::vector<FloeInitiation> initiations;  // in floe order
};

// The analyses by owner on several ranks, per rank (Simulation's percussion
// phase; the summary's parallel.fracture_*): the steps that exchanged
// analyses, and each rank's checks (summing to PercussionStats::counts.checks)
// and wall time in them (the share's PercussionAnalyses::seconds, summed).
struct PercussionRanks {
  long steps = 0;
  std::vector<long> checks;
  std::vector<double> seconds;
  // The steps in which a split may be made (Percussion::may_split), which
  // gather the states conclude reads first (every share's split_readers,
  // Simulation::split_states), and the bytes this rank received in those
  // gathers (the summary's parallel.split_gathers; docs/parallel.md, "The
  // split step's owners and gather by holder (split28)").
  long split_gathers = 0;
  long long split_bytes = 0;
};

// One share's analyses as bytes for parallel::Communicator::allgather_parts,
// and back (`loaded` is not sent: a share that sends has loaded floes).
std::vector<std::byte> pack(const PercussionAnalyses& analyses);
PercussionAnalyses unpack_percussion(std::span<const std::byte> bytes);

// The ranks' analyses of a step (`parts`, one per rank in rank order) as
// one, which Percussion::conclude takes: the counts summed, the seconds
// summed, every rank's initiations (rank by rank: conclude puts them in floe
// order). Each rank's checks and seconds are added to `ranks`, and the step
// counted.
PercussionAnalyses combine(std::span<const PercussionAnalyses> parts, PercussionRanks& ranks);

class Percussion {
public:
  // `gap`: how far apart the pieces of a split are put (m).
  Percussion(const FractureParams& params, double gap, double screen = 0.1);
  ~Percussion();
  Percussion(Percussion&&) noexcept;
  Percussion& operator=(Percussion&&) noexcept;

  // Checks the floes loaded in `record` during the step of length dt that
  // ends at time t (positions are those of t; the loads are in the floes'
  // body frames). Split floes are replaced in `floes`. Returns true if the
  // set of floes changed.
  // It is conclude(analyse(..., every floe)).
  bool check(Floes& floes, const contact::ImpulseRecord& record, double t, double dt);

  // The first part of check: the analyses of the loaded floes `share` owns.
  // The models of the floes analysed are built and kept on this share.
  PercussionAnalyses analyse(const Floes& floes, const contact::ImpulseRecord& record, double t, double dt,
                             const PercussionShare& share);
  // The second part: adds the counts of `all` (every share's analyses,
  // combined) to the stats and turns its initiations (any order) into events
  // and splits in floe order, each split as decided by its share unless an
  // earlier split of the step was within reach, or undecided (then decided
  // here, against the floes as they then are). Returns true if the set of
  // floes changed. `split` (if given) gets the indices of the floes split,
  // in floe order: each is now its first piece, the second appended
  // (FloeOwners::place_pieces takes them). `readable` (per floe before the
  // splits, 1: current; empty: every floe): the floes whose states it may
  // read, which must hold every share's split_readers; the pieces it
  // appends are read too (built from their parents).
  bool conclude(Floes& floes, PercussionAnalyses all, std::vector<std::uint32_t>* split = nullptr,
                std::span<const std::uint8_t> readable = {});
  // Whether conclude(all) may split a floe, and so read floes' states (the
  // parents', their neighbours'): conclude splits only a floe whose decision
  // is a split, or undecided, and takes a decision again only near a split
  // it made before in floe order. Without such an initiation (no through
  // crack, split = false, or every one refused for a sliver, a chord or the
  // neighbours) it splits nothing and reads no state (on several ranks no
  // floe is gathered for it).
  bool may_split(const PercussionAnalyses& all) const;

  // Floe i's split along the crack of `fi` (mesh frame), worked out against
  // `floes`: the pieces at the widest opening (from gap, quartered down to
  // 1e-3 gap) at which neither overlaps a floe within reach of floe i, or
  // why there is none. It reads floe i and the floes whose centroid lies
  // within R_i + R_j + gap of its centroid (R the radius about the
  // centroid), no other: within the halo band of floe i's owner
  // (docs/parallel.md, "Splits"; tests/parallel/test_halo_split.cpp).
  // `held` (per floe, 1: held; empty: every floe): the floes it may read,
  // which must hold those (the owner's band does): the same decision.
  // The floes past held's end (pieces appended since) are read.
  SplitDecision decide_split(const Floes& floes, std::size_t i, const FloeInitiation& fi,
                             std::span<const std::uint8_t> held = {}) const;
  // The floes a split of floe i is decided against, the one rule of
  // decide_split's neighbours: floe i first, then ascending every other
  // floe it may read (`held` as decide_split's) whose centroid lies within
  // R_i + R_j + gap of floe i's.
  std::vector<std::size_t> split_neighbours(const Floes& floes, std::size_t i,
                                            std::span<const std::uint8_t> held = {}) const;
  // The floes whose states conclude() may read for a share's initiations
  // `mine`, analysed against `held` (docs/parallel.md, "The split step's
  // owners and gather by holder (split28)"): each floe cracked through whose
  // verdict may be taken again or applied (split, refused_overlap,
  // undecided) and its neighbours (split_neighbours over `held`),
  // ascending, each once. Why every share's lists hold all that conclude
  // reads: changed_near reads such a parent's place; a split reads its
  // parent alone; a decision taken again reads the parent's neighbours at
  // its turn, which are the floes within reach at the analysis (a floe not
  // split keeps its place; the owner's band holds every one of them), the
  // indices of earlier splits (parents with a split verdict, listed) and
  // the pieces appended (built on every rank from their listed parents).
  std::vector<std::uint32_t> split_readers(const Floes& floes, const PercussionAnalyses& mine,
                                           std::span<const std::uint8_t> held) const;

  // The initiations since the last call.
  std::vector<FractureEventRow> take_events();
  const PercussionStats& stats() const { return stats_; }
  // m^2: no split leaves a piece smaller ([fracture] min_fragment_area, or
  // mesh_size^2 when that is 0: the model does not resolve smaller pieces).
  double min_fragment_area() const;
  // Restart: the counts go on from a checkpoint's (models are rebuilt on a
  // floe's next analysis, to the same bits).
  void restore_stats(const PercussionStats& stats) { stats_ = stats; }

private:
  fracture::FloeFracture& model_of(const Floes& floes, std::size_t i);
  // Makes `decision` (a split: floe i becomes the first piece, the second is
  // appended; the event gets their numbers) and counts it. Returns whether
  // the floes changed.
  bool apply_split(Floes& floes, std::size_t i, const FloeInitiation& fi, SplitDecision decision,
                   FractureEventRow& event);

  FractureParams params_;
  double gap_, screen_;
  std::unordered_map<std::uint32_t, std::unique_ptr<fracture::FloeFracture>> models_;  // by floe number
  std::unordered_set<std::uint32_t> fresh_;  // pieces made in the current step
  double fresh_time_ = -1.0;
  std::vector<FractureEventRow> events_;
  PercussionStats stats_;
};

}  // namespace floesim
