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
#include <memory>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "contact/detection.hpp"
#include "contact/impulse.hpp"

namespace floesim::contact {

namespace detail {
class Stepper;
}

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
// So are the impulse record's events: the serial advance numbers its solves
// in pop order, and a share's solves of one pop get that pop's key, which
// no other share's pop has (merge_advance_record, impulse.hpp).
// The warm store (ImpulseOptions::warm) is kept across steps by pair: a
// solve reads and then replaces the entries of its contacts' pairs
// (warm_guess, warm_store), and a contact's pair has both floes in the
// cluster (or one and an obstacle), so the pairs one cluster's solves read
// and write are no other cluster's. A share therefore runs on a copy of the
// store as it was at the step's start (the same on every rank): each of its
// solves reads what the serial advance's would (the step's start, or what
// the share's own earlier solves stored), and the pairs it stored
// (ShareOutcome::warm), written into every rank's store with the other
// shares', leave it as the serial advance leaves it (each pair written by
// one share, its last write the serial one's). A failed LCP is a conflict
// (its dump is numbered in the run) and so is a RunError (the serial
// advance throws it, or a different one, in its order).
//
// The set-up by share. A pair's room (step 1) is a function of the pair and
// of its floes' states at the step's start: the same bits on whichever share
// computes it. The clusters read only which rooms are below xi (hot: below
// 0; tight: below xi), and, for the pads of jam-sized clusters (jam.hpp),
// the rooms of the pairs of those clusters' floes. So each share computes
// the rooms of the pairs whose lower floe it owns, the shares exchange their
// tight pairs (the caller's exchange between ShareAdvance::rooms and
// ShareAdvance::advance), and then every share knows every room below xi and
// finds the same clusters, whole. A room the share reads besides (a pad's
// pair, the budgets and breaks of its members: compute_budgets,
// collect_breaks) it computes when first read, from the step's start. Only
// the share's clusters' members and the obstacles are posed (a member is
// posed again before each measure; obstacles do not move). (ClusterShare:
// impulse.hpp; its owners must each be one of the sharing ranks, so that
// each pair's room is computed by one share.)

// A pair's room over the step (m), as one share gives it to the others,
// keyed by the pair itself (floes a < b and b's periodic shift), not by its
// place in one rank's list: a key every share can look up in whatever list
// of pairs it holds. On a share, owner_a and owner_b are the floes'
// ClusterShare::owner as the share that computed the room read them (it
// holds both floes); every cluster's lowest floe is a floe of a tight pair
// or contact edge, so the clusters' runners come from the edges, not from
// an owner array (-1 without a share). left_a and left_b (m) are the
// floes' reach less their straight travel over the step, as that share
// holds them: the join candidates' closure reads them (Stepper::routes).
struct PairRoom {
  std::uint32_t a = 0, b = 0;
  Vec2 shift = Vec2::Zero();
  double room = 0.0;
  std::int32_t owner_a = -1, owner_b = -1;
  double left_a = 0.0, left_b = 0.0;
};

// A pair with contact points between two dynamic floes: the jams
// (find_jams; jam.hpp) are the components of these edges, so the shares
// find the same jams from every share's edges, without every contact point.
// The pads' edges (ShareAdvance::pad_edges) are of this type too. Owners
// as in PairRoom.
struct ContactEdge {
  std::uint32_t a = 0, b = 0;
  std::int32_t owner_a = -1, owner_b = -1;
};

// On a part of the detection: a free floe that a cluster run by share `rank`
// may take in during the step, so every share sends it the floe's pairs too
// (ShareAdvance::clusters and routes; docs/parallel.md, "The advance from the
// rank's part").
struct JoinCandidate {
  std::uint32_t floe = 0;
  std::int32_t rank = 0;
  // Ordered by (floe, rank): the candidates are kept as sorted sets.
  friend bool operator<(const JoinCandidate& x, const JoinCandidate& y) {
    return x.floe != y.floe ? x.floe < y.floe : x.rank < y.rank;
  }
  friend bool operator==(const JoinCandidate& x, const JoinCandidate& y) {
    return x.floe == y.floe && x.rank == y.rank;
  }
};

// What a share did. On `conflict` other than none the floes' states are
// unusable and the caller redoes the advance whole from the step's states.
struct ShareOutcome {
  // missing_pairs: on a part of the detection, a free floe would join a
  // cluster of the share without being its candidate (JoinCandidate): the
  // share may not hold its pairs. missing_floe: on a part, a floe of the
  // pairs routed to the share came without its state, mass, collision shape
  // or reach (not finite where the share holds it: ShareAdvance::hold); not
  // a fallback but a fault of the routing, which the caller reports.
  // A solve from the warm store is not a conflict: the share runs on a
  // copy of the store and reports what it stored (`warm`).
  enum class Conflict { none, foreign_cluster, failed_lcp, error, missing_pairs, missing_floe };
  Conflict conflict = Conflict::none;
  // Ascending: the floes of the share's clusters (joined free floes
  // included); on missing_floe, the floe that came incomplete.
  std::vector<std::uint32_t> moved;
  long clusters = 0;                 // clusters of the share at the start of the step
  // The share's last floor step (floor_steps counted in its report): its key
  // (tau, cluster) and pair text; the serial floor_pair is the largest key's.
  double floor_tau = -1.0;
  long floor_cluster = -1;
  long rooms = 0;  // pair rooms the share computed (its own pairs', and those it read besides)
  long pairs = 0;  // pairs in the step's list (the serial advance computes every one's room)
  // Per event the share recorded (options.impulse.record), the key (tau,
  // cluster) of the queue's pop it was solved in (RecordPart, impulse.hpp).
  std::vector<EventPlace> events;
  // With a warm store (options.impulse.warm): the pairs the share's solves
  // stored, by key ascending, each as the share's copy holds it at the end
  // (WarmStart::Pair), and the share's solves that started from the store
  // (WarmStart::uses). Written into every rank's store, they make it the
  // serial advance's (ShareAdvance, "Why a share gives the serial bits").
  WarmStart::Written warm;
  long warm_uses = 0;
  // Which clusters (numbered as every share numbers them) the serial
  // advance would run together where the shares ran them apart, for the
  // caller to join them on one rank (ClusterShare::runners): on
  // foreign_cluster, (the share's cluster, each cluster of another runner
  // it would merge with); `merged`, (cluster, the share's cluster it
  // merged into) for each merge the share made; `taken`, (free floe,
  // cluster) for each free floe a cluster of the share took in (a free floe
  // two shares took is in both shares' `taken`).
  std::vector<std::pair<std::int32_t, std::int32_t>> met, merged, taken;
};

// The first half's answer: the share's tight pairs (room below xi) and
// contact edges, each in pair order, or a conflict (a RunError in the
// set-up). Concatenated over the shares (in any order), the second half's
// input.
// On a part, `outrun`: a floe the share owns would outrun its reach over
// the step (step 4 above), and the share computed no room: every share then
// rebuilds the pair list alike (ShareAdvance::rooms_rebuilt); the callers
// agree on it through this flag, gathered with the rooms.
struct ShareRooms {
  ShareOutcome::Conflict conflict = ShareOutcome::Conflict::none;
  bool outrun = false;
  std::vector<PairRoom> tight;
  std::vector<ContactEdge> touching;
};

// One share of the advance, in two halves around the caller's exchange of
// the tight pairs (contact/ knows nothing of ranks: the exchange is the
// caller's, parallel::advance_by_owner's gather, and each half is a plain
// call). Between the two halves `floes` must stay at the step's start.
// advance() moves the free floes (linearly: all of them, or on a part those
// it holds) and the clusters of `share` only; stats() and report() get this share's counts (report.rebuilt,
// the pair list's rebuild, is counted on every share: it is not the share's
// own). The impulse record (options.impulse.record, if any) receives the
// share's events, and ShareOutcome::events their places in the serial
// queue's order (merge_advance_record, impulse.hpp).
class ShareAdvance {
public:
  // on_part: `detection` is only this share's part of the detection (each
  // pair in exactly one share's part; the part's reach the whole reach):
  // the share computes the rooms of all its pairs, and between advance()'s
  // two halves below (clusters(), advance()) the caller routes the pairs.
  // `mine` (on a part; ascending): the floes the share's rank owns by place.
  // On a part the share reads and moves only the floes it holds (held()):
  // `mine`, its part's pairs' floes and, after hold(), the floes of the
  // pairs routed to it (their states, shapes and reach); its outrun check
  // reads `mine` (rooms(), ShareRooms::outrun).
  ShareAdvance(Floes& floes, const CollisionShapes& shapes, const Detection& detection, double dt,
               const SubstepOptions& options, const ClusterShare& share, bool on_part = false,
               std::span<const std::uint32_t> mine = {});
  ~ShareAdvance();
  ShareAdvance(const ShareAdvance&) = delete;
  ShareAdvance& operator=(const ShareAdvance&) = delete;

