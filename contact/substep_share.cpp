// One share of the multirate advance (contact/substep.hpp, ShareAdvance):
// on a part of the detection, the free floes a cluster may take in (join
// candidates), the pairs to route to the clusters' runners and the pairs
// the share then holds; and ShareAdvance's calls around the caller's
// exchanges, each a conflict rather than an exception when it fails.
#include "contact/substep.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

#include "contact/substep_stepper.hpp"
#include "core/error.hpp"

namespace floesim::contact {

namespace detail {

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

bool Stepper::whole(std::uint32_t i) const {
  const FloeState& s = floes_.state[i];
  bool finite = std::isfinite(s.x) && std::isfinite(s.y) && std::isfinite(s.yaw) && std::isfinite(s.vx) &&
                std::isfinite(s.vy) && std::isfinite(s.yaw_rate) && std::isfinite(shapes_.radius[i]) &&
                std::isfinite(det_->reach[i]) && (floes_.is_static[i] || std::isfinite(floes_.mass[i])) &&
                shapes_.has(i);  // a shape held by band: none where the rank neither holds it nor was sent it
  for (std::size_t p = shapes_.parts_begin(i); finite && p < shapes_.parts_end(i); ++p)
    for (const Vec2& v : shapes_.part(p)) finite = finite && std::isfinite(v.x()) && std::isfinite(v.y());
  return finite;
}

long Stepper::hold(Detection held) {
  if (!holds_part()) return -1;  // the pair list was rebuilt whole
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
  // The floes the routed pairs brought in: each must have come whole.
  long missing = -1;
  std::vector<std::uint32_t> routed;
  add_floes(routed, held_.pairs);
  for (const std::uint32_t i : routed)
    if (missing < 0 && !std::binary_search(held_floes_.begin(), held_floes_.end(), i) && !whole(i))
      missing = i;
  add_floes(held_floes_, held_.pairs);
  room_ = std::move(room);
  known_ = std::move(known);
  build_pair_index();
  for (const PairRoom& t : tight_)
    if (const std::size_t p = find_pair(t); p < det_->pairs.size() && !known_[p]) {
      room_[p] = t.room;
      known_[p] = 1;
    }
  return missing;
}


}  // namespace detail

ShareAdvance::ShareAdvance(Floes& floes, const CollisionShapes& shapes, const Detection& detection, double dt,
                           const SubstepOptions& options, const ClusterShare& share, bool on_part,
                           std::span<const std::uint32_t> mine)
    : options_(options), share_(share) {
  // The warm store: a copy of the caller's (the step's start, the same on
  // every rank), logging the pairs the share stores (substep.hpp: the
  // pairs of one cluster's solves are no other cluster's). A failure's
  // dump is left to the whole advance that follows it, which numbers it in
  // the run's count (the share's count starts at zero and would overwrite
  // the run's first dumps).
  if (options.impulse.warm) {
    warm_ = options.impulse.warm->share_copy();
    options_.impulse.warm = &warm_;
  }
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

ShareRooms ShareAdvance::rooms_rebuilt(std::span<const double> reach) {
  ShareRooms out;
  out.conflict = set_up_;
  if (set_up_ != ShareOutcome::Conflict::none) return out;
  try {
    out = stepper_->set_up_rebuilt(reach);
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

int ShareAdvance::runner_of_cluster(std::int32_t k) const { return stepper_->cluster_runner(static_cast<std::size_t>(k)); }

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
  if (set_up_ != ShareOutcome::Conflict::none) return;
  missing_ = stepper_->hold(std::move(held));
  if (missing_ >= 0) set_up_ = ShareOutcome::Conflict::missing_floe;
}

ShareOutcome ShareAdvance::advance() {
  ShareOutcome outcome;
  outcome.conflict = set_up_;
  if (outcome.conflict == ShareOutcome::Conflict::missing_floe)
    outcome.moved.push_back(static_cast<std::uint32_t>(missing_));
  if (outcome.conflict != ShareOutcome::Conflict::none) return outcome;
  try {
    stepper_->run_share();
    outcome = stepper_->outcome();
  } catch (const RunError&) {
    outcome.conflict = ShareOutcome::Conflict::error;
  }
  if (outcome.conflict == ShareOutcome::Conflict::none && stats_.failures > 0)
    outcome.conflict = ShareOutcome::Conflict::failed_lcp;
  if (outcome.conflict == ShareOutcome::Conflict::none && options_.impulse.warm) {
    outcome.warm = warm_.written_pairs();
    outcome.warm_uses = warm_.uses;
  }
  return outcome;
}


}  // namespace floesim::contact
