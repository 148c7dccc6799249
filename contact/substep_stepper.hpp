#pragma once
// The multirate advance's stepper (contact/substep.hpp): internal to the
// files that define its members: substep_setup.cpp (the set-up: paths,
// rooms, clusters), substep.cpp (the clusters' events), substep_share.cpp
// (a share on a part: candidates, routes, held pairs) and substep_jam.cpp
// (the jams' time steps).

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <span>
#include <utility>
#include <vector>

#include "contact/detection.hpp"
#include "contact/impulse.hpp"
#include "contact/step_limit.hpp"
#include "contact/substep.hpp"

namespace floesim::contact::detail {

inline constexpr double kInf = std::numeric_limits<double>::infinity();
inline constexpr int kFree = -1;
// A sub-step is halved after an overlap down to this fraction of the floor.
inline constexpr double kHalvingFloor = 0x1.0p-20;
// On a part of the detection, the pairs whose room is below this many xi
// ("near") are gathered with the tight ones: the join candidates' closure
// (Stepper::candidates, routes). The pairs that brought floes in beyond
// depth two on the 1500- and 10 000-floe packs had rooms of a few mm.
inline constexpr double kNearRooms = 10.0;

// Compressed rows (CSR): row r holds entries[offsets[r], offsets[r + 1]).
// Built by compressed_rows: the stepper's pair index (each pair in the rows
// of its two floes) and routes' near pairs and candidates' shares by floe.
template <class T>
struct CompressedRows {
  std::vector<std::size_t> offsets{0};
  std::vector<T> entries;
  std::span<const T> row(std::size_t r) const { return {entries.data() + offsets[r], offsets[r + 1] - offsets[r]}; }
};
// `rows` rows from `count` items: each(k, put) calls put(row, value) for
// each entry item k adds (any number); a row's entries keep the items'
// order. Two passes over the items (count, then fill), O(rows + entries).
template <class T, class Each>
CompressedRows<T> compressed_rows(std::size_t rows, std::size_t count, Each&& each) {
  CompressedRows<T> out;
  out.offsets.assign(rows + 1, 0);
  for (std::size_t k = 0; k < count; ++k) each(k, [&](std::size_t r, const T&) { ++out.offsets[r + 1]; });
  for (std::size_t r = 0; r < rows; ++r) out.offsets[r + 1] += out.offsets[r];
  out.entries.resize(out.offsets[rows]);
  std::vector<std::size_t> fill(out.offsets.begin(), out.offsets.end() - 1);
  for (std::size_t k = 0; k < count; ++k) each(k, [&](std::size_t r, const T& v) { out.entries[fill[r]++] = v; });
  return out;
}

// The floes of `pairs` (both ends) merged into the ascending set `into`
// (a share's held floes: set_up, hold).
inline void add_floes(std::vector<std::uint32_t>& into, std::span<const NearPair> pairs) {
  const std::size_t old = into.size();
  for (const NearPair& q : pairs) into.insert(into.end(), {q.a, q.b});
  std::sort(into.begin() + static_cast<std::ptrdiff_t>(old), into.end());
  std::inplace_merge(into.begin(), into.begin() + static_cast<std::ptrdiff_t>(old), into.end());
  into.erase(std::unique(into.begin(), into.end()), into.end());
}

// Pairs measured with their contact points and witnesses.
struct Measured {
  std::vector<NearPair> pairs;
  std::vector<ContactPoint> contacts;
  std::vector<Witness> witnesses;
};

// A cluster being sub-stepped. Its floes move on straight lines between its
// sub-step ends (tau_snap -> tau), where its collisions are resolved.
struct Cluster {
  std::vector<std::uint32_t> members;  // dynamic floes
  double tau = 0.0;                    // s into the step: where the cluster is
  double tau_snap = 0.0;               // start of its last sub-step
  std::vector<FloeState> snap;         // members' states at tau_snap (velocities of that sub-step)
  std::vector<std::uint32_t> internal; // pairs: members with members, and with obstacles
  Measured cur;                        // the internal pairs measured at tau
  bool alive = true;                   // false once merged into another cluster
  bool events_only = false;            // its time step overlapped: events for the rest of the step
  double jam_h = std::numeric_limits<double>::infinity();  // s, its time step (halved when one overlaps)
};

// One call of advance_with_collisions (the steps of substep.hpp). Clusters
// are advanced in time order, one sub-step at a time (the cluster furthest
// behind goes next), so when one must merge with another, that one has a
// sub-step in progress that started no later than now: its floes are put
// where their straight paths take them now, and the two go on together.
class Stepper {
public:
  Stepper(Floes& floes, const CollisionShapes& shapes, const Detection& detection, double dt,
          const SubstepOptions& options, CollisionStats& stats, SubstepReport& report,
          const ClusterShare* share = nullptr, bool part = false, std::span<const std::uint32_t> mine = {})
      : floes_(floes), shapes_(shapes), det_(&detection), dt_(dt), opt_(options), stats_(stats), report_(report),
        share_(share), part_(part), mine_(mine) {}

