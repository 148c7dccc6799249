#pragma once
// The time loop of a run. One call to step() advances the floes and the sea
// by one step; the step reads as a table of contents, one named and timed
// phase per line (MODEL.md §5, the staggered loop):
//
//   choose dt (output schedule, dt_max, penalty limit)
//   -> sample forcing
//   -> floes' half kick from the sea (penalty loads at t, coupling/floe_sea.hpp)
//   -> drift velocities (drag relative to current + the incident waves'
//      orbital velocity, wind, Coriolis) -> collide (LCPs: W(t-) -> W(t+))
//   -> advance horizontal positions (floes that may collide within the step
//      are sub-stepped event by event, contact/substep.hpp)
//   -> detect (new contacts; an overlap rejects the step, which is redone
//      with half the dt from the floes at t: the sea has not moved yet)
//   -> sea: half kick with the pressures at t, then the floes' vertical DOFs
//      and the sea over dt (explicit: their free flows, the sea's exact;
//      implicit: the midpoint step of the penalty spring, floe_sea.hpp)
//   -> penalty loads at t + dt: second half kick of the sea and the floes,
//      then the orbital velocity under the floes (for the next drag)
//   -> percussion (fracture checks on every collision impulse of the step,
//      collide's and the sub-steps', coupling/percussion.hpp; a split floe
//      becomes two, which start the next step)
//   -> check state and close the step's momentum budget (the whole-pack sums
//      are by owner and exact: docs/parallel.md, "Exact sums")
//
// The kicks and flows are the Strang splitting of the floe–sea Hamiltonian
// (second order, energy conserving for the strong law without drag); drag
// and collisions sit in the middle, where the floes' horizontal drift is.
// The loads at t + dt serve as the next step's first half kick (the strong
// law's do not depend on the kick length; the damper's are made afresh), and
// the sea's two half kicks by that one pressure share its projection
// (Sea::repeat_kick). Steps cut by the explicit penalty limit are equal and
// keep one dt, so the sea's rotations are computed once. With the implicit
// integrator there is no penalty limit: the kicks carry the damper and the
// horizontal forces only.
// Step contract: on entry the state is at time() and the contact detection
// matches the positions; step(t_stop) advances both to time() + dt with
// 0 < dt <= min(dt_max, t_stop - time()) and returns dt. At the end of every
// step no two floes overlap (or the step throws RunError naming the pair).
// Units: SI; the state layout is FloeState (core/floes.hpp).

#include <array>
#include <chrono>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "coupling/drift.hpp"
#include "coupling/floe_sea.hpp"
#include "coupling/incident.hpp"
#include "coupling/mooring.hpp"
#include "coupling/percussion.hpp"
#include "coupling/poison_mode.hpp"
#include "contact/detection.hpp"
#include "contact/impulse.hpp"
#include "contact/shapes.hpp"
#include "contact/substep.hpp"
#include "core/checkpoint.hpp"
#include "core/exact_sum.hpp"
#include "core/run_file.hpp"
#include "coupling/scenario.hpp"
#include "parallel/comm.hpp"
#include "parallel/advance_share.hpp"
#include "parallel/held.hpp"
#include "parallel/place.hpp"