  // The set-up of the share's pairs: the straight paths, the pair list (and
  // its rebuild), and the rooms of the pairs whose lower floe the share owns.
  // On a part the rebuild is not the share's alone: when its own floes
  // would outrun their reach it says so (ShareRooms::outrun) and computes
  // nothing; when any share's did (the gathered flags, the same on every
  // share), every share calls rooms_rebuilt(reach): every floe's straight
  // path and the pair list rebuilt whole (the serial set-up; it reads the
  // whole pack, as before: the halo plan's piece 3 replaces it) with
  // `reach`, every floe's detection reach (the part's hold only its band's,
  // band18: the caller makes them whole from their owners), the rooms by
  // lower floe's owner as off a part, to be gathered as rooms()'s are.
  ShareRooms rooms();
  ShareRooms rooms_rebuilt(std::span<const double> reach);
  // On a part, the floes the share holds (ascending; every floe once the
  // pair list was rebuilt whole): those it reads and moves. The caller
  // keeps the others (the share moves none of them). Off a part, empty (the
  // share holds every floe).
  std::span<const std::uint32_t> held() const;
  // The rest, given the tight pairs and contact edges of every share
  // (concatenated, in any order; this share's included): the clusters, and
  // the share's advance.
  ShareOutcome advance(const ShareRooms& all);