  ShareOutcome::Conflict conflict() const { return conflict_; }
  // The share that runs cluster k (after clusters()).
  int cluster_runner(std::size_t k) const { return edge_owner_[clusters_[k].members.front()]; }
  // A share's run (ShareAdvance): what it did.
  ShareOutcome outcome() const {
    ShareOutcome o;
    o.conflict = conflict_;
    o.floor_tau = floor_tau_;
    o.floor_cluster = floor_cluster_;
    o.rooms = rooms_;
    o.pairs = pairs_;
    o.events = events_;
    o.met = met_;
    o.merged = merged_;
    o.taken = taken_;
    for (std::size_t k = 0; k < clusters_.size(); ++k) {
      if (!own_[k]) continue;
      ++o.clusters;
      if (clusters_[k].alive) o.moved.insert(o.moved.end(), clusters_[k].members.begin(), clusters_[k].members.end());
    }
    std::sort(o.moved.begin(), o.moved.end());
    return o;
  }

  // The advance over dt (substep.hpp, steps 1 to 5): set_up, then advance
  // with its own tight pairs (every pair's room computed: the serial advance).
  void run() {
    const ShareRooms own = set_up();
    advance(own.tight, own.touching);
  }

  // Step 1's set-up for the pairs this call computes (a share's: those whose
  // lower floe it owns; else all): the straight paths, the pair list
  // (rebuilt if a floe would outrun its reach), its index, and those pairs'
  // rooms. Returns the tight ones (room below xi) and the contact edges of
  // those pairs, in pair order. On a part: the straight paths of the floes
  // it holds (held_floes_) only, and, when one of its own floes (mine_)
  // would outrun its reach, only that (ShareRooms::outrun): the caller
  // agrees on it with the other shares and calls set_up_rebuilt.
  ShareRooms set_up();
  // On a part, after any share's set_up said outrun: every floe's straight
  // path and the pair list rebuilt whole with every floe's reach `reach`
  // (a part holds only its band's: the caller has them from their owners),
  // then set_up's rooms.
  ShareRooms set_up_rebuilt(std::span<const double> reach);
  // The floes this call reads and moves, ascending (every floe off a part
  // or once rebuilt whole).
  std::span<const std::uint32_t> held_floes() const { return held_floes_; }