namespace floesim {

namespace fluid { class Sea; }

enum class Phase { choose_dt, forcing, drift, collide, percussion, advance, detect, sea, check, record, penalty, count };
inline constexpr std::array<const char*, static_cast<std::size_t>(Phase::count)> kPhaseNames = {
    "choose_dt", "forcing", "drift", "collide", "percussion", "advance", "detect", "sea", "check", "record", "penalty"};

// Wall time spent in each phase (s), for `floesim run --profile`; on
// several ranks also this rank's collective calls and the bytes it received
// in them, by phase (the run's summary, docs/parallel.md "Communication per
// step").
struct Profile {
  static constexpr std::size_t kPhases = static_cast<std::size_t>(Phase::count);
  std::array<double, kPhases> seconds{};
  std::array<long long, kPhases> calls{}, bytes{};
  double& operator[](Phase p) { return seconds[static_cast<std::size_t>(p)]; }
  double operator[](Phase p) const { return seconds[static_cast<std::size_t>(p)]; }
};

// Per-step data passed from phase to phase.
struct StepContext {
  double t = 0.0;      // s, time at the start of the step
  double dt = 0.0;     // s
  ForcingSample forcing;
  // The floes at t, to redo a rejected step (Simulation::copy_start): every
  // floe's, or (start_held not empty) those of the floes marked there, the
  // others' entries left as they were (stale, unread).
  std::vector<FloeState> start;
  std::vector<std::uint8_t> start_held;  // per floe, 1 if copied into start; empty: every floe
  // The dynamic floes' momentum (x, y; kg m/s) at the try's start (before
  // the first half kick), after the drift, after the collisions and after
  // the advance, then before and after the sea's second half kick, as exact
  // sums (core/exact_sum.hpp): this rank's part, of the floes it owns, until
  // a call the step makes anyway combines them over the ranks (the try's
  // four: detection's reach, Simulation::set_reach; the kick's two: the
  // state check, Simulation::close_step); the step's budget is read then.
  std::array<ExactSum, 12> momenta;
  static constexpr std::size_t kAtStart = 0, kAfterDrift = 2, kAfterCollide = 4, kAfterAdvance = 6,
                               kTry = 8, kBeforeSeaKick = 8, kAfterSeaKick = 10;
  // The momentum at slot k (one of the above), once combined.
  Vec2 momentum_at(std::size_t k) const { return {momenta[k].value(), momenta[k + 1].value()}; }
};

// Energies by part (J), named as the columns of /diagnostics/energy; the last
// column is the total.
struct Energies {
  std::vector<std::string> names;
  std::vector<double> values;
};

class Simulation {
public:
  // `comm`: the ranks of a distributed run (parallel/comm.hpp; default: serial).
  // The ranks share the step by place (each its floes, docs/parallel.md);
  // each rank keeps current the floes it holds (its own and its halo band:
  // the halo exchange, or every floe where the run reads every floe), so
  // its held floes and the writer's gather (writer_states()) are the
  // serial run's, bit for bit. step() is then collective.
  explicit Simulation(Scenario scenario, parallel::Communicator comm = {});
  ~Simulation();
  Simulation(Simulation&&) noexcept;

  // One step toward t_stop (never past it); returns its length. A t_stop
  // within 1e-12 max(1, t) of the clock is round-off: the clock lands on it
  // with no step, and 0 is returned.
  double step(double t_stop);

  // Restart (core/checkpoint.hpp): the run's state at the end of a step, as
  // data, and back. save() applies the sea's deferred kicks (as a record's
  // energies do; no bit of the run changes). restore() takes a checkpoint of
  // a run of this scenario's configuration (the floes at t = 0 built the
  // same law and sea) and puts the simulation where the checkpoint was:
  // stepping on gives the steps the saved run took, to the bit. Throws
  // InputError if the checkpoint does not fit this run (sea, sizes).
  Checkpoint save();
  void restore(const Checkpoint& checkpoint);
  // save() with the writer's states already gathered at this state
  // (writer_states(), a record's): no second gather. Collective alike.
  Checkpoint save(std::vector<FloeState> writer_states);