  // On a part, advance(all) in pieces around the caller's exchanges.
  // clusters(): the clusters (the same on every share) and the free floes
  // the part says a cluster may take in (`candidates`: the rule in
  // substep_share.cpp, Stepper::candidates). routes(every share's candidates):
  // the pairs of the part to send, (share, index in the part), each pair to
  // every other share that runs a cluster with one of its floes or has one
  // of its floes as a candidate. hold(): the part and the pairs received,
  // merged in pair order; a routed pair's floe whose state, mass, shape or
  // reach is not finite there makes advance() a missing_floe conflict
  // without running (its sub-steps would read NaN: a sub-step that makes
  // no progress never ends). advance(): the share's advance on them; a free
  // floe that would join one of its clusters and is not its candidate (its
  // pairs are not all held) is a conflict (missing_pairs).
  // When a cluster is jam-sized (`pads`, the same on every share) its pads'
  // pairs are spread over the parts: the caller gathers every share's
  // pad_edges() (8 bytes each) and pads(every share's) gives the
  // candidates.
  struct Routes {
    ShareOutcome::Conflict conflict = ShareOutcome::Conflict::none;
    bool pads = false;
    bool any_cluster = false;  // the step has a cluster (the same on every share)
    std::vector<JoinCandidate> candidates;
  };
  Routes clusters(const ShareRooms& all);
  std::vector<ContactEdge> pad_edges();
  Routes pads(std::span<const ContactEdge> edges);
  std::vector<std::pair<int, std::uint32_t>> routes(std::span<const JoinCandidate> candidates);
  void hold(Detection held);
  ShareOutcome advance();

  const CollisionStats& stats() const { return stats_; }
  const SubstepReport& report() const { return report_; }
  // After clusters() (and pads()): the share that runs cluster k (its
  // lowest floe's owner as the edges carried it, or ClusterShare::runners').
  int runner_of_cluster(std::int32_t k) const;

private:
  SubstepOptions options_;  // the caller's, with the warm store replaced by warm_
  WarmStart warm_;          // a copy of the caller's warm store, logging what the share stores
  CollisionStats stats_;
  SubstepReport report_;
  ClusterShare share_;
  ShareOutcome::Conflict set_up_ = ShareOutcome::Conflict::none;
  long missing_ = -1;  // on missing_floe: the floe (hold)
  std::unique_ptr<detail::Stepper> stepper_;
};

}  // namespace floesim::contact
