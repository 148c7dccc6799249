// The multirate advance's cluster events (contact/substep.hpp, steps 2 and
// 3): a share's run of its clusters in time order, each event a sub-step
// (limit, move, measure, collide) or floes joining at the cluster's time
// (budgets, breaks, joins and merges); and advance_with_collisions, the
// serial call. The set-up (paths, rooms, clusters) is substep_setup.cpp,
// the share on a part substep_share.cpp, the jams' time steps
// substep_jam.cpp.
#include "contact/substep.hpp"

#include <algorithm>
#include <queue>
#include <sstream>

#include "contact/step_limit.hpp"
#include "contact/substep_stepper.hpp"
#include "core/error.hpp"

namespace floesim::contact {

namespace detail {

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
      met_.emplace_back(k, l);
    }
  if (conflict_ != ShareOutcome::Conflict::none) return;
  std::sort(joining_.begin(), joining_.end());
  joining_.erase(std::unique(joining_.begin(), joining_.end()), joining_.end());
  for (std::uint32_t j : joining_) {
    cluster_of_[j] = k;
    c.members.push_back(j);
    floes_.state[j] = linear(j, c.tau);
    ++report_.joined;
    if (share_) taken_.emplace_back(static_cast<std::int32_t>(j), k);
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
    if (share_) merged_.emplace_back(l, k);
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


}  // namespace floesim::contact