  // The floes' states the writer writes at a record and a checkpoint
  // (collective): on the writer rank, every floe's state from the rank that
  // holds it (the drift's owners by place; parallel/writer_gather.hpp),
  // not from the writer's own arrays; empty on the other ranks. Serial: the
  // states. One call, rank 0 receiving 96 B a floe it does not own.
  std::vector<FloeState> writer_states() const;
  // Test option (not a user key): `poison`: each rank's copy of the floes
  // it does not hold is set to NaN before writer_states() gathers, so a
  // record or a checkpoint is right only if the gather reads every floe
  // from its holder; `poison_unread`: the same and the writer keeps its own
  // poisoned copy (the gather's messages are sent but not read: the
  // mutation that shows the poison reaches the file).
  enum class WriterTest { off, poison, poison_unread };
  void set_writer_test(WriterTest mode) { writer_test_ = mode; }
  // Test option (not a user key): the poison mode of the run
  // (coupling/poison_mode.hpp): on several ranks, each rank poisons its
  // copies of the floes it does not hold where the halo exchange will be,
  // and reports the first NaN it finds in a held floe after each phase.
  // Nothing changes on one rank. Its reports (also said on stderr):
  void set_poison_test(PoisonOptions options);
  // Test option (not a user key): on several ranks, a step-start share that
  // used the warm store falls back to the whole solve
  // (parallel::CollideShareOptions::warm_conflict), so that tests reach it.
  void set_collide_test(bool warm_conflict) { collide_warm_conflict_ = warm_conflict; }
  std::vector<std::string> poison_reports() const;
  std::string poison_summary() const;  // windows, floes poisoned, phases reported (empty when off)

  double time() const { return t_; }
  std::size_t steps() const { return steps_; }
  const Floes& floes() const { return scenario_.floes; }
  const Scenario& scenario() const { return scenario_; }
  const parallel::Communicator& communicator() const { return comm_; }
  const Profile& profile() const { return profile_; }
  Profile& profile() { return profile_; }
  Energies energies() const;

  const contact::CollisionStats& collision_stats() const { return stats_; }
  // Momentum given to the dynamic floes since t = 0 (kg m/s): by the smooth
  // forces (drag, wind, Coriolis) and by collisions. Between dynamic floes
  // impulses cancel, so the collision part is what obstacles gave.
  struct MomentumBudget {
    Vec2 external = Vec2::Zero();
    Vec2 collisions = Vec2::Zero();
  };
  const MomentumBudget& momentum_budget() const { return budget_; }
  // Of the dynamic floes now: each rank sums the floes it owns exactly and
  // the ranks combine (collective: every rank calls it). The same bits on
  // any number of ranks (docs/parallel.md, "Exact sums"); so are
  // energies() and the budget.
  Vec2 momentum() const;
  LcpCounters lcp_counters() const;
  // The contact detection at the present positions, whole. On several ranks
  // with [run] advance_on_part each rank holds only its part between steps,
  // and this gathers the parts (once until the next detection): collective
  // then, every rank must call it at the same point between the same steps.
  const contact::Detection& detection() { return whole_detection(); }
  // The floes' owners by place for the drift and detection (one rank: all 0).
  const parallel::FloeOwners& floe_owners() const { return owners_; }
  // The floes this rank holds (its own and its halo band, parallel::held_floes)
  // at the places and reaches of the last detection; one rank: every floe.
  const parallel::HeldFloes& held_floes() const { return held_; }
  // What the per-floe structures allocate on this rank, against the entries
  // of the floes it holds (core/floe_bytes.hpp; docs/parallel.md, "The
  // arrays held by band: measured (mem27)"): one entry a structure, named
  // as the run's summary prints it (memory.floes.NAME), and the held
  // floes' count (its own and its band, held_now(); one rank: every
  // floe). Not counted: the per-step scratch (the step-start copies, the
  // posed shapes), the per-cell arrays (the sea's), the contact store.
  struct FloeMemory {
    std::size_t floes = 0, held = 0;
    std::vector<std::pair<std::string, FloeBytes>> parts;
  };
  FloeMemory floe_memory() const;
  const contact::SubstepReport& substep_report() const { return substeps_; }
  // The drift's quadrature: serially every floe's; on several ranks the
  // points of the floes this rank holds only (hold_quadrature).
  const FootprintQuadrature& quadrature() const { return quadrature_; }
  // The collision shapes: on several ranks the parts of the floes this rank
  // holds only (hold_shapes), every floe's radius.
  const contact::CollisionShapes& shapes() const { return shapes_; }
  const parallel::AdvanceShareCounts& advance_share() const { return advance_share_; }  // stage seven
  const parallel::AdvanceShareCounts& collide_share() const { return collide_share_; }  // the step-start collisions
  long rejected_steps() const { return rejected_steps_; }
  // Things a user should hear about once, with a count (e.g. steps cut to the floor).
  std::vector<std::string> warnings() const;

