#include "contact/substep.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <queue>
#include <sstream>

#include "contact/step_limit.hpp"
#include "contact/substep_stepper.hpp"
#include "core/error.hpp"

namespace floesim::contact {

namespace detail {

namespace {
// The floes of `pairs` (both ends) merged into the ascending set `into`.
void add_floes(std::vector<std::uint32_t>& into, std::span<const NearPair> pairs) {
  const std::size_t old = into.size();
  for (const NearPair& q : pairs) into.insert(into.end(), {q.a, q.b});
  std::sort(into.begin() + static_cast<std::ptrdiff_t>(old), into.end());
  std::inplace_merge(into.begin(), into.begin() + static_cast<std::ptrdiff_t>(old), into.end());
  into.erase(std::unique(into.begin(), into.end()), into.end());
}
}  // namespace

ShareRooms Stepper::set_up() {
  const std::size_t n = floes_.size();
  if (holds_part()) {
    // The floes the share holds: its own and its part's pairs' (the routed
    // pairs' join them in hold()). Their straight paths only; the other
    // entries of start_ and lin_ are never read (piece 9 of the halo plan
    // makes the arrays the held floes').
    held_floes_.assign(mine_.begin(), mine_.end());
    add_floes(held_floes_, det_->pairs);
    start_.resize(n);
    lin_.assign(n, 0.0);
    for (const std::uint32_t i : held_floes_) {
      start_[i] = floes_.state[i];
      if (!floes_.is_static[i]) lin_[i] = travel(i);
    }
    // Every floe is some share's own: the shares' flags, gathered, are the
    // serial check over every floe.
    ShareRooms out;
    for (const std::uint32_t i : mine_) out.outrun = out.outrun || lin_[i] > det_->reach[i];
    if (out.outrun) return out;
    return set_up_rooms();
  }
  start_ = floes_.state;
  lin_.assign(n, 0.0);
  bool outrun = false;
  for (std::size_t i = 0; i < n; ++i) {
    if (floes_.is_static[i]) continue;
    lin_[i] = travel(i);
    outrun = outrun || lin_[i] > det_->reach[i];
  }
  if (outrun) rebuild_pairs();
  return set_up_rooms();
}

ShareRooms Stepper::set_up_rebuilt() {
  // As the serial set-up whose check found a floe outrunning: every floe.
  const std::size_t n = floes_.size();
  start_ = floes_.state;
  lin_.assign(n, 0.0);
  for (std::size_t i = 0; i < n; ++i)
    if (!floes_.is_static[i]) lin_[i] = travel(i);
  rebuild_pairs();
  held_floes_.resize(n);
  for (std::uint32_t i = 0; i < n; ++i) held_floes_[i] = i;
  return set_up_rooms();
}

ShareRooms Stepper::set_up_rooms() {
  build_pair_index();
  const std::size_t pairs = det_->pairs.size();
  pairs_ = static_cast<long>(pairs);
  room_.assign(pairs, kInf);
  known_.assign(pairs, 0);
  ShareRooms out;
  for (std::uint32_t p = 0; p < pairs; ++p) {
    if (!computes(p)) continue;
    const NearPair& q = det_->pairs[p];
    const double r = room(p);
    // On a part the near pairs too (Stepper::candidates, depth three and on).
    const auto [oa, ob] = owners(q);
    if (r < (holds_part() ? kNearRooms : 1.0) * opt_.collision_distance)
      out.tight.push_back({q.a, q.b, q.shift, r, oa, ob, det_->reach[q.a] - lin_[q.a], det_->reach[q.b] - lin_[q.b]});
    if (q.contact_count > 0 && !floes_.is_static[q.a] && !floes_.is_static[q.b])
      out.touching.push_back({q.a, q.b, oa, ob});
  }
  return out;
}

void Stepper::clusters(std::span<const PairRoom> tight, std::span<const ContactEdge> touching) {
  tight_.assign(tight.begin(), tight.end());
  // The rooms of the tight pairs this call holds (pair order: find_pair); on
  // a part, a tight pair of another share's part is not held.
  for (const PairRoom& t : tight_) {
    const std::size_t p = find_pair(t);
    FLOESIM_ASSERT(p < det_->pairs.size() || holds_part());
    if (p < det_->pairs.size() && !known_[p]) {
      room_[p] = t.room;
      known_[p] = 1;
    }
  }
  touching_.assign(touching.begin(), touching.end());
  edge_owner_.assign(floes_.size(), -1);
  take_owners(std::span<const PairRoom>(tight_));
  take_owners(std::span<const ContactEdge>(touching_));
  make_clusters();
}

namespace {
// The candidates as a set: sorted by (floe, rank), each once.
void sort_unique(std::vector<JoinCandidate>& c) {
  std::sort(c.begin(), c.end());
  c.erase(std::unique(c.begin(), c.end()), c.end());
}
}  // namespace

// Which free floes a cluster may take in during the step. A free floe j
// joins cluster k at time t only through a member i and a pair p = (i, j)
// with room(p)/2 < dev_i(t) (collect_breaks), dev_i the member's deviation
// from its straight path; the deviation has no bound known at the start
// (the collisions set it), so every free dynamic floe with a pair to a
// member is a candidate: exact at depth one. A floe j that joined is a
// member from then on, and brings in a free l through a pair (j, l) with
// room(j, l)/2 < dev_j. As long as j stays within its reach, dev_j <=
// reach_j - lin_j (beyond it the detection no longer holds every pair j may
// meet: reach_exceeded, the caller's check), so l is a candidate at depth two
// when room(j, l) < 2 (reach_j - lin_j). The rank holding a pair (i, j) says
// j, and l from the pairs (j, l) of its own part (away from the cuts a rank
// holds all of them). Deeper, and across parts, the shares' near pairs
// (room below kNearRooms xi, gathered with the tight ones) carry the same
// rule on every share: l is a candidate of s when a near pair (j, l) has j a
// candidate of s and room(j, l) < 2 (reach_j - lin_j), to the closure
// (routes). A floe joining beyond that (through a pair of another part
// that is not near, a jam of free floes brought in whole) is not held:
// missing_pairs, and the advance is redone whole, the serial path.
std::vector<JoinCandidate> Stepper::candidates() const {
  std::vector<JoinCandidate> out;
  if (!holds_part()) return out;
  auto free_dynamic = [&](std::uint32_t j) { return !floes_.is_static[j] && cluster_of_[j] == kFree; };
  for (std::uint32_t p = 0; p < det_->pairs.size(); ++p) {
    const NearPair& q = det_->pairs[p];
    for (const auto& [i, j] : {std::pair{q.a, q.b}, std::pair{q.b, q.a}}) {
      const int r = runner(i);
      if (r < 0 || !free_dynamic(j)) continue;
      out.push_back({j, r});
      const double left = det_->reach[j] - lin_[j];
      for (const std::uint32_t pl : pairs_of(j)) {
        const std::uint32_t l = other(pl, j);
        if (free_dynamic(l) && room_[pl] < 2.0 * left) out.push_back({l, r});
      }
    }
  }
  sort_unique(out);
  return out;
}

std::vector<std::pair<int, std::uint32_t>> Stepper::routes(std::span<const JoinCandidate> candidates) {
  std::vector<std::pair<int, std::uint32_t>> out;
  if (!holds_part()) return out;
  const std::size_t n = floes_.size();
  // The closure over the near pairs (every share's, the same on every
  // share), from the candidates gathered: a set, so the same whatever the
  // order.
  std::vector<JoinCandidate> all(candidates.begin(), candidates.end());
  {
    // Per floe, its near pairs (indices into tight_).
    const CompressedRows<std::uint32_t> near =
        compressed_rows<std::uint32_t>(n, tight_.size(), [&](std::size_t t, auto&& put) {
          put(tight_[t].a, static_cast<std::uint32_t>(t));
          put(tight_[t].b, static_cast<std::uint32_t>(t));
        });
    // Per floe with a near pair, its reach less its travel as the pair's
    // share gave it (every share the same numbers, whatever floes it holds).
    std::vector<double> left_of(n, kInf);
    for (const PairRoom& q : tight_) {
      left_of[q.a] = q.left_a;
      left_of[q.b] = q.left_b;
    }
    sort_unique(all);
    std::vector<JoinCandidate> grow = all;
    while (!grow.empty()) {
      std::vector<JoinCandidate> next;
      for (const JoinCandidate& c : grow) {
        const double left = left_of[c.floe];
        for (const std::uint32_t t : near.row(c.floe)) {
          const PairRoom& q = tight_[t];
          const std::uint32_t l = q.a == c.floe ? q.b : q.a;
          if (floes_.is_static[l] || cluster_of_[l] != kFree || !(q.room < 2.0 * left)) continue;
          const JoinCandidate d{l, c.rank};
          if (!std::binary_search(all.begin(), all.end(), d)) next.push_back(d);
        }
      }
      sort_unique(next);
      const std::size_t old = all.size();
      all.insert(all.end(), next.begin(), next.end());
      std::inplace_merge(all.begin(), all.begin() + static_cast<std::ptrdiff_t>(old), all.end());
      grow = std::move(next);
    }
  }
  // Per floe, the shares it is a candidate of; with its cluster's runner,
  // the shares that must hold every pair of it.
  const CompressedRows<int> to = compressed_rows<int>(n, all.size(), [&](std::size_t k, auto&& put) {
    put(all[k].floe, all[k].rank);
  });
  held_floe_.assign(n, 0);
  for (std::uint32_t i = 0; i < n; ++i) {
    held_floe_[i] = runner(i) == share_->rank;
    for (const int r : to.row(i)) held_floe_[i] = held_floe_[i] || r == share_->rank;
  }
  std::vector<int> ranks;
  for (std::uint32_t p = 0; p < det_->pairs.size(); ++p) {
    const NearPair& q = det_->pairs[p];
    ranks.clear();
    for (const std::uint32_t i : {q.a, q.b}) {
      ranks.push_back(runner(i));
      const std::span<const int> shares = to.row(i);
      ranks.insert(ranks.end(), shares.begin(), shares.end());
    }
    std::sort(ranks.begin(), ranks.end());
    ranks.erase(std::unique(ranks.begin(), ranks.end()), ranks.end());
    for (const int r : ranks)
      if (r >= 0 && r != share_->rank) out.push_back({r, p});
  }
  std::sort(out.begin(), out.end());
  return out;
}

void Stepper::hold(Detection held) {
  if (!holds_part()) return;  // the pair list was rebuilt whole
  std::vector<double> room(held.pairs.size(), kInf);
  std::vector<std::uint8_t> known(held.pairs.size(), 0);
  for (std::size_t p = 0; p < held.pairs.size(); ++p) {
    const std::size_t was = find_pair(held.pairs[p]);
    if (was < det_->pairs.size() && known_[was]) {
      room[p] = room_[was];
      known[p] = 1;
    }
  }
  held_ = std::move(held);
  det_ = &held_;
  // The held pairs' floes as the caller holds them now (the routed ones
  // arrived with their pairs, after set_up): their straight paths and
  // travel. Nothing has moved yet, so floes_.state is the step's start.
  for (const NearPair& q : held_.pairs)
    for (const std::uint32_t i : {q.a, q.b}) {
      start_[i] = floes_.state[i];
      if (!floes_.is_static[i]) lin_[i] = travel(i);
    }
  add_floes(held_floes_, held_.pairs);
  room_ = std::move(room);
  known_ = std::move(known);
  build_pair_index();
  for (const PairRoom& t : tight_)
    if (const std::size_t p = find_pair(t); p < det_->pairs.size() && !known_[p]) {
      room_[p] = t.room;
      known_[p] = 1;
    }
}

void Stepper::run_share() {
  const std::size_t n = floes_.size();
  reach_left_.assign(n, kInf);
  budget_.assign(n, kInf);
  outran_.assign(n, 0);
  // On a part, the floes the share holds only (for_held): a member's pairs
  // are all held, so are its obstacles, and the free floes it moves are its
  // own and its pairs' (the caller keeps the others).
  for_held([&](std::uint32_t i) {
    if (!floes_.is_static[i]) reach_left_[i] = det_->reach[i] - lin_[i];
  });
  if (clusters_.empty()) {
    for_held([&](std::uint32_t i) {
      if (!floes_.is_static[i]) floes_.state[i] = linear(i, dt_);
    });
    return;
  }
  // The clusters this call runs: a share's, those whose lowest floe
  // (members.front()) it owns, as the edges carried its owner (runner).
  // Posed: the obstacles (they never move) and these clusters' members
  // (posed again before each measure); a measure reads no other floe
  // (internal pairs: members with members and with obstacles).
  own_.assign(clusters_.size(), 1);
  std::vector<std::uint32_t> posed;
  for_held([&](std::uint32_t i) {
    if (floes_.is_static[i]) posed.push_back(i);
  });
  for (std::size_t k = 0; k < clusters_.size(); ++k) {
    const Cluster& c = clusters_[k];
    if (share_) own_[k] = edge_owner_[c.members.front()] == share_->rank;
    if (own_[k]) posed.insert(posed.end(), c.members.begin(), c.members.end());
  }
  posed_ = PosedShapes(floes_, shapes_, posed);
  moving_ = true;
  // Free floes go to the end of the step now: nobody reads them before, and
  // a floe that joins a cluster is put back on its straight path.
  for_held([&](std::uint32_t i) {
    if (!floes_.is_static[i] && cluster_of_[i] == kFree) floes_.state[i] = linear(i, dt_);
  });
  // Time order: a min-heap of (tau, cluster); stale entries are skipped.
  using Entry = std::pair<double, int>;
  std::priority_queue<Entry, std::vector<Entry>, std::greater<Entry>> queue;
  for (std::size_t k = 0; k < clusters_.size(); ++k) {
    Cluster& c = clusters_[k];
    if (!own_[k]) continue;
    compute_budgets(static_cast<int>(k));
    collect_internal(static_cast<int>(k));
    measure_internal(c);
    snapshot(c);
    queue.push({0.0, static_cast<int>(k)});
  }
  while (!queue.empty()) {
    const auto [tau, k] = queue.top();
    queue.pop();
    Cluster& c = clusters_[static_cast<std::size_t>(k)];
    if (!c.alive || tau != c.tau || !(c.tau < dt_)) continue;
    // A share's solves of this pop get its key (RecordPart, impulse.hpp).
    ImpulseRecord* const record = opt_.impulse.record;
    const std::uint32_t events = record ? record->events : 0;
    advance_cluster(k);
    if (share_ && record) events_.insert(events_.end(), record->events - events, EventPlace{tau, k});
    if (conflict_ != ShareOutcome::Conflict::none) return;
    if (c.alive && c.tau < dt_) queue.push({c.tau, k});
  }
  for (std::size_t k = 0; k < clusters_.size(); ++k)
    if (const Cluster& c = clusters_[k]; c.alive && own_[k]) {
      ++report_.clusters;
      report_.largest_cluster = std::max(report_.largest_cluster, static_cast<long>(c.members.size()));
    }
}

void Stepper::rebuild_pairs() {
  DetectionOptions o;
  o.collision_distance = opt_.collision_distance;
  o.domain = opt_.domain;
  o.reach = det_->reach;
  o.horizon = dt_;
  for (std::size_t i = 0; i < o.reach.size(); ++i) o.reach[i] = std::max(o.reach[i], 1.5 * lin_[i]);
  rebuilt_ = detect(floes_, shapes_, o);
  det_ = &rebuilt_;
  ++report_.rebuilt;
}

void Stepper::build_pair_index() {
  pairs_by_floe_ = compressed_rows<std::uint32_t>(floes_.size(), det_->pairs.size(), [&](std::size_t p, auto&& put) {
    put(det_->pairs[p].a, static_cast<std::uint32_t>(p));
    put(det_->pairs[p].b, static_cast<std::uint32_t>(p));
  });
  stamp_.assign(det_->pairs.size(), 0);
}

void Stepper::make_clusters() {
  const std::size_t n = floes_.size();
  sets_ = DisjointSets(n);
  hot_.assign(n, 0);
  const double tight = opt_.collision_distance;
  for (const PairRoom& q : tight_) {
    if (!(q.room < tight)) continue;  // a near pair (on a part), not a tight one
    const bool da = !floes_.is_static[q.a], db = !floes_.is_static[q.b];
    if (q.room < 0.0) {
      if (da) hot_[q.a] = 1;
      if (db) hot_[q.b] = 1;
    }
    if (da && db) sets_.join(q.a, q.b);
  }
  // A jam (a contact component of jam.floes floes or more, impulse.hpp)
  // joins a cluster whole: its floes would come in one by one anyway, each
  // time with an LCP of the part that came in so far.
  find_jams();
  for (std::uint32_t i = 0; i < n; ++i)
    if (jam_of_[i] >= 0) sets_.join(i, jams_[static_cast<std::size_t>(jam_of_[i])].front());
  // A jam whose LCP was not solved at the start of the step (jam.hpp,
  // at_step_start) is time-stepped whatever its rooms: its time step is
  // where its contacts are resolved.
  if (!opt_.impulse.jam.at_step_start)
    for (std::uint32_t i = 0; i < n; ++i)
      if (jam_of_[i] >= 0) hot_[i] = 1;
  // A cluster of jam.floes floes or more takes time steps, whose LCP turns
  // and speeds up its floes: their deviations from the straight paths
  // outgrow small budgets. The dynamic floes close to such a cluster (room
  // below jam.pad xi) join it now rather than during its time step, where
  // each join reruns its LCP.
  std::vector<std::uint32_t> size(n, 0), hot_root(n, 0);
  for (std::uint32_t i = 0; i < n; ++i)
    if (!floes_.is_static[i]) {
      ++size[sets_.find(i)];
      if (hot_[i]) hot_root[sets_.find(i)] = 1;
    }
  big_.assign(n, 0);
  for (std::uint32_t i = 0; i < n; ++i) {
    const std::uint32_t r = sets_.find(i);
    big_[i] = !floes_.is_static[i] && hot_root[r] && size[r] >= opt_.impulse.jam.floes;
  }
  // On a part the pads' pairs are spread over the shares (each pair in one
  // part): every share finds the same big clusters, so all wait alike for
  // the caller's exchange of the pad edges (pad_edges, apply_pads).
  if (std::find(big_.begin(), big_.end(), 1) == big_.end()) return form_clusters();
  if (holds_part()) {
    pads_pending_ = true;
    return;
  }
  apply_pads(pad_edges());
}

std::vector<ContactEdge> Stepper::pad_edges() {
  // The pairs of the big clusters' floes between dynamic floes with a room
  // below jam.pad xi; on a part, those of the part (each rank the rooms of
  // its own pairs: the same bits on any).
  std::vector<ContactEdge> out;
  const double pad = opt_.impulse.jam.pad * opt_.collision_distance;
  for (std::uint32_t i = 0; i < floes_.size(); ++i) {
    if (!big_[i]) continue;
    for (const std::uint32_t p : pairs_of(i)) {
      const NearPair& q = det_->pairs[p];
      if (floes_.is_static[q.a] || floes_.is_static[q.b] || !(room(p) < pad)) continue;
      const auto [oa, ob] = owners(q);
      out.push_back({q.a, q.b, oa, ob});
    }
  }
  return out;
}

void Stepper::apply_pads(std::span<const ContactEdge> pads) {
  // Joins and flags are the same in any order (the components and the hot
  // floes do not depend on it), and an edge given twice changes nothing:
  // every share's edges, concatenated, give the serial clusters.
  take_owners(pads);
  for (const ContactEdge& e : pads) {
    hot_[e.a] = hot_[e.a] || big_[e.a];
    hot_[e.b] = hot_[e.b] || big_[e.b];
    sets_.join(e.a, e.b);
  }
  pads_pending_ = false;
  form_clusters();
}

void Stepper::form_clusters() {
  const std::size_t n = floes_.size();
  std::vector<std::uint8_t> active_root(n, 0);
  for (std::uint32_t i = 0; i < n; ++i)
    if (hot_[i]) active_root[sets_.find(i)] = 1;
  cluster_of_.assign(n, kFree);
  std::vector<int> of_root(n, kFree);
  for (std::uint32_t i = 0; i < n; ++i) {
    if (floes_.is_static[i] || !active_root[sets_.find(i)]) continue;
    const std::uint32_t r = sets_.find(i);
    if (of_root[r] == kFree) {
      of_root[r] = static_cast<int>(clusters_.size());
      clusters_.emplace_back();
    }
    cluster_of_[i] = of_root[r];
    clusters_[static_cast<std::size_t>(of_root[r])].members.push_back(i);
  }
  // A cluster's floes are joined by tight pairs, contact edges or pads, or
  // it is one floe hot through a tight pair: its lowest floe is an end of
  // an edge, whose owner the edge carried (runner, run_share).
  for ([[maybe_unused]] const Cluster& c : clusters_) FLOESIM_ASSERT(!share_ || edge_owner_[c.members.front()] >= 0);
}

void Stepper::find_jams() {
  const std::size_t n = floes_.size();
  DisjointSets sets(n);
  auto find = [&](std::uint32_t i) { return sets.find(i); };
  for (const ContactEdge& e : touching_) sets.join(e.a, e.b);
  std::vector<std::uint32_t> size(n, 0);
  for (std::uint32_t i = 0; i < n; ++i)
    if (!floes_.is_static[i]) ++size[find(i)];
  jam_of_.assign(n, -1);
  std::vector<int> of_root(n, -1);
  for (std::uint32_t i = 0; i < n; ++i) {
    const std::uint32_t r = find(i);
    if (floes_.is_static[i] || size[r] < opt_.impulse.jam.floes) continue;
    if (of_root[r] < 0) {
      of_root[r] = static_cast<int>(jams_.size());
      jams_.emplace_back();
    }
    jam_of_[i] = of_root[r];
    jams_[static_cast<std::size_t>(of_root[r])].push_back(i);
  }
}

void Stepper::compute_budgets(int k) {
  for (std::uint32_t i : clusters_[static_cast<std::size_t>(k)].members) {
    double b = kInf;
    for (std::uint32_t p : pairs_of(i)) {
      const std::uint32_t j = other(p, i);
      if (floes_.is_static[j] || cluster_of_[j] == k) continue;
      b = std::min(b, 0.5 * room(p));
    }
    budget_[i] = b;
  }
}

void Stepper::collect_internal(int k) {
  Cluster& c = clusters_[static_cast<std::size_t>(k)];
  c.internal.clear();
  ++epoch_;
  for (std::uint32_t i : c.members)
    for (std::uint32_t p : pairs_of(i)) {
      if (stamp_[p] == epoch_) continue;
      const std::uint32_t j = other(p, i);
      if (!floes_.is_static[j] && cluster_of_[j] != k) continue;
      stamp_[p] = epoch_;
      c.internal.push_back(p);
    }
}

bool Stepper::measure(const Cluster& c, Measured& m) const {
  m.pairs.clear();
  m.contacts.clear();
  m.witnesses.clear();
  bool overlap = false;
  for (std::uint32_t p : c.internal) {
    const NearPair& q = det_->pairs[p];
    const double range = exact_range(floes_, shapes_, q.a, q.b, dt_, opt_.collision_distance);
    m.pairs.push_back(measure_pair(posed_, q.a, q.b, q.shift, opt_.collision_distance, range, m.contacts, m.witnesses));
    overlap = overlap || m.pairs.back().overlap;
  }
  return overlap;
}

void Stepper::measure_internal(Cluster& c) {
  for (std::uint32_t i : c.members) posed_.update(floes_, i);
  measure(c, c.cur);
}

void Stepper::advance_cluster(int k) {
  Cluster& c = clusters_[static_cast<std::size_t>(k)];
  if (c.members.size() >= opt_.impulse.jam.floes && !c.events_only) {
    time_step(k);
    return;
  }
  const double xi = opt_.collision_distance;
  double limit = kInf;
  const NearPair* by = nullptr;
  for (const NearPair& q : c.cur.pairs) {
    const double l = pair_step_limit(floes_, shapes_, q, witnesses_of(q, c.cur.witnesses), xi);
    if (l < limit) {
      limit = l;
      by = &q;
    }
  }
  double h = std::min(limit, dt_ - c.tau);
  if (h < opt_.floor && dt_ - c.tau > opt_.floor) {
    h = opt_.floor;
    ++report_.floor_steps;
    floor_tau_ = c.tau;
    floor_cluster_ = k;
    std::ostringstream m;
    m << "floes " << by->a << " and " << by->b << " at distance " << by->distance << " m, " << c.tau
      << " s into the step";
    report_.floor_pair = m.str();
  }
  snapshot(c);
  for (;;) {
    const bool last = h >= dt_ - c.tau;
    const double t1 = last ? dt_ : c.tau + h;
    for (std::size_t m = 0; m < c.members.size(); ++m) {
      floes_.state[c.members[m]] = drifted(c.snap[m], h);
    }
    // Budgets: the pairs with floes outside that this sub-step would break
    // bring those floes in, at the cluster's time.
    joining_.clear();
    merging_.clear();
    collect_breaks(k, t1);
    if (!joining_.empty() || !merging_.empty()) {
      restore(c);
      bring_in(k);
      return;
    }
    for (std::uint32_t i : c.members) posed_.update(floes_, i);
    if (!measure(c, next_)) {
      c.tau = t1;
      std::swap(c.cur, next_);
      ++report_.substeps;
      // Collisions at the end of the sub-step (at the end of the step they
      // are left to the next step, which starts with them).
      if (c.tau < dt_ && !c.cur.contacts.empty()) collide(c.cur.contacts);
      return;
    }
    // Overlap: redo with half the length.
    ++report_.rejected;
    restore(c);
    h *= 0.5;
    if (h < kHalvingFloor * opt_.floor) {
      const NearPair* bad = nullptr;
      for (const NearPair& q : next_.pairs)
        if (q.overlap) bad = &q;
      std::ostringstream m;
      m << "floes " << bad->a << " and " << bad->b << " overlap however short the sub-step, " << c.tau
        << " s into the step";
      throw RunError(m.str());
    }
  }
}

void Stepper::collect_breaks(int k, double t1) {
  for (std::uint32_t i : clusters_[static_cast<std::size_t>(k)].members) {
    const double dev = deviation(i, t1);
    if (dev > reach_left_[i] && !outran_[i]) {
      outran_[i] = 1;
      ++report_.reach_exceeded;
    }
    if (!(dev > budget_[i])) continue;
    for (std::uint32_t p : pairs_of(i)) {
      const std::uint32_t j = other(p, i);
      if (floes_.is_static[j] || cluster_of_[j] == k || !(0.5 * room(p) < dev)) continue;
      if (cluster_of_[j] == kFree) joining_.push_back(j);
      else merging_.push_back(cluster_of_[j]);
    }
  }
}

void Stepper::bring_in(int k) {
  Cluster& c = clusters_[static_cast<std::size_t>(k)];
  // A jam comes in whole (make_clusters).
  for (std::size_t m = 0, n = joining_.size(); m < n; ++m) {
    const int jam = jam_of_[joining_[m]];
    if (jam < 0) continue;
    for (std::uint32_t f : jams_[static_cast<std::size_t>(jam)]) {
      if (cluster_of_[f] == kFree) joining_.push_back(f);
      else if (cluster_of_[f] != k) merging_.push_back(cluster_of_[f]);
    }
  }
  // On a part, a free floe that is not one of the share's candidates
  // (Stepper::candidates) has pairs the share may not hold: it stops.
  if (holds_part())
    for (const std::uint32_t j : joining_)
      if (!held_floe_[j]) {
        conflict_ = ShareOutcome::Conflict::missing_pairs;
        return;
      }
  // A share stops at a cluster it does not run: the serial advance merges
  // the two at a time the share cannot know.
  for (int l : merging_)
    if (!own_[static_cast<std::size_t>(l)]) {
      conflict_ = ShareOutcome::Conflict::foreign_cluster;
      return;
    }
  std::sort(joining_.begin(), joining_.end());
  joining_.erase(std::unique(joining_.begin(), joining_.end()), joining_.end());
  for (std::uint32_t j : joining_) {
    cluster_of_[j] = k;
    c.members.push_back(j);
    floes_.state[j] = linear(j, c.tau);
    ++report_.joined;
  }
  std::sort(merging_.begin(), merging_.end());
  merging_.erase(std::unique(merging_.begin(), merging_.end()), merging_.end());
  for (int l : merging_) {
    Cluster& o = clusters_[static_cast<std::size_t>(l)];
    const double since = c.tau - o.tau_snap;  // >= 0 by the time order
    for (std::size_t m = 0; m < o.members.size(); ++m) {
      floes_.state[o.members[m]] = drifted(o.snap[m], since);
      cluster_of_[o.members[m]] = k;
      c.members.push_back(o.members[m]);
    }
    o.members.clear();
    o.alive = false;
    ++report_.merges;
  }
  compute_budgets(k);
  collect_internal(k);
  measure_internal(c);
  if (!c.cur.contacts.empty()) collide(c.cur.contacts);
  snapshot(c);
}

}  // namespace detail

void advance_with_collisions(Floes& floes, const CollisionShapes& shapes, const Detection& detection, double dt,
                             const SubstepOptions& options, CollisionStats& stats, SubstepReport& report) {
  detail::Stepper(floes, shapes, detection, dt, options, stats, report).run();
}

ShareAdvance::ShareAdvance(Floes& floes, const CollisionShapes& shapes, const Detection& detection, double dt,
                           const SubstepOptions& options, const ClusterShare& share, bool on_part,
                           std::span<const std::uint32_t> mine)
    : options_(options), share_(share) {
  // The warm store is replaced by an empty probe that only says whether a
  // solve of the share would have used it (ClusterShare above). A failure's
  // dump is left to the whole advance that follows it, which numbers it in
  // the run's count (the share's count starts at zero and would overwrite
  // the run's first dumps).
  if (options.impulse.warm) options_.impulse.warm = &probe_;
  options_.impulse.dump_failed_lcps.clear();
  stepper_ =
      std::make_unique<detail::Stepper>(floes, shapes, detection, dt, options_, stats_, report_, &share_, on_part, mine);
}

ShareAdvance::~ShareAdvance() = default;

ShareRooms ShareAdvance::rooms() {
  ShareRooms out;
  try {
    out = stepper_->set_up();
  } catch (const RunError&) {
    out.conflict = ShareOutcome::Conflict::error;
  }
  set_up_ = out.conflict;
  return out;
}

ShareRooms ShareAdvance::rooms_rebuilt() {
  ShareRooms out;
  out.conflict = set_up_;
  if (set_up_ != ShareOutcome::Conflict::none) return out;
  try {
    out = stepper_->set_up_rebuilt();
  } catch (const RunError&) {
    out.conflict = ShareOutcome::Conflict::error;
  }
  set_up_ = out.conflict;
  return out;
}

std::span<const std::uint32_t> ShareAdvance::held() const { return stepper_->held_floes(); }

ShareOutcome ShareAdvance::advance(const ShareRooms& all) {
  if (set_up_ == ShareOutcome::Conflict::none) {
    try {
      stepper_->clusters(all.tight, all.touching);
      set_up_ = stepper_->conflict();
    } catch (const RunError&) {
      set_up_ = ShareOutcome::Conflict::error;
    }
  }
  return advance();
}

ShareAdvance::Routes ShareAdvance::clusters(const ShareRooms& all) {
  Routes out;
  if (set_up_ == ShareOutcome::Conflict::none) {
    try {
      stepper_->clusters(all.tight, all.touching);
      set_up_ = stepper_->conflict();
      out.pads = stepper_->pads_pending();
      if (set_up_ == ShareOutcome::Conflict::none && !out.pads) out.candidates = stepper_->candidates();
      out.any_cluster = stepper_->any_cluster();
    } catch (const RunError&) {
      set_up_ = ShareOutcome::Conflict::error;
    }
  }
  out.conflict = set_up_;
  return out;
}

std::vector<ContactEdge> ShareAdvance::pad_edges() {
  if (set_up_ != ShareOutcome::Conflict::none) return {};
  return stepper_->pad_edges();
}

ShareAdvance::Routes ShareAdvance::pads(std::span<const ContactEdge> edges) {
  Routes out;
  if (set_up_ == ShareOutcome::Conflict::none) {
    stepper_->apply_pads(edges);
    out.candidates = stepper_->candidates();
    out.any_cluster = stepper_->any_cluster();
  }
  out.conflict = set_up_;
  return out;
}

std::vector<std::pair<int, std::uint32_t>> ShareAdvance::routes(std::span<const JoinCandidate> candidates) {
  if (set_up_ != ShareOutcome::Conflict::none) return {};
  return stepper_->routes(candidates);
}

void ShareAdvance::hold(Detection held) {
  if (set_up_ == ShareOutcome::Conflict::none) stepper_->hold(std::move(held));
}

ShareOutcome ShareAdvance::advance() {
  ShareOutcome outcome;
  outcome.conflict = set_up_;
  if (outcome.conflict != ShareOutcome::Conflict::none) return outcome;
  try {
    stepper_->run_share();
    outcome = stepper_->outcome();
  } catch (const RunError&) {
    outcome.conflict = ShareOutcome::Conflict::error;
  }
  if (outcome.conflict == ShareOutcome::Conflict::none && probe_.uses > 0)
    outcome.conflict = ShareOutcome::Conflict::warm_start;
  if (outcome.conflict == ShareOutcome::Conflict::none && stats_.failures > 0)
    outcome.conflict = ShareOutcome::Conflict::failed_lcp;
  return outcome;
}

}  // namespace floesim::contact