  // Steps 1 to 5 from there, given the tight pairs and contact edges of
  // every share (this call's included, in any order): the clusters, then
  // the advance of the share's clusters only when given one. A tight pair is
  // looked up in the pair list by its key (a, b, shift).
  void advance(std::span<const PairRoom> tight, std::span<const ContactEdge> touching) {
    clusters(tight, touching);
    if (conflict_ == ShareOutcome::Conflict::none) run_share();
  }
  // The two halves of advance() for a share on a part of the detection
  // (ShareAdvance, on_part), around the caller's routing of the pairs.
  // clusters(): the same clusters on every share; on a part, a jam-sized
  // cluster (its pads read pairs no share holds whole) is a conflict.
  void clusters(std::span<const PairRoom> tight, std::span<const ContactEdge> touching);
  // On a part: the free floes the part's pairs say a cluster may take in,
  // with the share that runs it (sorted, unique; substep_share.cpp).
  std::vector<JoinCandidate> candidates() const;
  // On a part, given every share's candidates: for each held pair touching
  // a member of a cluster another share runs or a candidate of another
  // share, (that share, the pair's index), sorted; and which floes this
  // share will hold every pair of (held_floe_: its members and candidates).
  std::vector<std::pair<int, std::uint32_t>> routes(std::span<const JoinCandidate> candidates);
  // On a part: the pairs the share holds from now on (its part and the
  // pairs routed to it, in pair order: every pair of its clusters' members),
  // the rooms known so far carried over by key. Returns the first floe the
  // routed pairs brought in whose state, mass, collision shape or reach is
  // not finite (it came without them), or -1.
  long hold(Detection held);
  void run_share();

private:
  // The share that runs floe i's cluster, or -1 for a free floe: the owner
  // of its lowest floe as the edges say (edge_owner_).
  int runner(std::uint32_t i) const {
    const int k = cluster_of_[i];
    return k == kFree ? -1 : edge_owner_[clusters_[static_cast<std::size_t>(k)].members.front()];
  }
  // The owners the tight pairs', contact edges' or pads' ends carry, into
  // edge_owner_ (every share is given the same edges: the same owners).
  template <class Edge>
  void take_owners(std::span<const Edge> edges) {
    for (const Edge& e : edges) {
      edge_owner_[e.a] = e.owner_a;
      edge_owner_[e.b] = e.owner_b;
    }
  }
  // The owners of pair q's floes as this share reads them (its part's
  // pairs: floes it holds), -1 without a share.
  std::pair<std::int32_t, std::int32_t> owners(const NearPair& q) const {
    if (!share_) return {-1, -1};
    return {share_->owner[q.a], share_->owner[q.b]};
  }

  // Floe i's straight-path travel over the step from its start state: the
  // bound |v| dt + |omega| R dt on any of its points' displacement (m).
  double travel(std::size_t i) const {
    const FloeState& s = start_[i];
    return (std::hypot(s.vx, s.vy) + std::abs(s.yaw_rate) * shapes_.radius[i]) * dt_;
  }

  std::uint32_t other(std::uint32_t p, std::uint32_t i) const {
    const NearPair& q = det_->pairs[p];
    return q.a == i ? q.b : q.a;
  }

  // The floe on its straight path, tau after the start of the step.
  FloeState linear(std::uint32_t i, double tau) const {
    return drifted(start_[i], tau);
  }

  // How far any point of floe i is from where its straight path would put it.
  double deviation(std::uint32_t i, double tau) const {
    const FloeState l = linear(i, tau);
    const FloeState& s = floes_.state[i];
    return std::hypot(s.x - l.x, s.y - l.y) + shapes_.radius[i] * std::abs(s.yaw - l.yaw);
  }

  // Whether floe i's state, mass (dynamic floes), collision shape and reach
  // are finite where this call holds them.
  bool whole(std::uint32_t i) const;

  // The pair list detected again over the step, each floe's reach at least
  // 1.5 times its straight path's travel (the serial set-up: det_->reach).
  void rebuild_pairs(std::span<const double> reach);
  // set_up's rest: the pair index and the rooms this call computes.
  ShareRooms set_up_rooms();
  // f(i) for each floe this call holds: held_floes_ on a part, else every floe.
  template <class F>
  void for_held(F&& f) const {
    if (holds_part()) {
      for (const std::uint32_t i : held_floes_) f(i);
    } else {
      for (std::uint32_t i = 0; i < floes_.size(); ++i) f(i);
    }
  }
  // A share given only its part of the detection (each pair in one part),
  // and the pair list not rebuilt whole.
  bool holds_part() const { return part_ && det_ != &rebuilt_; }
  // The index of the pair keyed as `k` in det_, or det_->pairs.size().
  template <class Key>
  std::size_t find_pair(const Key& k) const {
    const auto before = [](const NearPair& q, const Key& key) {
      return pair_before(PairRoom{q.a, q.b, q.shift, 0.0}, PairRoom{key.a, key.b, key.shift, 0.0});
    };
    const auto at = std::lower_bound(det_->pairs.begin(), det_->pairs.end(), k, before);
    if (at == det_->pairs.end() || at->a != k.a || at->b != k.b || at->shift.x() != k.shift.x() ||
        at->shift.y() != k.shift.y())
      return det_->pairs.size();
    return static_cast<std::size_t>(at - det_->pairs.begin());
  }

