#include "parallel/collide_share.hpp"

#include <algorithm>
#include <array>
#include <string>
#include <tuple>
#include <utility>

#include "core/error.hpp"
#include "parallel/bytes.hpp"
#include "parallel/detect.hpp"
#include "parallel/refusals.hpp"

namespace floesim::parallel {

namespace {

using contact::CollisionStats;
using contact::StepCollisionShare;

constexpr std::size_t kStats = std::tuple_size_v<decltype(contact::collision_counts(std::declval<CollisionStats&>()))>;

// The header's longs: conflict, moved, groups, speculative, the states'
// count (the moved floes' when the share had no conflict, else none), the
// load places' count, the stats; then the moved floes, their states, the
// places (segment, a, b, index as uint32, then the shift's x and y: 32
// bytes each), the record (append_record) and the warm pairs stored
// (append_warm: 16 bytes, and 37 an entry).
constexpr std::size_t kHeader = 6 + kStats;

}  // namespace

std::vector<std::byte> pack(const CollidePart& p) {
  std::array<long, kHeader> head{};
  head[0] = static_cast<long>(p.outcome.conflict);
  head[1] = static_cast<long>(p.outcome.moved.size());
  head[2] = p.outcome.groups;
  head[3] = static_cast<long>(p.outcome.speculative);
  head[4] = static_cast<long>(p.states.size());
  head[5] = static_cast<long>(p.outcome.places.size());
  std::size_t k = 6;
  for (const auto& [name, f] : contact::collision_counts(p.stats)) head[k++] = *f;
  std::vector<std::byte> out(sizeof(head) + p.outcome.moved.size() * sizeof(std::uint32_t) +
                             p.states.size() * sizeof(FloeState));
  std::byte* at = put(out.data(), head.data(), head.size());
  at = put(at, p.outcome.moved.data(), p.outcome.moved.size());
  put(at, p.states.data(), p.states.size());
  for (const contact::ContactPlace& c : p.outcome.places) {
    const std::array<std::uint32_t, 4> ints{c.segment, c.a, c.b, c.index};
    const std::array<double, 2> shift{c.shift_x, c.shift_y};
    append(out, std::span<const std::uint32_t>(ints));
    append(out, std::span<const double>(shift));
  }
  append_record(out, p.record);
  append_warm(out, p.outcome.warm, p.outcome.warm_uses);
  return out;
}

CollidePart unpack_collide_part(std::span<const std::byte> bytes) {
  CollidePart p;
  const std::byte* in = bytes.data();
  FLOESIM_ASSERT(bytes.size() >= kHeader * sizeof(long));
  std::array<long, kHeader> head{};
  for (std::size_t j = 0; j < kHeader; ++j) head[j] = at<long>(in, j);
  in += sizeof(head);
  p.outcome.conflict = static_cast<StepCollisionShare::Conflict>(head[0]);
  const auto moved = static_cast<std::size_t>(head[1]);
  p.outcome.groups = head[2];
  p.outcome.speculative = static_cast<std::size_t>(head[3]);
  const auto states = static_cast<std::size_t>(head[4]);
  const auto places = static_cast<std::size_t>(head[5]);
  std::size_t k = 6;
  for (const auto& [name, f] : contact::collision_counts(p.stats)) *f = head[k++];
  p.outcome.moved = take<std::uint32_t>(in, moved);
  p.states = take<FloeState>(in, states);
  p.outcome.places.resize(places);
  for (contact::ContactPlace& c : p.outcome.places) {
    const std::vector<std::uint32_t> ints = take<std::uint32_t>(in, 4);
    const std::vector<double> shift = take<double>(in, 2);
    c = {ints[0], ints[1], ints[2], shift[0], shift[1], ints[3]};
  }
  p.record = take_record(in);
  p.outcome.warm = take_warm(in, p.outcome.warm_uses);
  FLOESIM_ASSERT(in == bytes.data() + bytes.size());
  return p;
}

CollidePart run_collide_share(Floes& floes, std::span<const FloeState> start, const contact::Detection& detection,
                              double step, const contact::ImpulseOptions& options, std::span<const int> owner,
                              int rank, const contact::StepGroups* groups,
                              const CollideShareOptions& share_options) {
  CollidePart part;
  contact::ImpulseOptions o = options;
  if (options.record) o.record = &part.record;
  part.outcome =
      contact::resolve_step_collisions_share(floes, start, detection, step, o, {owner, rank}, part.stats, groups);
  // The test hook: a share's use of the warm store made a conflict
  // (CollideShareOptions::warm_conflict).
  if (share_options.warm_conflict && part.outcome.conflict == StepCollisionShare::Conflict::none &&
      part.outcome.warm_uses > 0)
    part.outcome.conflict = StepCollisionShare::Conflict::warm_start;
  if (part.outcome.conflict == StepCollisionShare::Conflict::none) {
    for (const std::uint32_t i : part.outcome.moved) part.states.push_back(floes.state[i]);
  } else {
    part.record.clear();
    part.outcome.places.clear();
    part.outcome.warm.clear();
    part.outcome.warm_uses = 0;
  }
  return part;
}

namespace {
const char* refused_name(StepCollisionShare::Conflict conflict) {
  switch (conflict) {
    case StepCollisionShare::Conflict::none: return nullptr;
    case StepCollisionShare::Conflict::warm_start: return "warm_start";
    case StepCollisionShare::Conflict::failed_lcp: return "failed_lcp";
    case StepCollisionShare::Conflict::error: return "error";
  }
  return "unknown";
}

// The kinds of conflict of a try's parts, each once, into counts.conflicts
// (AdvanceShareCounts): refusals.hpp.
void count_conflicts(std::span<const CollidePart> parts, AdvanceShareCounts& counts) {
  for (const std::string& k : refusals(parts, refused_name)) ++counts.conflicts[k];
}
}  // namespace

bool combine_collide_parts(std::span<const CollidePart> parts, Floes& floes, CollisionStats& stats,
                           std::size_t& speculative, contact::ImpulseRecord* record, contact::WarmStart* warm) {
  // Each warm pair is one group's (impulse.hpp), so one part's.
  if (!refusals(parts, refused_name).empty()) return false;
  // The store: every part's pairs as its share left them, the whole call's
  // last writes (impulse.hpp, StepCollisionShare), on every rank alike.
  if (warm)
    for (const CollidePart& p : parts) hold_warm(p.outcome.warm, p.outcome.warm_uses, *warm);
  speculative = 0;
  for (const CollidePart& p : parts) {
    for (std::size_t j = 0; j < p.states.size(); ++j) floes.state[p.outcome.moved[j]] = p.states[j];
    contact::add_collision_counts(stats, p.stats);
    speculative += p.outcome.speculative;
  }
  if (record) {
    std::vector<contact::RecordPart> records;
    for (const CollidePart& p : parts) records.push_back({&p.record, p.outcome.places, {}});
    contact::merge_step_record(*record, records);
  }
  return true;
}

std::size_t collide_by_owner(const Communicator& comm, std::span<const int> owner, Floes& floes,
                             std::span<const FloeState> start, const contact::Detection& detection, double step,
                             const contact::ImpulseOptions& options, contact::CollisionStats& stats,
                             AdvanceShareCounts& counts, const CollideShareOptions& share_options) {
  if (counts.whole_now()) return contact::resolve_step_collisions(floes, start, detection, step, options, stats);
  // W^-: a fallback starts again from it. Only the velocities change here.
  const std::vector<FloeState> entry = floes.state;
  const CollidePart mine =
      run_collide_share(floes, start, detection, step, options, owner, comm.rank(), nullptr, share_options);
  const std::vector<CollidePart> parts = comm.allgather_parts(pack(mine), unpack_collide_part);
  counts.clusters.resize(parts.size(), 0);
  std::size_t speculative = 0;
  if (combine_collide_parts(parts, floes, stats, speculative, options.record, options.warm)) {
    for (std::size_t r = 0; r < parts.size(); ++r) counts.clusters[r] += parts[r].outcome.groups;
    counts.combined();
    return speculative;
  }
  // A conflict: the whole solve from the states on entry, as the serial run.
  count_conflicts(parts, counts);
  counts.fell_back(share_options.back_off);
  floes.state = entry;
  return contact::resolve_step_collisions(floes, start, detection, step, options, stats);
}

std::vector<contact::Detection> pairs_for_groups(const Floes& floes, const contact::Detection& part,
                                                 const contact::StepGroups& groups, int ranks, int rank,
                                                 double collision_distance) {
  // The rank whose share reads pair p (resolve_step_collisions_share keeps
  // the contacts and witnesses whose dynamic floes are all in its groups),
  // or -1: none does, or p has nothing a share reads (no contact point and
  // no witness at or beyond xi of a pair that does not overlap). The group's
  // owner is its lowest floe's, as the edges said it.
  auto reader = [&](const contact::NearPair& p) {
    bool read = p.contact_count > 0;
    if (!p.overlap)
      for (std::uint32_t k = p.first_witness; k < p.first_witness + p.witness_count && !read; ++k)
        read = !(part.witnesses[k].distance < collision_distance);
    if (!read) return -1;
    const bool da = !floes.is_static[p.a], db = !floes.is_static[p.b];
    if (!da && !db) return -1;
    const std::size_t k = groups.entry(da ? p.a : p.b);
    if (k == groups.floes.size() || groups.lowest[k] == contact::StepGroups::kNone) return -1;
    if (da && db && groups.lowest_of(p.b) != groups.lowest[k]) return -1;
    return groups.owner[k];
  };
  std::vector<contact::Detection> out(static_cast<std::size_t>(ranks));
  std::vector<int> to(part.pairs.size());
  for (std::size_t j = 0; j < part.pairs.size(); ++j) to[j] = reader(part.pairs[j]);
  for (int s = 0; s < ranks; ++s) {
    if (s == rank) continue;
    std::size_t j = 0;
    out[static_cast<std::size_t>(s)] = select_pairs(part, [&](const contact::NearPair&) { return to[j++] == s; });
  }
  return out;
}

std::size_t collide_on_part(const Communicator& comm, std::span<const int> owner, Floes& floes,
                            std::span<const FloeState> start, const contact::Detection& part, double step,
                            const contact::ImpulseOptions& options, contact::CollisionStats& stats,
                            AdvanceShareCounts& counts, const CollideShareOptions& share_options,
                            const WholeOnDemand* whole) {
  if (comm.serial())
    return collide_by_owner(comm, owner, floes, start, gather(comm, part), step, options, stats, counts,
                            share_options);
  // The whole solve reads every floe's W^- and start (`start` views the
  // caller's copy, which whole->state makes whole): the state first, then
  // the lists.
  contact::Detection gathered;
  const auto solve_whole = [&]() {
    if (whole) whole->state(WholeState::state_and_start);
    const contact::Detection& lists = whole ? whole->detection() : (gathered = gather(comm, part));
    return contact::resolve_step_collisions(floes, start, lists, step, options, stats);
  };
  if (counts.whole_now()) return solve_whole();
  // Every rank's edges (20 bytes a pair with a flag: the floes' owners in
  // them), the same step groups and group owners on every rank.
  const std::vector<contact::GroupEdge> mine = contact::group_edges(floes, start, part, step, options, owner);
  const std::vector<contact::GroupEdge> edges = comm.allgather<contact::GroupEdge>(mine);
  const contact::StepGroups groups = contact::step_groups(floes, edges, options);
  // No step group on any rank (the same groups on all): the serial call
  // solves nothing and changes nothing, and every rank skips the exchanges.
  // Its record still counts its one event, with no load.
  if (!groups.any()) {
    if (options.record) contact::merge_step_record(*options.record, {});
    counts.clusters.resize(static_cast<std::size_t>(comm.size()), 0);
    counts.combined();
    return 0;
  }
  // The pairs of the groups owned elsewhere, to their owners, with their
  // floes (W^-, the step's start, mass and inertia), which the share then
  // reads from the message.
  const std::vector<contact::Detection> out =
      pairs_for_groups(floes, part, groups, comm.size(), comm.rank(), options.collision_distance);
  Carried carried{1, std::vector<Pieces>(out.size()), {}};
  for (std::size_t s = 0; s < out.size(); ++s)
    if (!out[s].pairs.empty()) carried.outgoing[s] = {pack(routed_floes(floes, start, out[s]))};
  const contact::Detection local = exchange_pairs(comm, part, out, &carried);
  // The share reads the routed floes' starts from a copy (the caller's
  // `start` is left as it came, for the fallback's whole state).
  std::vector<FloeState> held_start;
  std::span<const FloeState> share_start = start;
  if (!carried.received.empty()) {
    held_start.assign(start.begin(), start.end());
    for (const Pieces& r : carried.received) hold(unpack_routed_floes(r[0]), floes, held_start);
    share_start = held_start;
  }
  // The share on its pairs, then collide_by_owner's exchange (with the
  // share's record and its loads' places keyed by pair: the serial record
  // merged from the parts).
  const std::vector<FloeState> entry = floes.state;
  const CollidePart share =
      run_collide_share(floes, share_start, local, step, options, owner, comm.rank(), &groups, share_options);
  const std::vector<CollidePart> shares = comm.allgather_parts(pack(share), unpack_collide_part);
  counts.clusters.resize(shares.size(), 0);
  std::size_t speculative = 0;
  if (combine_collide_parts(shares, floes, stats, speculative, options.record, options.warm)) {
    for (std::size_t r = 0; r < shares.size(); ++r) counts.clusters[r] += shares[r].outcome.groups;
    counts.combined();
    return speculative;
  }
  count_conflicts(shares, counts);
  counts.fell_back(share_options.back_off);
  floes.state = entry;
  return solve_whole();
}

}  // namespace floesim::parallel