  // Fracture initiations since the last call ([fracture] enabled), and counts.
  std::vector<FractureEventRow> take_fracture_events();
  // The collisions since the last call ([run] record_collisions; rows of
  // /events/collisions). On several ranks the writer's (rank 0) only; the
  // other ranks get none.
  std::vector<CollisionEventRow> take_collision_events() { return std::exchange(collision_events_, {}); }
  const PercussionStats* percussion_stats() const { return percussion_ ? &percussion_->stats() : nullptr; }
  // The fracture analyses by owner on several ranks, per rank (empty when serial).
  const PercussionRanks& percussion_ranks() const { return percussion_ranks_; }
  // The gathers of every floe's state from the owners on several ranks
  // (whole_state: a split, the pair list's rebuild, a fallback, a redone
  // try's footprints) and the bytes this rank received in them (the
  // summary's parallel.whole_state_gathers).
  struct WholeStateCounts {
    long gathers = 0;
    long long bytes = 0;
  };
  const WholeStateCounts& whole_state_counts() const { return whole_state_counts_; }

  // The sea surface, if the run has one ([sea] model != "none").
  bool has_sea() const { return sea_ != nullptr; }
  SeaGridInfo sea_grid() const;
  // On the grid, x fastest; empty without a sea. A sea in slabs gathers it
  // to the writer (rank 0) alone and the other ranks get an empty span;
  // every rank calls it (collective).
  std::span<const double> sea_elevation();
  // The floe–sea contact, if the run has a sea and floes that move.
  const FloeSeaContact* floe_sea() const { return floe_sea_.get(); }
  // The same, for the contact's operations a caller drives between steps
  // (FloeSeaContact::cell_product: tests/parallel/product_routes_ranks.cpp).
  FloeSeaContact* floe_sea() { return floe_sea_.get(); }
  std::vector<std::string> notes() const;  // said once at the start (e.g. calibrated blend)

private:
  StepContext choose_dt(double t_stop);
  // The step-start copies into ctx.start, in the array of the last step
  // (start_copies_): every floe's serially, before the first detection,
  // while every copy is current (state_whole_) and without the halo
  // exchange (whose ranks read every floe); else the held floes'
  // (held_now()), the only ones a rank reads. restore_start() puts them
  // back at a rejected try.
  void copy_start(StepContext& ctx);
  void restore_start(const StepContext& ctx);
  std::vector<FloeState> start_copies_;  // ctx.start between steps: its allocation kept
  void sample_forcing(StepContext& ctx) const;
  void sea_flow(const StepContext& ctx);
  void floes_half_kick(StepContext& ctx);
  // The drift's owners by place to the coupling for its next evaluation
  // (FloeSeaContact::take_place_owners), when they follow the sea's slabs.
  void offer_place_owners();
  void sea_half_kick(StepContext& ctx);
  void drift(StepContext& ctx);
  void follow_slabs();  // the sea and the coupling take the owners' moved slabs
  // The owners' slabs moved at a drift and the sea and the coupling have
  // not followed yet: they follow in sea_flow, after the sea's first kick
  // (follow_slabs' comment says why).
  bool slabs_to_follow_ = false;
  void collide(StepContext& ctx);
  void note_collisions();
  void percussion(StepContext& ctx);
  void on_floes_changed();  // rebuilds every per-floe structure (after a split)
  void advance(StepContext& ctx);
  bool detect_and_check(StepContext& ctx);  // false: the step overlapped, dt halved
  // The owners by place afresh (the start, a restore): the strips by equal
  // counts, or the sea's slabs.
  void start_owners();
  // The floes a restore keeps (1) from the checkpoint every rank reads
  // whole: those this rank holds at the restored places (every floe until
  // the arrays are held by band, piece 9).
  std::vector<std::uint8_t> kept_on_restore() const;
  // The detection at the present places outside a step (the start, a
  // restore, after a split): by place, this rank's part (collective).
  void detect_in_place();
  // The floes this rank holds at the present places (owners assigned, its
  // own floes' reaches set): announced by their owners with their reaches,
  // which it writes (parallel::announce_held). Collective on several ranks;
  // one rank holds every floe.
  // At a detection whose owners come from the own floes: `leaving`, this
  // rank's notices of its floes that left its strip, and every rank's count
  // of them, which the owners take there (announce_held).
  // With the halo exchange (`halo`: halo_part()), the part (b) rides on it.
  parallel::HeldFloes hold_band(std::span<const parallel::LeaveNotice> leaving = {},
                                std::span<const long long> leaving_counts = {}, parallel::HaloPart* halo = nullptr);
  // The state held by owner with a halo (docs/parallel.md, "The halo
  // exchange (halo26)", "... on the seas not in slabs (halo27)"): on
  // several ranks, with the advance from the parts, with or without a sea,
  // the explicit kicks or the implicit step ("... for the implicit step
  // (implicit28)"; the advance from the whole detection reads every floe
  // at every step: the drift sends every state to every rank there). The
  // same on every rank, for the whole run.
  bool halo_exchange() const;
  // The halo exchange's part (a), after the drift: each floe this rank owns
  // to the ranks that hold it (held_now() on each: those its owner at the
  // last detection announced it to, its coupling's owners; a floe whose
  // owner changed since, to every rank), one all-to-all.
  void send_to_holders();
  // Part (b) at a detection: the HaloPart for announce_held (none without
  // the exchange but in the poison mode), with `last` the announced sets of the last detection
  // (null: none known, every entering state sent) and `start` the
  // step-start copies (null outside a step: no floe leaves its strip
  // there). The detection keeps its announced sets (announced_) if kept.
  std::optional<parallel::HaloPart> halo_part(const parallel::Announced* last, std::vector<FloeState>* start);
  // The floes whose states arrived there are their owners' copies, which
  // the owners wrapped: noted as wrapped (wrap_entering leaves them).
  void note_arrived(const std::optional<parallel::HaloPart>& halo);
  // The ranks this rank announced its floes to at the last detection kept
  // (the floes it owned then; empty before the first, or without the exchange).
  parallel::Announced announced_;
  // From a rejected try to the redone try's drift: the owners are those of
  // the try's places, not of the places the floes are back at.
  bool owners_off_places_ = false;
  // Wraps the centroids of the floes this rank holds (held_now()) into a
  // periodic box, and notes which (wrapped_).
  void wrap_periodic();
  void wrap_floe(FloeState& s) const;
  // At a detection: wraps those of `floes` (the rank's own, then its held
  // set) that the last wrap_periodic left unwrapped here.
  void wrap_entering(std::span<const std::uint32_t> floes);
  // On several ranks, in a step whose cuts moved: each floe whose owner
  // changed goes from `detected` (the last detection's owners) to its new
  // owner (its state, step-start copy and reach; one all-to-all).
  void hand_over_moved(StepContext& ctx, std::span<const int> detected);
  // Per floe, 1 if this rank holds it now: held_'s mask, its own floes
  // (owners_.mine()) and its own floes for the coupling. Empty: every floe
  // (one rank, no detection yet). With the implicit step every rank holds
  // every floe's vertical DOFs besides (not marked).
  std::vector<std::uint8_t> held_now() const;
  // Whether held_now() marks a part (not empty), without building the mask.
  bool holds_part() const;
  // The floes this rank kicks with the sea's loads (FloeSeaContact::
  // kick_floes): with the halo exchange the floes it holds (held_now()),
  // whose rates its collisions (the step-start copy) and its law (the
  // explicit damper) read before the next drift's exchange; else every
  // floe (empty), each rank reading every floe.
  std::vector<std::uint8_t> kicked_floes() const;
  // The drift's quadrature held by band (docs/parallel.md, "The arrays held
  // by band: measured (mem27)"): on several ranks, at each detection that
  // sets held_, the points of the floes this rank holds (held_now()) and
  // none of the others' (FootprintQuadrature::hold). Only the drift reads
  // them, each rank its own floes', which it holds (a floe come to it
  // since: ensure() at the drift). Serially nothing (every floe's, built).
  void hold_quadrature();
  // The collision shapes held by band (docs/parallel.md, "The collision
  // shapes held by band (shapes28)"; contact/shapes.hpp): on several ranks
  // with the advance on each rank's part, at each detection that sets
  // held_, the parts of the floes this rank holds (held_now()) and none
  // of the others' (CollisionShapes::hold); the detection's entering floes'
  // built before it poses them, the floes come by a move of the cuts at
  // the drift, routed floes' with their pairs, every floe's on the whole
  // paths (parallel::advance_on_part). Else every floe's: serially, and
  // with the advance from the whole detection, whose share set-up and
  // fallback read every pair's floes on every rank.
  bool shapes_held_by_band() const;
  void build_shapes();  // every floe's, or (held by band) the radii alone
  void hold_shapes();
  // The poison mode's hook after the phase `phase` (poison_mode.cpp): opens,
  // checks and closes its windows; nothing when the mode is off.
  void probe(const char* phase, StepContext& ctx) {
    if (poison_) poison_step(phase, ctx);
  }
  void poison_step(const char* phase, StepContext& ctx);
  // Detection reach of this rank's own floes for the next step (owners
  // assigned at the present places; one rank: every floe). Collective: the
  // pack's rms speed is summed by owner; `along` (exact sums of this rank's
  // part) are combined over the ranks in the same call.
  // `counts` (integers of this rank's part) are summed over the ranks in
  // the same call.
  void set_reach(std::span<ExactSum> along = {}, std::span<long long> counts = {});
  void read_try_budget(const StepContext& ctx);  // the try's momenta, combined, into step_budget_
  // The state check (the ranks agree on the first non-finite value) and the
  // step's momentum budget (the sea kick's momenta combined): one call.
  void close_step(StepContext& ctx);
  // The floes whose terms this rank adds to the whole-pack sums: its floes
  // by place, or (before they are placed, after a split) its share by index.
  template <class F>
  void for_owned(F&& f) const;
  // Adds this rank's part of the dynamic floes' momentum to `into` (x, y).
  void add_owned_momentum(std::span<ExactSum, 2> into) const;

