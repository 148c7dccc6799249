// Simulation: the collision phases of the step (docs/parallel.md, stage
// seven): the collisions at the step's start (collide), their rows
// (note_collisions), the advance with its sub-stepped collisions (advance),
// and the detection at the advanced places with its overlap check
// (detect_and_check, set_reach, read_try_budget). The step's other phases
// are in simulation.cpp.
#include <algorithm>
#include <cmath>
#include <optional>
#include <sstream>

#include "contact/substep.hpp"
#include "core/error.hpp"
#include "coupling/simulation.hpp"
#include "coupling/simulation_detail.hpp"
#include "parallel/advance_share.hpp"
#include "parallel/collide_share.hpp"
#include "parallel/detect.hpp"
#include "parallel/held.hpp"

namespace floesim {

using simulation_detail::kFloorFraction;

namespace {
// A step that overlaps is halved at most this many times before the run fails.
constexpr int kMaxHalvings = 40;
}  // namespace

void Simulation::collide(StepContext& ctx) {
  // Contacts were found at the positions of the start of the step; the LCPs
  // turn W(t-) into W(t+). Contacts the step itself pushed together rest
  // (restitution 0), and pushed points that would close below xi/2 within the
  // step are held by speculative contacts (contact/impulse.hpp).
  if (impulse_options_.record) impulse_options_.record->clear();  // this try's impulses (a redone step starts again)
  // On several ranks each rank solves the step groups it owns and the ranks
  // exchange the velocities they changed and the impulses they recorded,
  // which every rank merges into the serial record (stage seven,
  // parallel/collide_share.hpp).
  // From this rank's part of the detection and the pairs of its groups the
  // others send it ("The detection's lists by owner"; the record's places
  // are keyed by pair, so record runs too).
  if (comm_.serial())
    contact::resolve_step_collisions(scenario_.floes, ctx.start, detection_, ctx.dt, impulse_options_, stats_);
  else {  // every detection on several ranks leaves this rank's part (the start's and a split's too)
    const parallel::WholeOnDemand whole = whole_on_demand(ctx);
    parallel::CollideShareOptions share;
    share.warm_conflict = collide_warm_conflict_;
    parallel::collide_on_part(comm_, owners_.owner(), scenario_.floes, ctx.start, *detection_part_, ctx.dt,
                              impulse_options_, stats_, collide_share_, share, &whole);
  }
  add_owned_momentum(std::span(ctx.momenta).subspan<StepContext::kAfterCollide, 2>());
}

void Simulation::note_collisions() {
  // Before percussion: a split renumbers the floes the record refers to.
  // The rows are the writer's alone: the other ranks' merged record is the
  // same, and only the writer writes /events/collisions.
  if (!record_collisions_ || !comm_.writer()) return;
  const std::vector<CollisionEventRow> rows = collision_rows(scenario_.floes, *impulse_record_, t_);
  collision_events_.insert(collision_events_.end(), rows.begin(), rows.end());
}

void Simulation::advance(StepContext& ctx) {
  // Free floes move in one go; those that may collide within the step are
  // sub-stepped event by event, cluster by cluster (contact/substep.hpp). All
  // the momentum this changes is collisions'.
  contact::SubstepOptions o;
  o.collision_distance = detection_options_.collision_distance;
  o.floor = kFloorFraction * scenario_.config.run.dt_max;
  o.domain = detection_options_.domain;
  o.impulse = impulse_options_;
  // On several ranks each rank advances the clusters it owns and the ranks
  // exchange what moved and the impulses they recorded, which every rank
  // merges into the serial record, events in the serial queue's order
  // (stage seven, parallel/advance_share.hpp).
  if (comm_.serial())
    contact::advance_with_collisions(scenario_.floes, shapes_, detection_, ctx.dt, o, stats_, substeps_);
  else if (detection_part_ && advance_share_options_.on_part)
    parallel::advance_on_part(comm_, owners_.owner(), owners_.mine(), scenario_.floes, shapes_, *detection_part_,
                              whole_on_demand(ctx), ctx.dt, o, stats_, substeps_, advance_share_,
                              advance_share_options_);
  else
    parallel::advance_by_owner(comm_, owners_.owner(), scenario_.floes, shapes_, detection_, ctx.dt, o, stats_,
                               substeps_, advance_share_, advance_share_options_);
  add_owned_momentum(std::span(ctx.momenta).subspan<StepContext::kAfterAdvance, 2>());
  wrap_periodic();
}

void Simulation::set_reach(std::span<ExactSum> along, std::span<long long> counts) {
  // The pair list must hold every pair that can meet within the next step:
  // each floe's reach is what it may travel in dt_max at 1.5 times its
  // present speed (rotation included), plus half the pack's rms speed for
  // what collisions at the start of the step may give it. A floe that would
  // still outrun its reach makes the sub-stepper rebuild the list.
  // The rms is the same bits on any number of ranks: each rank sums the
  // squares of the floes it owns exactly, and counts them; one call
  // combines both (and `along`, `counts`). Each rank writes the reaches of
  // its own floes (at the detection, those it owned before the places
  // advanced: the floes that left its strip take theirs to their new
  // owners, hold_band); those of its band come from their owners
  // (hold_band), and the others are not written.
  const Floes& f = scenario_.floes;
  const double dt_max = scenario_.config.run.dt_max;
  FLOESIM_ASSERT(comm_.serial() || owners_.owner().size() == f.size());
  const auto speed = [&](std::size_t i) {
    const FloeState& s = f.state[i];
    return std::hypot(s.vx, s.vy) + std::abs(s.yaw_rate) * shapes_.radius[i];
  };
  std::vector<ExactSum> sums(1 + along.size());
  std::vector<long long> dynamic(1 + counts.size(), 0);
  for_owned([&](std::size_t i) {
    if (f.is_static[i]) return;
    const double v = speed(i);
    sums[0].add(v * v);
    ++dynamic[0];
  });
  std::copy(along.begin(), along.end(), sums.begin() + 1);
  std::copy(counts.begin(), counts.end(), dynamic.begin() + 1);
  comm_.sum(sums, dynamic);
  std::copy(sums.begin() + 1, sums.end(), along.begin());
  std::copy(dynamic.begin() + 1, dynamic.end(), counts.begin());
  const double rms = dynamic[0] ? std::sqrt(sums[0].value() / static_cast<double>(dynamic[0])) : 0.0;
  detection_options_.reach.resize(f.size());
  for_owned([&](std::size_t i) {
    detection_options_.reach[i] =
        f.is_static[i] ? 0.0 : dt_max * (1.5 * speed(i) + 0.5 * rms) + detection_options_.collision_distance;
  });
}

void Simulation::read_try_budget(const StepContext& ctx) {
  // The momenta of the try, combined over the ranks (set_reach): the smooth
  // forces' part is the drift phase's change (the first half kick's
  // included), the collisions' part the collide and advance phases'.
  const Vec2 start = ctx.momentum_at(StepContext::kAtStart), drifted = ctx.momentum_at(StepContext::kAfterDrift),
             collided = ctx.momentum_at(StepContext::kAfterCollide),
             advanced = ctx.momentum_at(StepContext::kAfterAdvance);
  step_budget_.external = drifted - start;
  step_budget_.collisions = collided - drifted;
  step_budget_.collisions += advanced - collided;
}

bool Simulation::detect_and_check(StepContext& ctx) {
  // The owners at the advanced places, from the owners' own floes: each
  // rank tests its floes against the cuts (the cuts do not move here) and
  // announces those that left its strip, with their places and reaches,
  // which it computes (set_reach, over the floes it owned until now: a
  // partition of the floes as good as the new one for the rms's exact
  // sum). Each rank's count of notices rides on set_reach's call and the
  // notices on the band's strips' gather (hold_band): no call added. The
  // whole assignment only when the owners are not assigned for these floes.
  std::vector<parallel::LeaveNotice> leaving;
  std::vector<long long> leaving_counts;  // per rank
  const bool by_own = !comm_.serial() && owners_.assigned_for(scenario_.floes);
  if (by_own) {
    leaving = owners_.leaving(comm_.rank(), scenario_.floes);
    leaving_counts.assign(static_cast<std::size_t>(comm_.size()), 0);
    leaving_counts[static_cast<std::size_t>(comm_.rank())] = static_cast<long long>(leaving.size());
  } else if (!comm_.serial()) {
    owners_.assign(scenario_.floes);
  }
  set_reach(std::span(ctx.momenta).first<StepContext::kTry>(), leaving_counts);  // combines the try's momenta too (one call)
  // The notices carry the reaches their senders computed: a floe that
  // comes to a rank takes its old owner's (the formula's bits).
  for (parallel::LeaveNotice& k : leaving) k.reach = detection_options_.reach[k.floe];
  read_try_budget(ctx);
  // The held floes at the advanced places, their reaches from their owners:
  // the detection's subset reads only those. Kept when the step is
  // accepted (a rejected try's places are undone).
  // The owners take the notices there (announce_held: they ride on the
  // strips' gather).
  // With the state held by owner the floes entering this rank's held set
  // (and those come to it) get their states here (the halo exchange's part
  // (b), on the same calls; kept only if the step is accepted).
  wrap_entering(owners_.mine());
  std::optional<parallel::HaloPart> halo = halo_part(&announced_, &ctx.start);
  parallel::HeldFloes held = hold_band(leaving, leaving_counts, halo ? &*halo : nullptr);
  note_arrived(halo);
  wrap_entering(held.index);
  contact::Detection part;  // this rank's (serially: `next` itself)
  // The whole lists are gathered only for the advance from the whole
  // detection; else whole_detection() gathers them when a step needs them
  // (record runs too: the record's places are keyed by pair, ContactPlace).
  const bool whole = !advance_share_options_.on_part;
  // The shapes of the floes the detection poses (held.index: the floes
  // entering the held set built; none dropped until the step is kept).
  if (shapes_held_by_band()) shapes_.ensure(scenario_.floes, held.index);
  contact::Detection next = parallel::detect(comm_, owners_, scenario_.floes, shapes_, detection_options_,
                                             comm_.serial() ? nullptr : &part, whole, &held);
  // The first overlapping pair and its distance at t, found from the ranks'
  // parts (a reduction): the serial scan's on every rank.
  const parallel::Overlap overlap = parallel::first_overlap(comm_, comm_.serial() ? next : part,
                                                            detection_part_ ? *detection_part_ : detection_);
  if (overlap.any) {
    // Redo the step with half the time.
    ++rejected_steps_;
    restore_start(ctx);
    owners_off_places_ = !comm_.serial();  // the owners took the try's notices
    ctx.dt *= 0.5;
    if (ctx.dt < kFloorFraction * scenario_.config.run.dt_max * std::pow(0.5, kMaxHalvings / 2)) {
      std::ostringstream m;
      m << "floes " << overlap.a << " and " << overlap.b << " overlap however short the step from t = " << ctx.t
        << " s (their distance at t was " << overlap.before << " m)";
      throw RunError(m.str());
    }
    return false;
  }
  detection_ = std::move(next);
  held_ = std::move(held);
  hold_quadrature();
  hold_shapes();
  // The copies of the floes this rank does not hold (held_now()) are stale
  // from here on, whatever the
  // drift's exchange (the vertical drift that follows is over the held
  // floes; with the state held by owner they were since the drift unless
  // gathered): a split gathers the states it reads (split_states).
  if (halo) announced_ = std::move(halo->announced);
  if (holds_part()) state_whole_ = false;
  detection_whole_ = comm_.serial() || whole;
  if (!comm_.serial()) {
    detection_part_ = std::move(part);
    detection_own_ = owners_.mine();
  }
  return true;
}

}  // namespace floesim