  // Whether set_up computes pair p's room: the share's when its lower floe is
  // the share's (each pair on exactly one share), every pair without a share.
  bool computes(std::uint32_t p) const {
    if (!share_ || holds_part()) return true;
    const NearPair& q = det_->pairs[p];
    return share_->owner[std::min(q.a, q.b)] == share_->rank;
  }

  // Pair p's room over the step on the straight paths from the step's start
  // (step_limit.hpp), computed when first read: set_up's pairs, the gathered
  // tight ones, and, on a share, those it reads besides (substep.hpp,
  // "The set-up by share"). A pair no share found tight and not read is
  // +inf in room_, which make_clusters reads as "not below xi": right, as
  // every pair below xi was gathered.
  double room(std::uint32_t p) {
    if (!known_[p]) {
      // pair_room reads the floes' states (only): the start's, swapped in
      // for the call (O(1); pair_room throws nothing). Before anything
      // moves (set_up, make_clusters) they are the floes' own.
      if (moving_) std::swap(floes_.state, start_);
      room_[p] = pair_room(floes_, shapes_, det_->pairs[p], witnesses_of(det_->pairs[p], det_->witnesses),
                           opt_.collision_distance, dt_);
      if (moving_) std::swap(floes_.state, start_);
      known_[p] = 1;
      ++rooms_;
    }
    return room_[p];
  }

  // pairs_of(i): indices of the candidate pairs of floe i (compressed rows).
  void build_pair_index();
  std::span<const std::uint32_t> pairs_of(std::uint32_t i) const { return pairs_by_floe_.row(i); }

  // Clusters: connected components of the hot pairs between dynamic floes,
  // grown through tight pairs (room below xi: a floe of the cluster that
  // collides would soon bring the other in anyway, one at a time), numbered
  // by their lowest floe. Reads the tight pairs (tight_) and the rooms of
  // the pairs of jam-sized clusters' floes (their pads: pad_edges, then
  // apply_pads and form_clusters; on a part the caller gathers every
  // share's pad edges in between, pads_pending()).
  void make_clusters();
  void form_clusters();

public:
  bool pads_pending() const { return pads_pending_; }
  bool any_cluster() const { return !clusters_.empty(); }
  // The pad edges of the pairs this call holds (every pair without a part).
  std::vector<ContactEdge> pad_edges();
  // Every share's pad edges (any order) joined, then the clusters formed.
  void apply_pads(std::span<const ContactEdge> pads);

private:

  // jam_of_[i]: the jam of floe i (-1: none), jams_: their floes; from the
  // contact edges of every share (touching_).
  void find_jams();

  // Budget of each member: half the room of each pair with a floe outside
  // the cluster (obstacles do not move: their pairs are internal).
  void compute_budgets(int k);

  void collect_internal(int k);

  // Measures a cluster's internal pairs at the present poses into m; true if
  // one overlaps.
  bool measure(const Cluster& c, Measured& m) const;
  void measure_internal(Cluster& c);

  void snapshot(Cluster& c) {
    c.snap.clear();
    for (std::uint32_t i : c.members) c.snap.push_back(floes_.state[i]);
    c.tau_snap = c.tau;
  }
  void restore(Cluster& c) {
    for (std::size_t m = 0; m < c.snap.size(); ++m) floes_.state[c.members[m]] = c.snap[m];
  }

  // The speculative contact of witness w of pair q (impulse.hpp).
  static ContactPoint speculative(const NearPair& q, const Witness& w) {
    return {q.a, q.b, 0.5 * (w.pa + w.pb), w.normal, w.distance, q.shift, true, w.vertex_of_b};
  }

  // One event of cluster k: a sub-step, or floes joining it at its time.
  void advance_cluster(int k);

  // The floes outside cluster k whose pairs with its members, now at time t1,
  // are past the members' budgets: free ones to joining_, clusters to merging_.
  void collect_breaks(int k, double t1);

  // A dense cluster (jam.floes floes or more) takes the rest of the step in
  // one go: its contacts rest and every point of its pairs beyond xi is a
  // speculative contact for that time (impulse.hpp), one LCP instead of an
  // event, and an LCP of the whole cluster, each time one of its many pairs
  // meets. If that overlaps after all (a pair turning faster than its
  // linearised witness gaps tell: an error in h^2), the time step is redone
  // with half the length; below jam.step_floor dt the cluster goes back to
  // events for the rest of the step.
  void time_step(int k);