  Scenario scenario_;
  parallel::Communicator comm_;
  std::unique_ptr<fluid::Sea> sea_;
  std::unique_ptr<FloeSeaContact> floe_sea_;
  // The incident waves (coupling/incident.hpp), for drag; none on a calm sea
  // without wave generation (its velocity is 0).
  std::unique_ptr<IncidentSea> incident_;
  double equal_dt_ = -1.0;            // the last of the equal steps the penalty limit asked for
  DriftParams drift_params_;
  FootprintQuadrature quadrature_;
  Moorings moorings_;  // [[floes.floe]] mooring_period
  contact::CollisionShapes shapes_;
  contact::DetectionOptions detection_options_;
  parallel::FloeOwners owners_;  // drift and detection by place (stage six)
  parallel::HeldFloes held_;     // own floes and band at the last detection (held_floes())
  // Between the advance's wrap_periodic and the next drift's exchange: per
  // floe, 1 if this rank's copy was wrapped (there or by wrap_entering
  // since); empty after wrap_periodic: every floe was. Cleared when every
  // copy is as given or its owner's (start_owners, the drift's exchange).
  std::vector<std::uint8_t> wrapped_;
  contact::ImpulseOptions impulse_options_;
  std::unique_ptr<contact::WarmStart> warm_ = std::make_unique<contact::WarmStart>();  // jam LCPs' last bases
  contact::Detection detection_;  // at the present positions
  // On several ranks, this rank's part of detection_ (the pairs it
  // detected, parallel::detect; at the start and after a split too).
  std::optional<contact::Detection> detection_part_;
  // The floes this rank owned at that detection: their reaches are the
  // ones it sends when the whole detection is gathered (its others are its
  // band's or not written).
  std::vector<std::uint32_t> detection_own_;
  // Whether detection_ holds the whole detection. On several ranks with the
  // advance from the parts, detect_and_check gathers it only when a step
  // needs it (whole_detection(): a fallback, a step the back-off does whole,
  // detection()), every rank alike.
  bool detection_whole_ = true;
  const contact::Detection& whole_detection();
  // Whether every floe's state and step-start copy (ctx.start) are current
  // on this rank, every rank alike. True where the drift sends every
  // state to every rank (halo_exchange() false); with the halo exchange
  // false from the drift on (only the held floes are current: held_now()).
  // whole_state() makes them current when a step reads every
  // floe (the pair list's rebuild on a part, a fallback, a whole step of
  // the back-off: parallel::WholeOnDemand), once in such a step; or the
  // states alone (what the advance reads), which leave the flag false.
  bool state_whole_ = true;
  WholeStateCounts whole_state_counts_;
  void whole_state(StepContext& ctx, parallel::WholeState what);
  // Collective, in a step where a split may be made: `readers` (this
  // rank's Percussion::split_readers) sent to every rank with their states;
  // returns the floes whose states every rank now has alike (every rank's
  // readers), which Percussion::conclude may read. `held`: held_now().
  std::vector<std::uint8_t> split_states(std::span<const std::uint32_t> readers, std::span<const std::uint8_t> held);
  parallel::WholeOnDemand whole_on_demand(StepContext& ctx);
  contact::CollisionStats stats_;
  std::unique_ptr<Percussion> percussion_;  // [fracture] enabled
  PercussionRanks percussion_ranks_;         // its analyses by owner (several ranks)
  // The step's contact impulses for percussion and /events/collisions
  // (impulse_options_.record; null without fracture and record_collisions).
  std::unique_ptr<contact::ImpulseRecord> impulse_record_;
  bool record_collisions_ = false;
  std::vector<CollisionEventRow> collision_events_;  // since take_collision_events()
  MomentumBudget budget_, step_budget_;  // run total; this step's (redone steps do not count)
  contact::SubstepReport substeps_;  // collision sub-steps (floors, merges, ...)
  parallel::AdvanceShareCounts advance_share_;  // the advances by cluster owner (stage seven)
  parallel::AdvanceShareOptions advance_share_options_;  // their back-off, and whether from the rank's part
  parallel::AdvanceShareCounts collide_share_;  // the step-start collisions by owner (stage seven)
  long rejected_steps_ = 0;       // steps redone after an overlap
  WriterTest writer_test_ = WriterTest::off;  // set_writer_test
  std::unique_ptr<UnheldPoison> poison_;      // set_poison_test
  bool collide_warm_conflict_ = false;        // set_collide_test
  Profile profile_;
  double t_ = 0.0;
  std::size_t steps_ = 0;
};

// Times a phase into a profile, and counts the communicator's collective
// calls and received bytes in it: `PhaseTimer timer(profile, Phase::drift, comm);`.
class PhaseTimer {
public:
  PhaseTimer(Profile& p, Phase phase, const parallel::Communicator& comm)
      : p_(p), phase_(phase), comm_(comm), traffic_(comm.traffic()), start_(std::chrono::steady_clock::now()) {}
  ~PhaseTimer() {
    const auto k = static_cast<std::size_t>(phase_);
    p_.seconds[k] += std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
    const parallel::Communicator::Traffic now = comm_.traffic();
    p_.calls[k] += now.calls - traffic_.calls;
    p_.bytes[k] += now.bytes - traffic_.bytes;
  }
  PhaseTimer(const PhaseTimer&) = delete;
  PhaseTimer& operator=(const PhaseTimer&) = delete;

private:
  Profile& p_;
  Phase phase_;
  const parallel::Communicator& comm_;
  parallel::Communicator::Traffic traffic_;
  std::chrono::steady_clock::time_point start_;
};

}  // namespace floesim
