#pragma once
// Stage seven (docs/parallel.md, "The collisions at the step's start: by
// cluster owner"): the collision LCPs at a step's start by owner. Every rank
// finds the step groups from the replicated detection and states (contact::
// resolve_step_collisions_share: the contact components joined by the
// speculative contacts they may gain); each group belongs to the owner by
// place (FloeOwners) of its lowest floe; each rank solves its own groups,
// and the ranks then exchange the velocities their solves changed (index +
// state), the warm-store pairs they stored and their collision counts. A
// step where a share could not run alone (StepCollisionShare::Conflict: a
// failed LCP, an error) is solved again whole on every rank from the states
// on entry: the serial solve, so the answer is the serial one bit for bit
// either way.

#include <cstddef>
#include <span>
#include <vector>

#include "contact/impulse.hpp"
#include "parallel/advance_share.hpp"
#include "parallel/comm.hpp"

namespace floesim::parallel {

// The options of the collisions at the step's start by owner.
struct CollideShareOptions {
  // The back-off after a fallback (AdvanceShareOptions::max_wait; the
  // advance's rule, its own counts).
  AdvanceShareOptions back_off;
  // Test hook, not a user key (`floesim run` reads it from the environment,
  // FLOESIM_TEST_COLLIDE_FALLBACK=warm): a share whose solves started from
  // the warm store is a conflict (StepCollisionShare::Conflict::warm_start;
  // docs/parallel.md, "The step-start collisions' conflicts (collide27)"):
  // the tries whose shares use the store fall back, so the tests reach the
  // whole path and the whole state gathered on demand on a real run (the
  // wall jam of examples/pack_against_wall.toml) with the shares otherwise
  // unchanged.
  bool warm_conflict = false;
};

// One rank's part of a step's collisions: what its share did, the states of
// the floes it changed (outcome.moved's order; none on a conflict), the
// warm-store pairs it stored (outcome.warm; none on a conflict), its
// counts and, in a run that keeps the impulse record, its record (its loads'
// places: outcome.places; none on a conflict).
struct CollidePart {
  contact::StepCollisionShare outcome;
  std::vector<FloeState> states;
  contact::CollisionStats stats;
  contact::ImpulseRecord record;
};

std::vector<std::byte> pack(const CollidePart& part);
CollidePart unpack_collide_part(std::span<const std::byte> bytes);

// Runs rank `rank`'s share (contact::resolve_step_collisions_share) on
// `floes` (the states on entry, W^-) and returns its part; `floes` is left
// with the share's states. With options.record, the share records into the
// part's own record (options.record itself is left alone); with
// options.warm, the share runs on a copy of the store (options.warm is left
// alone) and its part carries the pairs it stored.
// With `groups` (contact::resolve_step_collisions_share), `detection` may be
// the rank's part of the step's (collide_on_part). `share_options`: its
// test hook (warm_conflict).
CollidePart run_collide_share(Floes& floes, std::span<const FloeState> start, const contact::Detection& detection,
                              double step, const contact::ImpulseOptions& options, std::span<const int> owner,
                              int rank, const contact::StepGroups* groups = nullptr,
                              const CollideShareOptions& share_options = {});

// Combines every rank's part (rank order) into `floes` (each part's moved
// floes take its states), `stats` (contact::add_collision_counts), `record`
// (if not null: the parts' records merged as the whole call's one event,
// contact::merge_step_record) and `warm` (if not null: the run's warm
// store, every part's stored pairs and uses written into it, hold_warm), sets
// `speculative` to the parts' sum and returns true; or returns false,
// changing nothing, when a part has a conflict, two parts moved one floe or
// two parts stored one warm pair (the groups are disjoint, and so are their
// pairs: this would be a bug, refused all the same).
bool combine_collide_parts(std::span<const CollidePart> parts, Floes& floes, contact::CollisionStats& stats,
                           std::size_t& speculative, contact::ImpulseRecord* record = nullptr,
                           contact::WarmStart* warm = nullptr);

// The collisions at the step's start on every rank of `comm`, as
// contact::resolve_step_collisions (whose arguments these are; no impulses
// out): this rank's share, one exchange (allgather_bytes: two collective
// calls on every rank; the share's impulse record, with options.record, in
// the same message), then the combination or, on a conflict, the whole
// solve from the states on entry (which records into options.record).
// `counts` and the back-off are those of the advance's (AdvanceShareCounts,
// AdvanceShareOptions), kept apart; `counts.clusters` counts each rank's step
// groups in the steps not redone. With options.warm, the parts' stored
// pairs are written into it on every rank. Returns the speculative contacts'
// count. Equal to the serial solve bit for bit, states, counts, record and
// warm store.
std::size_t collide_by_owner(const Communicator& comm, std::span<const int> owner, Floes& floes,
                             std::span<const FloeState> start, const contact::Detection& detection, double step,
                             const contact::ImpulseOptions& options, contact::CollisionStats& stats,
                             AdvanceShareCounts& counts, const CollideShareOptions& share_options = {});

// The detection's lists by owner (docs/parallel.md, "The detection's lists
// by owner"). `part`: the pairs a rank detected (parallel::detect_part, in
// pair order). Per rank s, the pairs of `part` that s's step groups read and
// s did not detect: a pair with contact points or a witness at or beyond xi
// (contact::group_edges' flags) whose dynamic floes are in one group whose
// lowest floe s owns (the group's owner as the edges say it: no owner array
// is read). Entry `rank` (this rank's) is empty. Reads of `floes` only the
// pairs' floes' flags.
std::vector<contact::Detection> pairs_for_groups(const Floes& floes, const contact::Detection& part,
                                                 const contact::StepGroups& groups, int ranks, int rank,
                                                 double collision_distance);

// The collisions at the step's start on every rank of `comm` from this
// rank's part of the detection (`part`, as parallel::detect gives it)
// instead of the whole: its edges (contact::group_edges) gathered to every
// rank (one allgather_bytes; each edge says its floes' owners, so the
// groups' owners come from the edges), the same step groups on every rank
// (contact::step_groups), the pairs of groups owned elsewhere sent to their
// owners with their floes (parallel::RoutedFloes: one alltoall_bytes, two
// collective calls), this rank's share on its pairs and those received,
// reading the received floes from the message, then collide_by_owner's exchange and
// combination; with options.record each share records its loads with
// their places keyed by pair (contact::ContactPlace) and every rank merges
// the parts into options.record. A fallback and a step the back-off does
// whole solve over every floe: `whole` gives them the whole state (W^- in
// `floes`, the step's start in the caller's `start`, which the span views)
// and then the whole detection; with no `whole`, the caller holds every
// floe current and the detection is gathered here (parallel::gather).
// Equal to the serial solve bit for bit, states, counts, record and warm
// store.
std::size_t collide_on_part(const Communicator& comm, std::span<const int> owner, Floes& floes,
                            std::span<const FloeState> start, const contact::Detection& part, double step,
                            const contact::ImpulseOptions& options, contact::CollisionStats& stats,
                            AdvanceShareCounts& counts, const CollideShareOptions& share_options = {},
                            const WholeOnDemand* whole = nullptr);

}  // namespace floesim::parallel
