#include "coupling/simulation.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <sstream>
#include <thread>

#include "contact/substep.hpp"
#include "core/error.hpp"
#include "coupling/simulation_detail.hpp"
#include "fluid/sea.hpp"
#include "parallel/advance_share.hpp"
#include "parallel/detect.hpp"
#include "parallel/held.hpp"
#include "parallel/sea_ranks.hpp"

namespace floesim {

namespace {
// A stop closer to the clock than this (relative to max(1, t)) is round-off,
// not a step (Simulation::step).
constexpr double kSliver = 1e-12;

// [run] threads = 0: OMP_NUM_THREADS when it is set (so that a test runner
// with several processes can ask for one thread each), else one per core.
int resolve_threads(int requested) {
  if (requested > 0) return requested;
  if (const char* env = std::getenv("OMP_NUM_THREADS")) {
    const int n = std::atoi(env);
    if (n > 0) return n;
  }
  return static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
}

contact::Domain make_domain(const Scenario& s) {
  contact::Domain d;
  const ContactParams& c = s.config.contact;
  if (!c.periodic) return d;
  std::array<double, 4> box = c.box;
  if (!(box[1] > box[0]) && s.window) box = *s.window;
  if (!(box[1] > box[0] && box[3] > box[2]))
    throw InputError(where(s.config.file, 0, "[contact] box",
                           "a periodic domain needs a box = [xmin, xmax, ymin, ymax] (or a pack with a window)"));
  d.periodic = true;
  d.xmin = box[0]; d.xmax = box[1]; d.ymin = box[2]; d.ymax = box[3];
  // Every floe starts in the box, and is narrower than it (a floe as wide as
  // the period would touch its own image across the seam).
  const Floes& f = s.floes;
  for (std::size_t i = 0; i < f.size(); ++i) {
    Vec2 lo = Vec2::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
    for (const Vec2& b : f.vertices(i)) {
      lo = lo.cwiseMin(f.to_world(i, b));
      hi = hi.cwiseMax(f.to_world(i, b));
    }
    std::ostringstream m;
    const double x = f.state[i].x, y = f.state[i].y;
    if (!(x >= d.xmin && x <= d.xmax && y >= d.ymin && y <= d.ymax))
      m << "floe " << i << ": centroid (" << x << ", " << y << ") m is outside the periodic box [" << d.xmin << ", "
        << d.xmax << "] x [" << d.ymin << ", " << d.ymax << "] m";
    else if (!f.is_static[i] && (hi.x() - lo.x() >= d.width() || hi.y() - lo.y() >= d.height()))
      m << "floe " << i << ": " << hi.x() - lo.x() << " m x " << hi.y() - lo.y()
        << " m, not smaller than the periodic box of " << d.width() << " m x " << d.height()
        << " m (it would touch its own image across the seam)";
    else
      continue;
    throw InputError(where(s.config.file, 0, "[contact] box", m.str() + " (floes are numbered from 0: pack floes first, then inline ones)"));
  }
  return d;
}
}  // namespace

Simulation::Simulation(Scenario scenario, parallel::Communicator comm)
    : scenario_(std::move(scenario)), comm_(std::move(comm)) {
  const Config& c = scenario_.config;
  drift_params_ = DriftParams{c.sea.rho, c.forcing.ocean_drag, c.forcing.air_density, c.forcing.air_drag,
                              c.forcing.coriolis};
  // Serially every floe's drift quadrature; on several ranks none until the
  // start's detection, which holds the rank's floes' (hold_quadrature).
  if (comm_.serial()) quadrature_ = build_footprint_quadrature(scenario_.floes);
  moorings_ = Moorings(scenario_.floes, c.floes.floes);  // anchored where the floes start (also on a restart)
  detection_options_.collision_distance = c.contact.collision_distance;
  detection_options_.domain = make_domain(scenario_);
  detection_options_.horizon = c.run.dt_max;
  impulse_options_.restitution = c.contact.restitution;
  impulse_options_.friction = c.contact.friction;
  impulse_options_.rest_speed = c.contact.rest_speed;
  impulse_options_.min_gap = 0.1 * c.contact.collision_distance;
  impulse_options_.relaxation_time = c.run.dt_max;
  impulse_options_.collision_distance = c.contact.collision_distance;
  impulse_options_.warm = warm_.get();
  impulse_options_.dump_failed_lcps = c.contact.dump_failed_lcps;
  advance_share_options_.on_part = c.run.advance_on_part;
  build_shapes();  // serially every floe's; held by band: the radii (the parts at the start's detection)
  wrap_periodic();
  fluid::SeaOptions sea_options;
  sea_options.tank = {c.sea.tank.enabled, c.sea.tank.generation_length, c.sea.tank.absorption_length,
                      c.sea.tank.rate, c.sea.tank.ramp_periods};
  sea_options.threads = resolve_threads(c.run.threads);
  // On several ranks the spectral sea runs in slabs (docs/parallel.md, stage
  // four; with the implicit step too since slabs30: its solve by owner); a
  // tank keeps it whole on every rank. The incident waves' sea (below) runs
  // in slabs alike (each rank holds its modes, and its fields' and
  // snapshots' slab and halo rows: the row window).
  if (!comm_.serial() && c.sea.model == SeaModel::spectral && c.sea.dims == 2 && !c.sea.tank.enabled) {
    sea_options.ranks = parallel::sea_ranks(comm_);
  }
  const fluid::SeaOptions incident_options = sea_options;
  try {
    sea_ = fluid::make_sea(c.sea, c.run.seed, sea_options);  // its input errors name the [sea] key; add the file
  } catch (const InputError& e) {
    throw InputError(c.file.empty() ? std::string(e.what()) : c.file + ": " + e.what());
  }
  const Floes& f = scenario_.floes;
  const bool any_dynamic = std::any_of(f.is_static.begin(), f.is_static.end(), [](std::uint8_t s) { return !s; });
  if (sea_ && any_dynamic) {
    floe_sea_ = std::make_unique<FloeSeaContact>(c.coupling, c.sea, scenario_.floes, *sea_, c.run.dt_max);
    floe_sea_->set_threads(resolve_threads(c.run.threads));
    floe_sea_->set_communicator(comm_);
    if (c.sea.waves.kind != WaveKind::none || c.sea.tank.enabled)
      incident_ = std::make_unique<IncidentSea>(fluid::make_sea(c.sea, c.run.seed, incident_options),
                                                IncidentSea::interval_for(c.sea));
    floe_sea_->start(scenario_.floes, *sea_, c.coupling.start_given);
    floe_sea_->ready_loads(scenario_.floes, *sea_, incident_.get(), 0.5 * c.run.dt_max);
  }
  start_owners();
  // The start's detection, by place as each step's (the strips known). The
  // first overlapping pair in pair order, found from the parts (the serial
  // scan's), is the error on every rank.
  detect_in_place();
  const parallel::Overlap overlap = parallel::first_overlap(comm_, comm_.serial() ? detection_ : *detection_part_,
                                                            comm_.serial() ? detection_ : *detection_part_);
  if (overlap.any)
    throw InputError(where(c.file, 0, "", "floes " + std::to_string(overlap.a) + " and " + std::to_string(overlap.b) +
                                              " overlap at t = 0 (floes are numbered from 0: pack floes first, then inline ones)"));
  // Pieces of a split are opened by the gap that collisions keep between floes.
  if (c.fracture.enabled) percussion_ = std::make_unique<Percussion>(c.fracture, impulse_options_.min_gap);
  record_collisions_ = c.run.record_collisions;
  if (percussion_ || record_collisions_) {
    impulse_record_ = std::make_unique<contact::ImpulseRecord>();
    impulse_options_.record = impulse_record_.get();
  }
}

Simulation::~Simulation() = default;
Simulation::Simulation(Simulation&&) noexcept = default;

double Simulation::step(double t_stop) {
  // A stop within round-off of the clock (1e-15 s ahead, as k dt and a
  // record time computed another way can be) is reached without a step: a
  // step that short would divide the contact targets by it (speculative
  // gaps and the floes' turning over the step, contact/impulse.hpp) and
  // throw the floes apart. The clock lands on t_stop, as it does at the end
  // of every step cut to reach one.
  if (t_stop > t_ && t_stop - t_ <= kSliver * std::max(1.0, std::abs(t_))) {
    t_ = t_stop;
    return 0.0;
  }
  // probe(): the poison mode's hooks between phases (a test option, off in a
  // run: set_poison_test, coupling/poison_mode.hpp).
  StepContext ctx;
  { PhaseTimer _(profile_, Phase::choose_dt, comm_); ctx = choose_dt(t_stop); }  probe("choose_dt", ctx);
  for (bool accepted = false; !accepted;) {
    { PhaseTimer _(profile_, Phase::forcing, comm_); sample_forcing(ctx); }       probe("forcing", ctx);
    { PhaseTimer _(profile_, Phase::penalty, comm_); floes_half_kick(ctx); }      probe("first half kick", ctx);
    { PhaseTimer _(profile_, Phase::drift, comm_);   drift(ctx); }                probe("drift", ctx);
    { PhaseTimer _(profile_, Phase::collide, comm_); collide(ctx); }              probe("collide", ctx);
    { PhaseTimer _(profile_, Phase::advance, comm_); advance(ctx); }              probe("advance", ctx);
    { PhaseTimer _(profile_, Phase::detect, comm_);  accepted = detect_and_check(ctx); }
  }
  probe("detect", ctx);
  { PhaseTimer _(profile_, Phase::sea, comm_);       sea_flow(ctx); }             probe("sea", ctx);
  { PhaseTimer _(profile_, Phase::penalty, comm_);   sea_half_kick(ctx); }        probe("second half kick", ctx);
  // Land exactly on t_stop when the step was cut to reach it.
  t_ = ctx.dt == t_stop - ctx.t ? t_stop : ctx.t + ctx.dt;
  { PhaseTimer _(profile_, Phase::record, comm_);     note_collisions(); }       probe("record", ctx);
  { PhaseTimer _(profile_, Phase::percussion, comm_); percussion(ctx); }         probe("percussion", ctx);
  { PhaseTimer _(profile_, Phase::check, comm_);      close_step(ctx); }         probe("check", ctx);
  ++steps_;
  start_copies_ = std::move(ctx.start);  // the next step's copies go into this array
  warm_->tick();  // the jam LCPs' warm starts age by one step
  return ctx.dt;
}

StepContext Simulation::choose_dt(double t_stop) {
  StepContext ctx;
  ctx.t = t_;
  const double remaining = t_stop - t_;
  const double dt_max = scenario_.config.run.dt_max;
  // Land on t_stop without leaving a sliver of a step before it: take the rest
  // when it is within round-off of dt_max, split it in two when it is short of
  // 1.5 dt_max.
  if (remaining <= dt_max * (1.0 + 1e-9)) ctx.dt = remaining;
  else if (remaining < 1.5 * dt_max) ctx.dt = 0.5 * remaining;
  else ctx.dt = dt_max;
  if (!(ctx.dt > 0.0)) throw RunError("step requested with no time left (t = " + std::to_string(t_) + ")");
  // The explicit penalty spring's stability limit (coupling/floe_sea.hpp).
  if (floe_sea_ && floe_sea_->stable_step() < ctx.dt) {
    if (std::isfinite(remaining)) {
      const double n = std::ceil(remaining / floe_sea_->stable_step());
      // Equal steps up to t_stop; the last equal step is kept while it
      // divides what remains to round-off (the sea's rotations, cached for
      // one dt, stay valid), and the last step of all lands on t_stop.
      const bool same = n > 1.0 && equal_dt_ > 0.0 && std::abs(remaining / equal_dt_ - n) < 1e-9 * n;
      equal_dt_ = same ? equal_dt_ : remaining / n;
      ctx.dt = std::min(ctx.dt, equal_dt_);
    } else {
      ctx.dt = floe_sea_->stable_step();  // no stop in sight (step(inf))
    }
  }
  // Collisions do not shorten the step: the floes that may meet within it are
  // sub-stepped by advance() (contact/substep.hpp); with fracture on, every
  // solve of the step hands its impulses to the percussion phase
  // (impulse_record_), whatever sub-step it fell in.
  copy_start(ctx);
  return ctx;
}

void Simulation::sample_forcing(StepContext& ctx) const {
  // Forcing is held over the step at its value at mid-step (second-order
  // accurate for a smooth series).
  ctx.forcing = scenario_.forcing.at(ctx.t + 0.5 * ctx.dt);
}

void Simulation::floes_half_kick(StepContext& ctx) {
  // The sea's loads at t (evaluated at the end of the previous step when
  // its half step was the same) kick the floes' vertical and horizontal rates.
  ctx.momenta = {};
  add_owned_momentum(std::span(ctx.momenta).subspan<StepContext::kAtStart, 2>());
  if (!floe_sea_) return;
  // The loads are evaluated here when they went stale (a split, a restore,
  // the explicit damper): a rebuild of the footprints then takes the drift's
  // owners (assigned at the last detection, at the present places: the sea's
  // flow and the kicks move no floe) and poses this rank's floes only, as in
  // sea_half_kick. After a rejected try the owners are those of its places,
  // not of the step's start the floes are back at: a rebuild then poses
  // every floe, so every floe's state comes from its owner first (rare).
  if (owners_off_places_) whole_state(ctx, parallel::WholeState::state);
  else offer_place_owners();
  // Each rank kicks the floes it holds (kicked_floes); a rejected try's
  // drift gave its owners floes since the loads travelled.
  const std::vector<std::uint8_t> kicked = kicked_floes();
  floe_sea_->ready_loads(scenario_.floes, *sea_, incident_.get(), 0.5 * ctx.dt, kicked, owners_off_places_);
  // The offer holds for this evaluation only: the drift's update moves the
  // owners and may reallocate their arrays. Withdrawn here (an evaluation
  // has cleared it already), so that a try redone after an overlap finds
  // no offer, rather than spans into the rejected try's arrays, and its
  // rebuild poses every floe.
  floe_sea_->take_place_owners({}, {}, {});
  floe_sea_->kick_floes(scenario_.floes, 0.5 * ctx.dt, kicked);
}

void Simulation::offer_place_owners() {
  if (!comm_.serial() && owners_.has_slabs() && owners_.owner().size() == scenario_.floes.size())
    floe_sea_->take_place_owners(owners_.owner(), owners_.mine(), owners_.slabs().first_row);
}

void Simulation::drift(StepContext& ctx) {
  const Vec2 current{ctx.forcing.current[0], ctx.forcing.current[1]};
  const Vec2 wind{ctx.forcing.wind[0], ctx.forcing.wind[1]};
  // Drag relative to the current plus the incident waves' orbital velocity
  // at t (on several ranks, of the floes this rank drifts: after the owners'
  // update below).
  std::vector<Vec2> water;
  const auto water_at = [&] {
    if (!floe_sea_) return;
    const std::span<const Vec2> orbital = floe_sea_->water_velocity();
    water.assign(orbital.begin(), orbital.end());
    for (Vec2& w : water) w += current;
  };
  if (comm_.serial()) {
    moorings_.kick(scenario_.floes, ctx.dt);
    water_at();
    drift_velocities(scenario_.floes, quadrature_, drift_params_, current, wind, ctx.dt, 0, scenario_.floes.size(),
                     water);
  } else {
    // Each rank drifts the floes in its strip (each floe's drift is its own),
    // charged to the load balance, then every rank takes the others' floes.
    if (owners_.has_slabs()) owners_.charge_rows(sea_->take_row_seconds());  // the sea's row work, by place too
    // The coupling's per-floe work since the last step, done by the floes'
    // owners by place (they follow the slabs): by-place cost on the floes'
    // rows, like the drift's (FloeOwners::charge_coupling).
    if (owners_.has_slabs() && floe_sea_) owners_.charge_coupling(floe_sea_->take_owned_seconds());
    // Floes migrate; every few steps the strips move (with slabs, the sea's and the coupling's too).
    // A floe that migrates across a cut was in its new owner's band; a move
    // of the cuts can give a rank floes its band did not hold, which it
    // then drifts and advances: they come from their owners at the last
    // detection (hand_over_moved).
    std::vector<int> detected;  // the last detection's owners, when the cuts may move
    if (owners_.may_move(steps_)) detected.assign(owners_.owner().begin(), owners_.owner().end());
    const bool moved = owners_.update(comm_, scenario_.floes, steps_);
    owners_off_places_ = false;
    if (moved && owners_.has_slabs()) slabs_to_follow_ = true;  // after the sea's first kick (sea_flow)
    if (moved) hand_over_moved(ctx, detected);
    // The moorings of the floes this rank drifts: each kick is its floe's
    // own, and the other floes' states come whole from their owners below.
    moorings_.kick(scenario_.floes, ctx.dt, owners_.mine());
    // The coupling's owners computed the water velocities; the drift's read them.
    if (floe_sea_) floe_sea_->hand_water_over(owners_.owner());
    water_at();
    const double start = parallel::thread_seconds();
    // The floes come to this rank by a move of the cuts since the detection
    // (hand_over_moved), or taken by the owners at a rejected try's, need
    // not be in its held set there: their quadratures built here.
    quadrature_.ensure(scenario_.floes, owners_.mine());
    shapes_.ensure(scenario_.floes, owners_.mine());  // as the quadrature's (hold_shapes)
    drift_velocities(scenario_.floes, quadrature_, drift_params_, current, wind, ctx.dt, owners_.mine(), water);
    owners_.charge(parallel::thread_seconds() - start);
    // The drifted states to the ranks that read them: with the state held
    // by owner, to the ranks that hold each floe (the halo exchange, part
    // (a)); else to every rank.
    if (halo_exchange()) {
      send_to_holders();
      state_whole_ = false;
    } else {
      comm_.complete_owned(scenario_.floes.state, owners_.owner());
      state_whole_ = true;
    }
    wrapped_.clear();  // every copy a rank holds is now its owner's (wrap_entering: nothing left to wrap)
  }
  add_owned_momentum(std::span(ctx.momenta).subspan<StepContext::kAfterDrift, 2>());
}

void Simulation::follow_slabs() {
  // Every rank, at the same step (the cuts are computed from the same
  // gathered charges): the sea's row scratch and halo, the coupling's
  // routes and owners are remade for the new slabs.
  // Not at the drift that moved the cuts, but after the sea's first kick of
  // the step (sea_flow): that kick may carry a pressure evaluated at this
  // step's first half kick (the explicit damper's loads are evaluated there),
  // whose cells each rank summed on the routes of the slabs it was evaluated
  // on; the sea's kick reads the rows of its slab, and the coupling's
  // set_slabs clears the old routes' sums. Followed before that kick, a rank
  // kicks its new rows with the sums of its old ones (zeros where a row came
  // to it), and the sea leaves the serial run. Between the drift and that
  // kick nothing reads the sea's slabs or the coupling's routes: the
  // collisions, the advance and the detection go by the owners' strips,
  // which are the new ones already. The sea's pending kicks are spectra of
  // its columns, which a move of the rows keeps.
  slabs_to_follow_ = false;
  const std::vector<int>& first_row = owners_.slabs().first_row;
  sea_->set_slab_rows(first_row);
  if (floe_sea_) floe_sea_->set_slabs(first_row);
}

void Simulation::percussion(StepContext& ctx) {
  // The step is done (the floes at t_ = ctx.t + dt): its collisions' loads
  // are judged; pieces of a split start the next step.
  if (!percussion_) return;
  if (comm_.serial()) {
    if (percussion_->check(scenario_.floes, *impulse_record_, t_, ctx.dt)) on_floes_changed();
    return;
  }
  // On several ranks every rank holds the serial record (stage seven) and
  // analyses the loaded floes it owns (docs/parallel.md, "The fracture
  // checks by owner"), by-place work charged to the load balance like the
  // drift's; one exchange of the ranks' analyses, made by all ranks alike
  // when any floe was loaded (the same on all: the record and the floes
  // are), and every rank concludes on all of them in floe order: the serial
  // events and splits.
  const double start = parallel::thread_seconds();
  const std::vector<std::uint8_t> held = held_now();  // a split's neighbours: among the held floes
  const PercussionAnalyses mine = percussion_->analyse(scenario_.floes, *impulse_record_, t_, ctx.dt,
                                                       PercussionShare{owners_.owner(), comm_.rank(), held});
  owners_.charge_fracture(parallel::thread_seconds() - start);
  if (!mine.loaded) return;
  PercussionAnalyses all = combine(comm_.allgather_parts(pack(mine), unpack_percussion), percussion_ranks_);
  // Every rank applies every split, deciding it again from the parent's
  // neighbours where an earlier split came near, and the pieces take their
  // parent's state; then the pieces' owners from their places, the other
  // floes' from their owners (place_pieces, detect_in_place). With the
  // state held by owner a rank's copies of the floes it does not hold are
  // stale, so when a split may be made (an initiation through a floe whose
  // share decided a split: the same on every rank, Percussion::may_split)
  // the states conclude reads (each owner's split_readers: the parents and
  // their neighbours) come from their owners first: one gather, in such a
  // step only, and conclude reads those alone (and the pieces). With a
  // floe-sea coupling too: after the split the coupling's next rebuild is
  // built by the owners just placed, which hold their floes
  // (FloeSeaContact::floes_changed; docs/parallel.md, "The split step's
  // gather with a sea (splitsea29)").
  std::vector<std::uint8_t> readable;
  if (percussion_->may_split(all))
    readable = split_states(percussion_->split_readers(scenario_.floes, mine, held), held);
  // The pieces' owners from their states (every rank builds them alike),
  // the other floes' from their owners (detect_in_place).
  std::vector<std::uint32_t> split;
  if (percussion_->conclude(scenario_.floes, std::move(all), &split, readable)) {
    owners_.place_pieces(scenario_.floes, split);
    on_floes_changed();
    // The poison mode (a test) checks them against assign() over every
    // floe's place, each floe's state gathered from its owner for it (a
    // test's gather; not with the mutation `stale`, which gathers nothing).
    if (poison_ && !poison_->options().stale) {
      Floes places = scenario_.floes;
      comm_.complete_owned(places.state, owners_.owner());
      parallel::FloeOwners by_place = owners_;
      by_place.assign(places);
      if (!std::ranges::equal(by_place.owner(), owners_.owner()) || by_place.mine() != owners_.mine())
        throw RunError("poison: rank " + std::to_string(comm_.rank()) + ": the owners after the splits at t = " +
                       std::to_string(t_) + " are not assign()'s over every floe's place");
    }
  }
}

void Simulation::on_floes_changed() {
  // A split replaces its parent's vertices: every quadrature made again
  // (on several ranks the held floes' at the detection below).
  if (comm_.serial())
    quadrature_ = build_footprint_quadrature(scenario_.floes);
  else
    quadrature_.forget();
  build_shapes();
  // The reaches (new pieces included) are set and the pieces are placed (appended at the same indices with the same ids
  // on every rank: Percussion::conclude on the same initiations in floe
  // order) and the detection made by place, as after a step.
  detect_in_place();
  if (floe_sea_) {
    // A split piece keeps its parent's reference bottom (same thickness);
    // the loads are evaluated afresh for the new footprints, built by the
    // owners just placed (they hold their floes; the other copies may be
    // stale since the split gathered only what it reads).
    floe_sea_->floes_changed(scenario_.floes, comm_.serial() ? std::span<const int>{} : owners_.owner());
  }
}

std::vector<FractureEventRow> Simulation::take_fracture_events() {
  return percussion_ ? percussion_->take_events() : std::vector<FractureEventRow>{};
}

void Simulation::sea_flow(const StepContext& ctx) {
  // The floes' pressures at t (half kick), then the floes' vertical DOFs and
  // the sea over dt: their free flows (explicit kicks), or the implicit step
  // of the penalty spring (coupling/floe_sea.hpp).
  if (!sea_) return;
  if (!floe_sea_) {
    if (slabs_to_follow_) follow_slabs();
    return sea_->flow(ctx.dt);
  }
  floe_sea_->kick_sea(*sea_, 0.5 * ctx.dt);
  if (slabs_to_follow_) follow_slabs();  // the kick above took the pressure on the slabs it was summed on
  // The implicit step's midpoint footprints: a rebuild takes the drift's
  // owners by place, which hold their floes (as the half kick's evaluation).
  if (floe_sea_->implicit()) offer_place_owners();
  floe_sea_->advance_vertical(scenario_.floes, ctx.start, *sea_, ctx.dt, held_now());
}

void Simulation::sea_half_kick(StepContext& ctx) {
  // Loads at t + dt (and the incident waves' velocity under the floes, for
  // the next drag): the second half kick of the sea and of the floes, and,
  // while they hold, the first of the next step (FloeSeaContact's loads cache).
  if (!floe_sea_) return;
  // The drift's owners by place were assigned at the detection, at the
  // places the loads are evaluated at (the sea's flow moves no floe
  // across): a rebuild of the footprints takes them, and poses this rank's
  // floes only.
  offer_place_owners();
  const std::vector<std::uint8_t> kicked = kicked_floes();
  floe_sea_->evaluate_loads(scenario_.floes, *sea_, incident_.get(), 0.5 * ctx.dt, kicked);
  add_owned_momentum(std::span(ctx.momenta).subspan<StepContext::kBeforeSeaKick, 2>());
  floe_sea_->kick_floes(scenario_.floes, 0.5 * ctx.dt, kicked);
  floe_sea_->kick_sea(*sea_, 0.5 * ctx.dt);
  add_owned_momentum(std::span(ctx.momenta).subspan<StepContext::kAfterSeaKick, 2>());
}

void Simulation::close_step(StepContext& ctx) {
  // Each rank checks the floes it owns for non-finite values; one call sums
  // their number over the ranks, with the sea kick's momenta (when the
  // floes feel the sea). Only when there are bad floes does a second call
  // agree on the first (the lowest floe, then column: floe * columns +
  // column, the least over the ranks), so that every rank throws the same
  // message.
  const Floes& f = scenario_.floes;
  constexpr long long kNone = std::numeric_limits<long long>::max();
  long long first = kNone;
  std::array<long long, 1> bad{0};
  for_owned([&](std::size_t i) {
    const double* s = reinterpret_cast<const double*>(&f.state[i]);
    for (int k = 0; k < kStateColumns; ++k)
      if (!std::isfinite(s[k])) {
        first = std::min(first, static_cast<long long>(i) * kStateColumns + k);
        ++bad[0];
        break;
      }
  });
  const std::span<ExactSum> kick =
      floe_sea_ ? std::span(ctx.momenta).subspan(StepContext::kBeforeSeaKick, 4) : std::span<ExactSum>{};
  comm_.sum(kick, bad);
  if (bad[0] > 0) {
    first = comm_.min(first);
    std::ostringstream m;
    m << "floe " << first / kStateColumns << ": " << kStateColumnNames[first % kStateColumns]
      << " is not finite after the step from t = " << ctx.t << " s with dt = " << ctx.dt << " s";
    throw RunError(m.str());
  }
  if (floe_sea_)
    step_budget_.external +=
        ctx.momentum_at(StepContext::kAfterSeaKick) - ctx.momentum_at(StepContext::kBeforeSeaKick);
  budget_.external += step_budget_.external;
  budget_.collisions += step_budget_.collisions;
}

}  // namespace floesim
