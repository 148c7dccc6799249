// The conflicting clusters on one rank (JoinedClusters,
// parallel/advance_share.hpp): a union-find over the clusters that a tried
// step's parts said met or took one free floe, and the runner of each group.
#include "parallel/advance_share.hpp"

#include <algorithm>

namespace floesim::parallel {

using contact::ShareOutcome;

bool JoinedClusters::add(std::span<const AdvancePart> parts, const contact::ShareAdvance& share) {
  bool any = false;
  std::map<std::uint32_t, std::int32_t> taker;  // a moved floe's cluster, over the parts without a conflict
  for (const AdvancePart& p : parts) {
    const ShareOutcome::Conflict c = p.outcome.conflict;
    if (c != ShareOutcome::Conflict::none && c != ShareOutcome::Conflict::foreign_cluster) return false;
    for (const auto& [a, b] : p.outcome.merged) unite(a, b);
    for (const auto& [a, b] : p.outcome.met) {
      unite(a, b);
      joined_.insert(a);
      any = true;
    }
    if (c != ShareOutcome::Conflict::none) continue;
    // A floe two parts moved was free at the step's start (the clusters are
    // the same on every rank) and taken in by a cluster of each.
    for (const auto& [floe, k] : p.outcome.taken) {
      const auto [it, fresh] = taker.emplace(static_cast<std::uint32_t>(floe), k);
      if (fresh) continue;
      unite(it->second, k);
      joined_.insert(it->second);
      any = true;
    }
  }
  if (!any) return false;
  // Each group with a joined cluster: all its clusters to the runner of
  // its lowest (as this try ran it: every rank the same).
  std::map<std::int32_t, std::int32_t> lowest;  // group (root) -> its lowest cluster
  for (const auto& [k, up] : parent_) {
    const std::int32_t r = find(k);
    const auto [it, fresh] = lowest.emplace(r, k);
    if (!fresh) it->second = std::min(it->second, k);
  }
  std::set<std::int32_t> groups;
  for (const std::int32_t k : joined_) groups.insert(find(k));
  runners_.clear();
  for (const auto& [k, up] : parent_)
    if (const std::int32_t r = find(k); groups.contains(r)) runners_.emplace_back(k, share.runner_of_cluster(lowest[r]));
  return true;
}

std::int32_t JoinedClusters::find(std::int32_t k) {
  auto it = parent_.emplace(k, k).first;
  while (it->second != it->first) {
    const auto up = parent_.find(it->second);
    it->second = up->second;  // halving
    it = up;
  }
  return it->first;
}

void JoinedClusters::unite(std::int32_t a, std::int32_t b) {
  const std::int32_t ra = find(a), rb = find(b);
  if (ra != rb) parent_[std::max(ra, rb)] = std::min(ra, rb);
}

}  // namespace floesim::parallel