  // The floes in joining_ (free) and the clusters in merging_ join cluster k
  // at its time: a free floe where its straight path puts it, a cluster's
  // floes where its sub-step in progress puts them (it started no later than
  // now: time order). Then the collisions at that time are resolved.
  void bring_in(int k);

  // An event's collisions: contacts approaching no faster than rest_speed
  // rest (restitution 0, impulse.hpp), the others are impacts.
  void collide(const std::vector<ContactPoint>& contacts) {
    resolve_collisions(floes_, contacts, opt_.impulse, stats_,
                       slow_contacts(floes_, contacts, opt_.impulse.rest_speed));
  }

  Floes& floes_;
  const CollisionShapes& shapes_;
  const Detection* det_;
  Detection rebuilt_;  // when the pair list had to be rebuilt
  double dt_;
  const SubstepOptions& opt_;
  CollisionStats& stats_;
  SubstepReport& report_;
  const ClusterShare* share_;          // null: every cluster (the serial advance)
  bool part_ = false;                  // det_ is the share's part of the detection (until rebuilt)
  std::span<const std::uint32_t> mine_; // on a part: the floes the share's rank owns by place (ascending)
  std::vector<std::uint32_t> held_floes_;  // on a part: mine_ and the held pairs' floes (ascending)
  Detection held_;                     // on a part: its pairs and those routed to the share
  std::vector<std::uint8_t> held_floe_;  // on a part: per floe, every pair of it held (members, candidates)
  std::vector<std::uint8_t> own_;      // per cluster: run by this call
  ShareOutcome::Conflict conflict_ = ShareOutcome::Conflict::none;
  std::vector<EventPlace> events_;     // a share's: per event it recorded, its pop's key
  std::vector<std::pair<std::int32_t, std::int32_t>> met_, merged_, taken_;  // ShareOutcome::met, merged, taken
  double floor_tau_ = -1.0;            // the last floor step's key (tau, cluster)
  long floor_cluster_ = -1;

  std::vector<FloeState> start_;       // at the start of the step: the straight paths
  std::vector<double> lin_;            // m, linear travel of each floe over the step
  std::vector<double> room_;           // m, per pair, over the step on straight paths (room(): when known_)
  std::vector<std::uint8_t> known_;    // per pair: room_ computed or gathered
  std::vector<PairRoom> tight_;        // the pairs whose room is below xi (every share's; on a part, the near ones too)
  std::vector<ContactEdge> touching_;  // every share's pairs with contact points between dynamic floes
  long rooms_ = 0;                     // rooms computed by this call (pair_room)
  long pairs_ = 0;                     // pairs in the list set_up saw (on a part: the part's)
  bool moving_ = false;                // floes moved: the start's states are start_ only
  CompressedRows<std::uint32_t> pairs_by_floe_;  // the pair index (pairs_of)
  std::vector<int> cluster_of_;        // kFree or a cluster
  std::vector<std::int32_t> edge_owner_;  // per floe: its owner as the gathered edges carry it, or -1
  std::vector<Cluster> clusters_;
  std::vector<double> budget_, reach_left_;  // m, per floe
  std::vector<std::uint8_t> outran_;
  PosedShapes posed_;
  std::vector<std::uint32_t> stamp_;
  std::uint32_t epoch_ = 0;
  Measured next_;                      // a cluster's pairs after the sub-step being tried
  std::vector<std::uint32_t> joining_;
  std::vector<int> merging_;
  std::array<Measured, 2> wide_;                 // time_step: the pairs measured within wider ranges (two rounds)
  DisjointSets sets_;                            // make_clusters: the floes' components so far
  std::vector<std::uint8_t> hot_, big_;          // make_clusters: per floe, hot; in a jam-sized cluster
  bool pads_pending_ = false;                    // on a part: the clusters wait for every share's pad edges
  std::vector<int> jam_of_;                      // per floe: its jam, or -1
  std::vector<std::vector<std::uint32_t>> jams_; // the floes of each jam
};

}  // namespace floesim::contact::detail
