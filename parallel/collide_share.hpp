#pragma once
// Stage seven (docs/parallel.md, "The collisions at the step's start: by
// cluster owner"): the collision LCPs at a step's start by owner. Every rank
// finds the step groups from the replicated detection and states (contact::
// resolve_step_collisions_share: the contact components joined by the
// speculative contacts they may gain); each group belongs to the owner by
// place (FloeOwners) of its lowest floe; each rank solves its own groups,
// and the ranks then exchange the velocities their solves changed (index +
// state) and their collision counts. A step where a share could not run
// alone (StepCollisionShare::Conflict: the warm store, a failed LCP, an
// error) is solved again whole on every rank from the states on entry: the
// serial solve, so the answer is the serial one bit for bit either way.

#include <cstddef>
#include <span>
#include <vector>

#include "contact/impulse.hpp"
#include "parallel/advance_share.hpp"
#include "parallel/comm.hpp"

namespace floesim::parallel {

// One rank's part of a step's collisions: what its share did, the states of
// the floes it changed (outcome.moved's order; none on a conflict) and its counts.
struct CollidePart {
  contact::StepCollisionShare outcome;
  std::vector<FloeState> states;
  contact::CollisionStats stats;
};

std::vector<std::byte> pack(const CollidePart& part);
CollidePart unpack_collide_part(std::span<const std::byte> bytes);

// Runs rank `rank`'s share (contact::resolve_step_collisions_share) on
// `floes` (the states on entry, W^-) and returns its part; `floes` is left
// with the share's states.
CollidePart run_collide_share(Floes& floes, std::span<const FloeState> start, const contact::Detection& detection,
                              double step, const contact::ImpulseOptions& options, std::span<const int> owner,
                              int rank);

// Combines every rank's part (rank order) into `floes` (each part's moved
// floes take its states) and `stats` (contact::add_collision_counts), sets
// `speculative` to the parts' sum and returns true; or returns false,
// changing nothing, when a part has a conflict or two parts moved one floe
// (the groups are disjoint: this would be a bug, refused all the same).
bool combine_collide_parts(std::span<const CollidePart> parts, Floes& floes, contact::CollisionStats& stats,
                           std::size_t& speculative);

// The collisions at the step's start on every rank of `comm`, as
// contact::resolve_step_collisions (whose arguments these are; no impulse
// record, no impulses out): this rank's share, one exchange
// (allgather_bytes: two collective calls on every rank), then the
// combination or, on a conflict, the whole solve from the states on entry.
// `counts` and the back-off are those of the advance's (AdvanceShareCounts,
// AdvanceShareOptions), kept apart; `counts.clusters` counts each rank's step
// groups in the steps not redone. Returns the speculative contacts' count.
// Equal to the serial solve bit for bit, states and counts.
std::size_t collide_by_owner(const Communicator& comm, std::span<const int> owner, Floes& floes,
                             std::span<const FloeState> start, const contact::Detection& detection, double step,
                             const contact::ImpulseOptions& options, contact::CollisionStats& stats,
                             AdvanceShareCounts& counts, const AdvanceShareOptions& share_options = {});

}  // namespace floesim::parallel
