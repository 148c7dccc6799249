// The collisions at the start of a step (impulse.hpp: resolve_step_collisions
// and its share by owner, resolve_step_collisions_share).
#include <algorithm>
#include <cstdint>
#include <limits>
#include <span>
#include <utility>
#include <vector>

#include "contact/impulse.hpp"
#include "contact/impulse_detail.hpp"
#include "core/error.hpp"

namespace floesim::contact {

using detail::approach;
using detail::Components;

namespace {

// The speed the step's smooth forces gave the two floes' points (the larger
// of the two): |v_f(p)| of W^- minus that of the step's start, at the present
// positions.
double smooth_kick(const Floes& floes, std::span<const FloeState> start, std::span<const FloeState> w_minus,
                   std::uint32_t a, std::uint32_t b, const Vec2& pa, const Vec2& pb_own) {
  auto kick = [&](std::uint32_t f, const Vec2& p) {
    const Vec2 arm = p - Vec2{floes.state[f].x, floes.state[f].y};
    return (arm_velocity(w_minus[f], arm) - arm_velocity(start[f], arm)).norm();
  };
  return std::max(kick(a, pa), kick(b, pb_own));
}
// Made by the step (impulse.hpp): the contact approached at the start of the
// step no faster than rest_speed, or than a third of now, or than the step's
// smooth forces move either floe's point.
bool made_by_step(double now, double at_start, double kick, double rest_speed) {
  return at_start <= std::max({rest_speed, kick, now / 3.0});
}

// Per floe, 1 if it is in a jam: a component of at least `size` dynamic
// floes joined by `contacts`.
std::vector<std::uint8_t> jam_floes(const Floes& floes, const std::vector<ContactPoint>& contacts, std::size_t size) {
  const std::size_t n = floes.size();
  DisjointSets sets(n);
  std::vector<std::uint8_t> joined(n, 0), jam(n, 0);
  for (const ContactPoint& c : contacts)
    if (!floes.is_static[c.a] && !floes.is_static[c.b]) {
      sets.join(c.a, c.b);
      joined[c.a] = joined[c.b] = 1;
    }
  std::vector<std::uint32_t> count(n, 0);
  for (std::uint32_t f = 0; f < n; ++f)
    if (joined[f]) ++count[sets.find(f)];
  for (std::uint32_t f = 0; f < n; ++f) jam[f] = joined[f] && count[sets.find(f)] >= size;
  return jam;
}

// Whether witness w of the non-overlapping pair p becomes a speculative
// contact with the floes' present velocities (impulse.hpp, "Speculative
// contacts"): its points would close below xi/2 within the step, and the
// step made their approach (`start`: the step's start, `before`: W^-).
bool becomes_speculative(const Floes& floes, std::span<const FloeState> start, std::span<const FloeState> before,
                         const NearPair& p, const Witness& w, double step, double xi, double rest_speed) {
  const Vec2 pb = w.pb - p.shift;
  const double now = approach(floes, floes.state, p.a, p.b, w.pa, pb, w.normal);
  if (!(now * step > w.distance - 0.5 * xi)) return false;
  return made_by_step(now, approach(floes, start, p.a, p.b, w.pa, pb, w.normal),
                      smooth_kick(floes, start, before, p.a, p.b, w.pa, pb), rest_speed);
}

// The witnesses the rounds of resolve_step_collisions may take, listed once
// a step (pair and witness indices, in the detection's order): of the pairs
// that do not overlap, those at or beyond xi not taken already (a jam's).
struct Candidate {
  std::uint32_t pair, witness;
};
std::vector<Candidate> candidate_witnesses(const Detection& detection, const std::vector<std::uint8_t>& taken,
                                           double xi) {
  std::vector<Candidate> out;
  for (std::uint32_t i = 0; i < detection.pairs.size(); ++i) {
    const NearPair& p = detection.pairs[i];
    if (p.overlap) continue;
    for (std::uint32_t k = p.first_witness; k < p.first_witness + p.witness_count; ++k)
      if (!taken[k] && !(detection.witnesses[k].distance < xi)) out.push_back({i, k});
  }
  return out;
}
// visit(pair, witness, index) for the candidates not taken since.
template <class Visit>
void each_candidate(const Detection& detection, const std::vector<Candidate>& candidates,
                    const std::vector<std::uint8_t>& taken, Visit&& visit) {
  for (const Candidate& c : candidates)
    if (!taken[c.witness]) visit(detection.pairs[c.pair], detection.witnesses[c.witness], c.witness);
}

// resolve_step_collisions (impulse.hpp), of the whole step or, with `share`,
// of the share's step groups: the same rounds on the share's contacts and
// witnesses. With a share, `moved` receives the floes whose velocities it
// changed (ascending), `groups` the share's group count and `places` the
// places of the loads it recorded (options.record) in the whole call's list.
std::size_t step_collisions(Floes& floes, std::span<const FloeState> start, const Detection& detection, double step,
                            const ImpulseOptions& options, CollisionStats& stats,
                            std::vector<ContactImpulse>* impulses, const ClusterShare* share,
                            const StepGroups* step_groups, std::vector<std::uint32_t>* moved, long* groups,
                            std::vector<ContactPlace>* places) {
  const double xi = options.collision_distance;
  ImpulseOptions opt = options;
  opt.speculative_step = step;
  // The solves below may be redone from W^-: only the impulses finally
  // applied are recorded, at the end.
  ImpulseRecord* record = std::exchange(opt.record, nullptr);
  // Jams: contact components (dynamic floes joined by contact points) of at
  // least opt.jam.floes floes. Per floe, as every pair asks (an array, not
  // a hash of the contacts' floes: O(floes) a step, the lookups O(1)).
  // (A share is given them with its groups: its detection may be a part.)
  std::vector<std::uint8_t> whole_jam;
  if (!share) whole_jam = jam_floes(floes, detection.contacts, opt.jam.floes);
  auto in_jam = [&](std::uint32_t f) { return share ? step_groups->in_jam(f) : whole_jam[f] != 0; };
  auto jammed = [&](std::uint32_t a, std::uint32_t b) { return in_jam(a) || in_jam(b); };
  // The contacts solved here (a jam's are left to its time step unless
  // jam.at_step_start) and where each came from in detection.contacts.
  std::vector<ContactPoint> contacts;
  std::vector<std::size_t> from;
  // With a share's record: each contact's place in the whole call's list,
  // keyed by pair (ContactPlace, impulse.hpp), which the share's list keeps
  // in order.
  const bool placed = places && record;
  std::vector<ContactPlace> place;
  std::vector<std::uint32_t> pair_of;  // with places: per contact point, its pair
  if (placed) {
    pair_of.resize(detection.contacts.size());
    for (std::uint32_t i = 0; i < detection.pairs.size(); ++i) {
      const NearPair& p = detection.pairs[i];
      std::fill_n(pair_of.begin() + p.first_contact, p.contact_count, i);
    }
  }
  for (std::size_t k = 0; k < detection.contacts.size(); ++k) {
    const ContactPoint& c = detection.contacts[k];
    if (!opt.jam.at_step_start && jammed(c.a, c.b)) continue;
    contacts.push_back(c);
    from.push_back(k);
    if (placed) {
      const NearPair& p = detection.pairs[pair_of[k]];
      place.push_back(contact_place(0, p, static_cast<std::uint32_t>(k) - p.first_contact));
    }
  }
  std::size_t detected = contacts.size();
  // In a jam every point beyond xi is speculative from the start (or left,
  // with the jam's contacts, to its time step).
  std::vector<std::uint8_t> taken(detection.witnesses.size(), 0);
  for (std::uint32_t i = 0; i < detection.pairs.size(); ++i) {
    const NearPair& p = detection.pairs[i];
    if (p.overlap || !jammed(p.a, p.b)) continue;
    for (std::uint32_t k = p.first_witness; k < p.first_witness + p.witness_count; ++k) {
      const Witness& w = detection.witnesses[k];
      if (w.distance < xi) continue;
      taken[k] = 1;
      if (!opt.jam.at_step_start) continue;
      contacts.push_back({p.a, p.b, 0.5 * (w.pa + w.pb), w.normal, w.distance, p.shift, true, w.vertex_of_b});
      if (placed) place.push_back(contact_place(1, p, k - p.first_witness));
    }
  }
  std::vector<Candidate> candidates = candidate_witnesses(detection, taken, xi);
  // A share keeps the contacts and witnesses of its step groups only.
  auto kept = [&](std::uint32_t a, std::uint32_t b) {
    if (!share) return true;
    const bool da = !floes.is_static[a], db = !floes.is_static[b];
    return (da || db) && (!da || step_groups->mine(a, share->rank)) && (!db || step_groups->mine(b, share->rank));
  };
  if (share) {
    *groups = step_groups->count(share->rank);
    std::erase_if(candidates, [&](const Candidate& c) {
      return !kept(detection.pairs[c.pair].a, detection.pairs[c.pair].b);
    });
    std::size_t to = 0, kept_detected = 0;
    for (std::size_t k = 0; k < contacts.size(); ++k) {
      if (!kept(contacts[k].a, contacts[k].b)) continue;
      if (k < detected) from[kept_detected++] = from[k];
      if (placed) place[to] = place[k];
      contacts[to++] = contacts[k];
    }
    contacts.resize(to);
    if (placed) place.resize(to);
    from.resize(kept_detected);
    detected = kept_detected;
  }
  // Resting (restitution 0): a jam's contacts and speculative points, and
  // the contacts the step made (impulse.hpp).
  std::vector<std::uint8_t> resting(contacts.size(), 1);
  for (std::size_t k = 0; k < detected; ++k) {
    const ContactPoint& c = contacts[k];
    const Vec2 pb = c.point - c.shift;  // in b's own image
    resting[k] = jammed(c.a, c.b) || made_by_step(approach(floes, floes.state, c.a, c.b, c.point, pb, c.normal),
                                                  approach(floes, start, c.a, c.b, c.point, pb, c.normal),
                                                  smooth_kick(floes, start, floes.state, c.a, c.b, c.point, pb),
                                                  opt.rest_speed);
  }
  std::size_t added = contacts.size() - detected;  // a jam's speculative points
  const std::vector<FloeState> before = floes.state;  // W^-
  std::vector<ContactPoint> again;  // the contacts to solve again: components that gained speculative ones
  std::vector<std::uint8_t> again_resting;
  std::vector<std::size_t> again_index;  // their places in contacts
  std::vector<ContactImpulse> total = resolve_collisions(floes, contacts, opt, stats, resting);
  for (int round = 1; round <= 2; ++round) {
    // Pushed points beyond xi that would now close below xi/2 within the step.
    const std::size_t first_new = contacts.size();
    each_candidate(detection, candidates, taken, [&](const NearPair& p, const Witness& w, std::uint32_t k) {
      if (!kept(p.a, p.b) || !becomes_speculative(floes, start, before, p, w, step, xi, opt.rest_speed)) return;
      taken[k] = 1;
      contacts.push_back({p.a, p.b, 0.5 * (w.pa + w.pb), w.normal, w.distance, p.shift, true, w.vertex_of_b});
      if (placed) place.push_back(contact_place(static_cast<std::uint32_t>(1 + round), p, k - p.first_witness));
      resting.push_back(1);
      ++added;
    });
    if (contacts.size() == first_new) break;
    // The components (over all contacts) that gained speculative contacts are
    // solved again from W^-; the others keep their solution.
    Components comp;
    auto dynamic_end = [&](const ContactPoint& c) { return floes.is_static[c.a] ? c.b : c.a; };
    for (const ContactPoint& c : contacts) {
      if (floes.is_static[c.a] || floes.is_static[c.b]) comp.node(dynamic_end(c));
      else comp.join(comp.node(c.a), comp.node(c.b));
    }
    std::vector<std::uint8_t> redo(comp.size(), 0);
    for (std::size_t k = first_new; k < contacts.size(); ++k) redo[comp.root_of(dynamic_end(contacts[k]))] = 1;
    again.clear();
    again_resting.clear();
    again_index.clear();
    for (std::size_t k = 0; k < contacts.size(); ++k)
      if (redo[comp.root_of(dynamic_end(contacts[k]))]) {
        again.push_back(contacts[k]);
        again_resting.push_back(resting[k]);
        again_index.push_back(k);
      }
    for (const auto& [f, local] : comp.local)
      if (redo[comp.find(local)]) {
        floes.state[f].vx = before[f].vx;
        floes.state[f].vy = before[f].vy;
        floes.state[f].yaw_rate = before[f].yaw_rate;
      }
    const std::vector<ContactImpulse> redone = resolve_collisions(floes, again, opt, stats, again_resting);
    total.resize(contacts.size());
    for (std::size_t j = 0; j < again.size(); ++j) total[again_index[j]] = redone[j];
  }
  // Sustained or impact by the approach at the start of the step, before the
  // step's smooth forces: a physical speed, not one the step's length made.
  if (record) {
    std::vector<std::uint32_t> contact_of;
    detail::record_impulses(*record, floes, contacts, total, slow_contacts(floes, contacts, opt.rest_speed, start),
                            placed ? &contact_of : nullptr);
    if (placed)
      for (const std::uint32_t j : contact_of) places->push_back(place[j]);
  }
  if (impulses) {
    impulses->assign(detection.contacts.size(), ContactImpulse{});
    for (std::size_t j = 0; j < detected; ++j) (*impulses)[from[j]] = total[j];
  }
  if (moved) {  // the floes the solves wrote, where they changed a velocity
    moved->clear();
    for (const ContactPoint& c : contacts)
      for (const std::uint32_t f : {c.a, c.b})
        if (!floes.is_static[f] && (floes.state[f].vx != before[f].vx || floes.state[f].vy != before[f].vy ||
                                    floes.state[f].yaw_rate != before[f].yaw_rate))
          moved->push_back(f);
    std::sort(moved->begin(), moved->end());
    moved->erase(std::unique(moved->begin(), moved->end()), moved->end());
  }
  return added;
}

}  // namespace

std::size_t resolve_step_collisions(Floes& floes, std::span<const FloeState> start, const Detection& detection,
                                    double step, const ImpulseOptions& options, CollisionStats& stats,
                                    std::vector<ContactImpulse>* impulses) {
  return step_collisions(floes, start, detection, step, options, stats, impulses, nullptr, nullptr, nullptr, nullptr,
                         nullptr);
}

StepCollisionShare resolve_step_collisions_share(Floes& floes, std::span<const FloeState> start,
                                                 const Detection& detection, double step,
                                                 const ImpulseOptions& options, const ClusterShare& share,
                                                 CollisionStats& stats, const StepGroups* groups) {
  // The share's solves read and write a copy of the warm store (impulse.hpp:
  // a pair's reads and writes are its group's alone); a failure's dump is
  // left to the whole solve, which numbers it in the run's count.
  ImpulseOptions o = options;
  WarmStart copy;
  if (options.warm) {
    copy = options.warm->share_copy();
    o.warm = &copy;
  }
  o.dump_failed_lcps.clear();
  const long failures = stats.failures;
  StepCollisionShare outcome;
  try {
    // The groups from the whole detection's edges, before any solve (W^-).
    StepGroups found;
    if (!groups) found = step_groups(floes, group_edges(floes, start, detection, step, o, share.owner), o);
    outcome.speculative = step_collisions(floes, start, detection, step, o, stats, nullptr, &share,
                                          groups ? groups : &found, &outcome.moved, &outcome.groups, &outcome.places);
  } catch (const RunError&) {
    outcome.conflict = StepCollisionShare::Conflict::error;
  }
  if (outcome.conflict == StepCollisionShare::Conflict::none && stats.failures != failures)
    outcome.conflict = StepCollisionShare::Conflict::failed_lcp;
  if (outcome.conflict == StepCollisionShare::Conflict::none && options.warm) {
    outcome.warm = copy.written_pairs();
    outcome.warm_uses = copy.uses;
  }
  return outcome;
}

std::vector<GroupEdge> group_edges(const Floes& floes, std::span<const FloeState> start, const Detection& detection,
                                   double step, const ImpulseOptions& options, std::span<const int> owner) {
  const double xi = options.collision_distance;
  std::vector<GroupEdge> out;
  for (const NearPair& p : detection.pairs) {
    GroupEdge e{p.a, p.b, p.contact_count > 0 ? GroupEdge::contacts : 0u};
    if (!owner.empty()) {
      e.owner_a = owner[p.a];
      e.owner_b = owner[p.b];
    }
    if (!p.overlap)
      for (std::uint32_t k = p.first_witness; k < p.first_witness + p.witness_count; ++k) {
        const Witness& w = detection.witnesses[k];
        if (w.distance < xi) continue;
        e.flags |= GroupEdge::witnesses;
        if (becomes_speculative(floes, start, floes.state, p, w, step, xi, options.rest_speed)) {
          e.flags |= GroupEdge::speculative;
          break;
        }
      }
    if (e.flags) out.push_back(e);
  }
  return out;
}

StepGroups step_groups(const Floes& floes, std::span<const GroupEdge> edges, const ImpulseOptions& options) {
  // The rule of impulse.hpp (resolve_step_collisions_share) on the edges:
  // the step's contacts are a pair's contact points unless a jam leaves them
  // to its time step, and a jam's speculative points when it does not; the
  // rounds' candidates are the witnesses beyond xi of the pairs outside jams.
  // Over the edges' floes (entries ascending by floe): a floe in no edge is
  // in no jam and no group, so the whole pack's arrays are not needed.
  StepGroups g;
  g.floes.reserve(2 * edges.size());
  for (const GroupEdge& e : edges) {
    g.floes.push_back(e.a);
    g.floes.push_back(e.b);
  }
  std::sort(g.floes.begin(), g.floes.end());
  g.floes.erase(std::unique(g.floes.begin(), g.floes.end()), g.floes.end());
  const std::size_t m = g.floes.size();
  // The edges on the entries, and each entry's owner from its edges.
  struct Local {
    std::uint32_t a, b, flags;
  };
  std::vector<Local> local;
  local.reserve(edges.size());
  std::vector<int> owner(m, -1);
  for (const GroupEdge& e : edges) {
    const auto a = static_cast<std::uint32_t>(g.entry(e.a)), b = static_cast<std::uint32_t>(g.entry(e.b));
    local.push_back({a, b, e.flags});
    owner[a] = e.owner_a;
    owner[b] = e.owner_b;
  }
  std::vector<std::uint8_t> dynamic(m);
  for (std::size_t k = 0; k < m; ++k) dynamic[k] = !floes.is_static[g.floes[k]];
  // Jams: components of dynamic floes joined by contact points.
  {
    DisjointSets sets(m);
    std::vector<std::uint8_t> joined(m, 0);
    for (const Local& e : local)
      if ((e.flags & GroupEdge::contacts) && dynamic[e.a] && dynamic[e.b]) {
        sets.join(e.a, e.b);
        joined[e.a] = joined[e.b] = 1;
      }
    std::vector<std::uint32_t> count(m, 0);
    for (std::uint32_t k = 0; k < m; ++k)
      if (joined[k]) ++count[sets.find(k)];
    g.jam.resize(m);
    for (std::uint32_t k = 0; k < m; ++k) g.jam[k] = joined[k] && count[sets.find(k)] >= options.jam.floes;
  }
  auto jammed = [&](const Local& e) { return g.jam[e.a] || g.jam[e.b]; };
  DisjointSets sets(m);
  std::vector<std::uint8_t> grouped(m, 0);
  auto link = [&](std::uint32_t a, std::uint32_t b) {  // obstacles join nothing
    if (dynamic[a]) grouped[a] = 1;
    if (dynamic[b]) grouped[b] = 1;
    if (dynamic[a] && dynamic[b]) sets.join(a, b);
  };
  const bool at_start = options.jam.at_step_start;
  for (const Local& e : local)
    if (((e.flags & GroupEdge::contacts) && (at_start || !jammed(e))) ||
        (at_start && jammed(e) && (e.flags & GroupEdge::witnesses)))
      link(e.a, e.b);
  const std::vector<std::uint8_t> v0 = grouped;  // round 0 may change these
  std::vector<std::uint8_t> v1 = v0;
  auto candidate = [&](const Local& e) { return (e.flags & GroupEdge::witnesses) && !jammed(e); };
  for (const Local& e : local)
    if (candidate(e) && (v0[e.a] || v0[e.b] || (e.flags & GroupEdge::speculative))) {
      if (dynamic[e.a]) v1[e.a] = 1;
      if (dynamic[e.b]) v1[e.b] = 1;
    }
  for (const Local& e : local)
    if (candidate(e) && (v1[e.a] || v1[e.b])) link(e.a, e.b);
  // A group's lowest floe: the first seen, ascending (the entries are).
  std::vector<std::uint32_t> lowest_of_root(m, StepGroups::kNone);
  g.lowest.assign(m, StepGroups::kNone);
  g.owner.assign(m, -1);
  for (std::uint32_t k = 0; k < m; ++k) {
    if (!grouped[k]) continue;
    std::uint32_t& low = lowest_of_root[sets.find(k)];
    if (low == StepGroups::kNone) low = k;
    g.lowest[k] = g.floes[low];
    g.owner[k] = owner[low];
  }
  return g;
}

bool StepGroups::any() const {
  return std::any_of(lowest.begin(), lowest.end(), [](std::uint32_t l) { return l != kNone; });
}

long StepGroups::count(int rank) const {
  long n = 0;
  for (std::size_t k = 0; k < floes.size(); ++k) n += lowest[k] == floes[k] && owner[k] == rank ? 1 : 0;
  return n;
}

void add_collision_counts(CollisionStats& total, const CollisionStats& part) {
  const auto to = collision_counts(total);
  const auto from = collision_counts(part);
  for (std::size_t k = 0; k < to.size(); ++k)
    *to[k].second = from[k].second == &part.largest ? std::max(*to[k].second, *from[k].second)
                                                     : *to[k].second + *from[k].second;
}

}  // namespace floesim::contact
