// The multirate advance's set-up (contact/substep.hpp, step 1, item 4 and
// "The set-up by share"): the straight paths, the pair list (rebuilt when
// a floe would outrun its reach) and its index, the rooms a call computes,
// and the clusters from every share's tight pairs and contact edges (the
// jams, the pads of jam-sized clusters).
#include <algorithm>
#include <vector>

#include "contact/substep_stepper.hpp"
#include "core/error.hpp"

namespace floesim::contact::detail {

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
  if (outrun) rebuild_pairs(det_->reach);
  return set_up_rooms();
}

ShareRooms Stepper::set_up_rebuilt(std::span<const double> reach) {
  // As the serial set-up whose check found a floe outrunning: every floe.
  const std::size_t n = floes_.size();
  start_ = floes_.state;
  lin_.assign(n, 0.0);
  for (std::size_t i = 0; i < n; ++i)
    if (!floes_.is_static[i]) lin_[i] = travel(i);
  rebuild_pairs(reach);
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

void Stepper::rebuild_pairs(std::span<const double> reach) {
  DetectionOptions o;
  o.collision_distance = opt_.collision_distance;
  o.domain = opt_.domain;
  o.reach.assign(reach.begin(), reach.end());
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
  // The clusters the caller gave another runner (ClusterShare::runners):
  // runner() and run_share read the lowest floe's entry.
  if (share_)
    for (const auto& [k, r] : share_->runners) {
      FLOESIM_ASSERT(k >= 0 && static_cast<std::size_t>(k) < clusters_.size());
      edge_owner_[clusters_[static_cast<std::size_t>(k)].members.front()] = r;
    }
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


}  // namespace floesim::contact::detail
