#pragma once
// Multirate advance of the floes over one step of the run: only the floes
// that may collide within the step are sub-stepped, cluster by cluster; every
// other floe moves in one go.
//
// Contract. On entry the floes are at time t with the velocities they keep
// over the step (drift done, and the collisions of the contacts found at t
// resolved: W(t+), except a jam's, item 5); `detection` was measured at these positions, with the
// reach of each floe (detection.hpp). On exit the positions are at t + dt (not
// wrapped into a periodic box) and velocities carry the collisions of the
// step; every pair the sub-steps measured ended each sub-step apart, and
// every other pair kept at least keep = min(d, xi)/2 of its gap by the bounds
// below. The caller still re-detects at t + dt and redoes the step if anything
// overlaps (estimates in step_limit.hpp are not all rigorous).
//
// How (one step of length dt):
//  1. Each candidate pair gets its room over dt (step_limit.hpp) with the
//     present velocities, as if both floes moved on straight paths ("linear"
//     below; rotation at a constant rate). A pair whose room is negative may
//     meet within the step: it is hot. Clusters are the connected components
//     of hot pairs between dynamic floes (obstacles join no cluster; a hot
//     pair with an obstacle puts its floe in a cluster of its own).
//  2. Floes in no cluster are free: they move linearly over dt. Two free floes
//     keep their room; so does every pair as long as each floe stays close to
//     its linear path.
//  3. Each cluster runs event-driven sub-steps of its own: limit from its
//     internal pairs (members with members, and with obstacles), move,
//     re-measure those pairs (an overlap halves the sub-step), collide
//     (impulse.hpp). Its floes' deviation from their linear paths,
//        dev_i = |X_i - X_i^lin| + R_i |theta_i - theta_i^lin|,
//     bounds how much closer they got to any floe outside than the linear
//     bounds said. Each pair with one floe outside splits its room in two
//     halves, one per floe, so clusters can run one after another: floe i's
//     budget is the least half-room of its pairs with floes outside, and the
//     reach it has left (reach_i - its linear travel). A sub-step that would
//     take a floe past its budget is not taken; instead the pairs it would
//     break join the cluster: a free floe joins at once (at its linear
//     position, which is where it is at that time), a floe of another cluster
//     merges the two clusters, which rerun from the start of the step.
//  4. A floe whose linear travel exceeds its reach before the step makes the
//     pair list be rebuilt (once) with a larger reach.
//  5. A jam (jam.hpp) is a cluster from the step's start, whatever its
//     rooms, and takes time steps: one LCP for the rest of the step, its
//     contacts resting and its witnesses beyond xi speculative. Its velocities
//     on entry are W^- (resolve_step_collisions leaves jams alone). The LCP is
//     solved again only when its answer stops being one: a contact whose
//     turning grew, or a witness that a wider range found, took an impulse or
//     is not met by the answer's velocities.
// With no collision in sight this is one step for every floe; the cost of a
// collision is the cost of its cluster's sub-steps, not of the whole pack's.

#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "contact/detection.hpp"
#include "contact/impulse.hpp"

namespace floesim::contact {

struct SubstepOptions {
  double collision_distance = 0.01;  // xi, m
  double floor = 1e-5;               // s: a sub-step the limit wants shorter is taken at this length and counted
  int max_halvings = 40;             // an overlapping sub-step is halved at most this many times
  Domain domain;                     // to rebuild the pair list
  ImpulseOptions impulse;
};

// Running totals of a run.
struct SubstepReport {
  long clusters = 0;        // clusters sub-stepped
  long substeps = 0;        // their sub-steps
  long time_steps = 0;      // of those, dense clusters' time steps (the rest of a step in one LCP)
  long largest_cluster = 0; // floes
  long joined = 0;          // free floes that joined a running cluster
  long merges = 0;          // cluster merges (the merged cluster reruns the step)
  long rejected = 0;        // sub-steps redone with half the length after an overlap
  long floor_steps = 0;     // sub-steps held at the floor
  long rebuilt = 0;         // pair lists rebuilt for a floe that would outrun its reach
  long reach_exceeded = 0;  // cluster floes that went past their reach (left to the caller's check)
  std::string floor_pair;   // the last pair that held a sub-step at the floor
};

// The counts of `r` by name, in one list (checkpoints, sums over ranks):
// pointers into r (const or not, as r is); floor_pair is not a count.
template <class Report>
auto substep_counts(Report& r) {
  return std::array{std::pair{"clusters", &r.clusters}, std::pair{"substeps", &r.substeps},
                    std::pair{"time_steps", &r.time_steps}, std::pair{"largest_cluster", &r.largest_cluster},
                    std::pair{"joined", &r.joined}, std::pair{"merges", &r.merges},
                    std::pair{"rejected", &r.rejected}, std::pair{"floor_steps", &r.floor_steps},
                    std::pair{"rebuilt", &r.rebuilt}, std::pair{"reach_exceeded", &r.reach_exceeded}};
}

// Advances the floes over dt as stated above. Throws RunError when a sub-step
// overlaps however short it is made.
void advance_with_collisions(Floes& floes, const CollisionShapes& shapes, const Detection& detection, double dt,
                             const SubstepOptions& options, CollisionStats& stats, SubstepReport& report);

// One share of the advance: the clusters whose lowest floe `owner` gives to
// `rank` (a distributed run's cluster owner, docs/parallel.md stage seven).
//
// Why a share gives the serial bits. The clusters (step 1), the jams, the
// rooms, the straight paths, the budgets' pairs and the reaches are functions
// of the floes at the step's start and of the detection, the same on every
// rank. A cluster's events read and write only: its members' states, the
// fixed rooms and straight paths (budgets = half-rooms fixed at the start;
// a floe joins at linear(j, tau), which no other cluster changes while j is
// free), the obstacles, and the pair index. They touch another cluster only
// by merging with it (collect_breaks -> bring_in), and another cluster's
// work only through a free floe both take. So, as long as no cluster of the
// share merges with a cluster outside it and no floe joins clusters of two
// shares, each cluster runs the same sub-steps on the same numbers as in the
// serial advance: the serial queue, ordered by (tau, cluster), pops the
// share's entries in the same relative order, and the events of other
// clusters in between change nothing the share reads. Collision counters
// are sums (largest: a maximum); the last floor pair of the serial advance
// is the one with the largest (tau, cluster) key, which each share reports.
// The warm store (ImpulseOptions::warm) is shared across steps by pair, so
// a share that would use it is a conflict too (the stores of the ranks
// would part); so is a failed LCP (its dump is numbered in the run) and a
// RunError (the serial advance throws it, or a different one, in its order).
// (ClusterShare: impulse.hpp.)

// What a share did. On `conflict` other than none the floes' states are
// unusable and the caller redoes the advance whole from the step's states.
struct ShareOutcome {
  enum class Conflict { none, foreign_cluster, warm_start, failed_lcp, error };
  Conflict conflict = Conflict::none;
  std::vector<std::uint32_t> moved;  // ascending: the floes of the share's clusters (joined free floes included)
  long clusters = 0;                 // clusters of the share at the start of the step
  // The share's last floor step (floor_steps counted in its report): its key
  // (tau, cluster) and pair text; the serial floor_pair is the largest key's.
  double floor_tau = -1.0;
  long floor_cluster = -1;
};

// Advances the free floes (all of them, linearly) and the clusters of
// `share` only; `stats` and `report` get this share's counts (report.rebuilt,
// the pair list's rebuild, is counted on every share: it is not the share's
// own). The impulse record (options.impulse.record) must be null: its events'
// order is the serial queue's, not a share's.
ShareOutcome advance_share(Floes& floes, const CollisionShapes& shapes, const Detection& detection, double dt,
                           const SubstepOptions& options, const ClusterShare& share, CollisionStats& stats,
                           SubstepReport& report);

}  // namespace floesim::contact
