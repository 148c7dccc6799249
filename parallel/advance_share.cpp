#include "parallel/advance_share.hpp"

#include <algorithm>
#include <array>
#include <cstring>
#include <map>
#include <optional>
#include <set>
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
using contact::ShareOutcome;
using contact::SubstepReport;

constexpr std::size_t kStats = std::tuple_size_v<decltype(contact::collision_counts(std::declval<CollisionStats&>()))>;
constexpr std::size_t kReport = std::tuple_size_v<decltype(contact::substep_counts(std::declval<SubstepReport&>()))>;

// The header's longs: conflict, moved, clusters, floor_cluster, the floor
// pair's length, the states' count (the moved floes' when the share had no
// conflict, else none), rooms, pairs, the event places' count, the stats,
// the report; then floor_tau, the moved floes, their states, the floor
// pair's text, the event places (tau, cluster) and the record.
constexpr std::size_t kHeader = 9 + kStats + kReport;

// A load in a message: floe, event, other, sustained (4 uint32), then
// point, impulse, world (2 doubles each) and normal.
constexpr std::size_t kLoadInts = 4, kLoadDoubles = 7;
constexpr std::size_t kLoadBytes = kLoadInts * sizeof(std::uint32_t) + kLoadDoubles * sizeof(double);

// A tight or near pair in a message: a, b (uint32), then shift x, y, the
// room and each floe's reach less travel (doubles), then the floes' owners
// (int32); a contact edge: a, b, then their owners.
constexpr std::size_t kTight = 2 * sizeof(std::uint32_t) + 5 * sizeof(double) + 2 * sizeof(std::int32_t);
constexpr std::size_t kEdge = 2 * sizeof(std::uint32_t) + 2 * sizeof(std::int32_t);

}  // namespace

void append_record(std::vector<std::byte>& out, const contact::ImpulseRecord& record) {
  const std::array<std::uint32_t, 2> head{static_cast<std::uint32_t>(record.loads.size()), record.events};
  append(out, std::span<const std::uint32_t>(head));
  const std::size_t from = out.size();
  out.resize(from + record.loads.size() * kLoadBytes);
  std::byte* at = out.data() + from;
  for (const contact::ImpulseRecord::Load& l : record.loads) {
    const std::array<std::uint32_t, kLoadInts> ints{l.floe, l.event, l.other, l.sustained ? 1u : 0u};
    const std::array<double, kLoadDoubles> doubles{l.point.x(), l.point.y(), l.impulse.x(), l.impulse.y(),
                                                   l.world.x(), l.world.y(), l.normal};
    at = put(at, ints.data(), ints.size());
    at = put(at, doubles.data(), doubles.size());
  }
}

contact::ImpulseRecord take_record(const std::byte*& in) {
  contact::ImpulseRecord record;
  const std::vector<std::uint32_t> head = take<std::uint32_t>(in, 2);
  record.events = head[1];
  record.loads.resize(head[0]);
  for (contact::ImpulseRecord::Load& l : record.loads) {
    const std::vector<std::uint32_t> ints = take<std::uint32_t>(in, kLoadInts);
    const std::vector<double> d = take<double>(in, kLoadDoubles);
    l.floe = ints[0];
    l.event = ints[1];
    l.other = ints[2];
    l.sustained = ints[3] != 0;
    l.point = {d[0], d[1]};
    l.impulse = {d[2], d[3]};
    l.world = {d[4], d[5]};
    l.normal = d[6];
  }
  return record;
}

void append_warm(std::vector<std::byte>& out, const contact::WarmStart::Written& pairs, long uses) {
  const std::array<std::int64_t, 2> head{static_cast<std::int64_t>(pairs.size()), uses};
  append(out, std::span<const std::int64_t>(head));
  for (const auto& [key, pair] : pairs) {
    const std::array<std::int64_t, 3> h{static_cast<std::int64_t>(key), pair.stored,
                                        static_cast<std::int64_t>(pair.entries.size())};
    append(out, std::span<const std::int64_t>(h));
    for (const contact::WarmStart::Entry& e : pair.entries) {
      const std::array<double, 4> d{e.body_point.x(), e.body_point.y(), e.body_normal.x(), e.body_normal.y()};
      const std::array<std::uint8_t, 5> b{e.basic[0], e.basic[1], e.basic[2], e.basic[3],
                                          static_cast<std::uint8_t>(e.vertex_of_b ? 1 : 0)};
      append(out, std::span<const double>(d));
      append(out, std::span<const std::uint8_t>(b));
    }
  }
}

contact::WarmStart::Written take_warm(const std::byte*& in, long& uses) {
  const std::vector<std::int64_t> head = take<std::int64_t>(in, 2);
  uses = head[1];
  contact::WarmStart::Written pairs(static_cast<std::size_t>(head[0]));
  for (auto& [key, pair] : pairs) {
    const std::vector<std::int64_t> h = take<std::int64_t>(in, 3);
    key = static_cast<std::uint64_t>(h[0]);
    pair.stored = h[1];
    pair.entries.resize(static_cast<std::size_t>(h[2]));
    for (contact::WarmStart::Entry& e : pair.entries) {
      const std::vector<double> d = take<double>(in, 4);
      const std::vector<std::uint8_t> b = take<std::uint8_t>(in, 5);
      e.body_point = {d[0], d[1]};
      e.body_normal = {d[2], d[3]};
      e.basic = {b[0], b[1], b[2], b[3]};
      e.vertex_of_b = b[4] != 0;
    }
  }
  return pairs;
}

void hold_warm(const contact::WarmStart::Written& pairs, long uses, contact::WarmStart& store) {
  for (const auto& [key, pair] : pairs) store.pairs[key] = pair;
  store.uses += uses;
}

std::vector<std::byte> pack(const AdvancePart& p) {
  std::array<long, kHeader> head{};
  head[0] = static_cast<long>(p.outcome.conflict);
  head[1] = static_cast<long>(p.outcome.moved.size());
  head[2] = p.outcome.clusters;
  head[3] = p.outcome.floor_cluster;
  head[4] = static_cast<long>(p.report.floor_pair.size());
  head[5] = static_cast<long>(p.states.size());
  head[6] = p.outcome.rooms;
  head[7] = p.outcome.pairs;
  head[8] = static_cast<long>(p.outcome.events.size());
  std::size_t k = 9;
  for (const auto& [name, f] : contact::collision_counts(p.stats)) head[k++] = *f;
  for (const auto& [name, f] : contact::substep_counts(p.report)) head[k++] = *f;
  std::vector<std::byte> out(sizeof(head) + sizeof(double) + p.outcome.moved.size() * sizeof(std::uint32_t) +
                             p.states.size() * sizeof(FloeState) + p.report.floor_pair.size());
  std::byte* at = put(out.data(), head.data(), head.size());
  at = put(at, &p.outcome.floor_tau, 1);
  at = put(at, p.outcome.moved.data(), p.outcome.moved.size());
  at = put(at, p.states.data(), p.states.size());
  put(at, p.report.floor_pair.data(), p.report.floor_pair.size());
  for (const contact::EventPlace& e : p.outcome.events) {
    append(out, std::span<const double>(&e.tau, 1));
    append(out, std::span<const std::int64_t>(&e.cluster, 1));
  }
  append_record(out, p.record);
  append_warm(out, p.outcome.warm, p.outcome.warm_uses);
  // The clusters to join (ShareOutcome::met, merged, taken: 8 bytes each).
  const std::array<std::int64_t, 3> joins{static_cast<std::int64_t>(p.outcome.met.size()),
                                          static_cast<std::int64_t>(p.outcome.merged.size()),
                                          static_cast<std::int64_t>(p.outcome.taken.size())};
  append(out, std::span<const std::int64_t>(joins));
  for (const auto* list : {&p.outcome.met, &p.outcome.merged, &p.outcome.taken})
    for (const auto& [a, b] : *list) {
      const std::array<std::int32_t, 2> ab{a, b};
      append(out, std::span<const std::int32_t>(ab));
    }
  return out;
}

AdvancePart unpack_advance_part(std::span<const std::byte> bytes) {
  AdvancePart p;
  const std::byte* in = bytes.data();
  std::array<long, kHeader> head{};
  for (std::size_t j = 0; j < kHeader; ++j) head[j] = at<long>(in, j);
  in += sizeof(head);
  p.outcome.conflict = static_cast<ShareOutcome::Conflict>(head[0]);
  const auto moved = static_cast<std::size_t>(head[1]);
  p.outcome.clusters = head[2];
  p.outcome.floor_cluster = head[3];
  const auto text = static_cast<std::size_t>(head[4]);
  const auto states = static_cast<std::size_t>(head[5]);
  p.outcome.rooms = head[6];
  p.outcome.pairs = head[7];
  const auto events = static_cast<std::size_t>(head[8]);
  std::size_t k = 9;
  for (const auto& [name, f] : contact::collision_counts(p.stats)) *f = head[k++];
  for (const auto& [name, f] : contact::substep_counts(p.report)) *f = head[k++];
  p.outcome.floor_tau = take<double>(in, 1).front();
  p.outcome.moved = take<std::uint32_t>(in, moved);
  p.states = take<FloeState>(in, states);
  p.report.floor_pair.assign(reinterpret_cast<const char*>(in), text);
  in += text;
  p.outcome.events.resize(events);
  for (contact::EventPlace& e : p.outcome.events) {
    e.tau = take<double>(in, 1).front();
    e.cluster = take<std::int64_t>(in, 1).front();
  }
  p.record = take_record(in);
  p.outcome.warm = take_warm(in, p.outcome.warm_uses);
  const std::vector<std::int64_t> joins = take<std::int64_t>(in, 3);
  for (auto [list, n] : {std::pair{&p.outcome.met, joins[0]}, std::pair{&p.outcome.merged, joins[1]},
                         std::pair{&p.outcome.taken, joins[2]}}) {
    const std::vector<std::int32_t> ab = take<std::int32_t>(in, 2 * static_cast<std::size_t>(n));
    for (std::size_t j = 0; j < ab.size(); j += 2) list->emplace_back(ab[j], ab[j + 1]);
  }
  FLOESIM_ASSERT(in == bytes.data() + bytes.size());
  return p;
}

std::vector<std::byte> pack(const contact::ShareRooms& rooms) {
  const std::array<long, 4> head{static_cast<long>(rooms.conflict), rooms.outrun ? 1L : 0L,
                                 static_cast<long>(rooms.tight.size()), static_cast<long>(rooms.touching.size())};
  std::vector<std::byte> out(sizeof(head) + rooms.tight.size() * kTight + rooms.touching.size() * kEdge);
  std::byte* at = put(out.data(), head.data(), head.size());
  for (const contact::PairRoom& t : rooms.tight) {
    const std::array<std::uint32_t, 2> ab{t.a, t.b};
    const std::array<double, 5> d{t.shift.x(), t.shift.y(), t.room, t.left_a, t.left_b};
    const std::array<std::int32_t, 2> owners{t.owner_a, t.owner_b};
    at = put(at, ab.data(), ab.size());
    at = put(at, d.data(), d.size());
    at = put(at, owners.data(), owners.size());
  }
  for (const contact::ContactEdge& e : rooms.touching) {
    const std::array<std::uint32_t, 2> ab{e.a, e.b};
    const std::array<std::int32_t, 2> owners{e.owner_a, e.owner_b};
    at = put(at, ab.data(), ab.size());
    at = put(at, owners.data(), owners.size());
  }
  return out;
}

contact::ShareRooms unpack_share_rooms(std::span<const std::byte> bytes) {
  contact::ShareRooms rooms;
  const std::byte* in = bytes.data();
  rooms.conflict = static_cast<ShareOutcome::Conflict>(at<long>(in, 0));
  rooms.outrun = at<long>(in, 1) != 0;
  const auto count = static_cast<std::size_t>(at<long>(in, 2));
  const auto edges = static_cast<std::size_t>(at<long>(in, 3));
  FLOESIM_ASSERT(bytes.size() == 4 * sizeof(long) + count * kTight + edges * kEdge);
  in += 4 * sizeof(long);
  rooms.tight.resize(count);
  for (contact::PairRoom& t : rooms.tight) {
    const std::vector<std::uint32_t> ab = take<std::uint32_t>(in, 2);
    const std::vector<double> d = take<double>(in, 5);
    const std::vector<std::int32_t> owners = take<std::int32_t>(in, 2);
    t = {ab[0], ab[1], {d[0], d[1]}, d[2], owners[0], owners[1], d[3], d[4]};
  }
  rooms.touching.resize(edges);
  for (contact::ContactEdge& e : rooms.touching) {
    const std::vector<std::uint32_t> ab = take<std::uint32_t>(in, 2);
    const std::vector<std::int32_t> owners = take<std::int32_t>(in, 2);
    e = {ab[0], ab[1], owners[0], owners[1]};
  }
  return rooms;
}

bool combine_rooms(std::span<const contact::ShareRooms> parts, contact::ShareRooms& all) {
  all.tight.clear();
  all.touching.clear();
  for (const contact::ShareRooms& p : parts) {
    if (p.conflict != ShareOutcome::Conflict::none) return false;
    all.tight.insert(all.tight.end(), p.tight.begin(), p.tight.end());
    all.touching.insert(all.touching.end(), p.touching.begin(), p.touching.end());
  }
  return true;
}

AdvancePart finish_share(contact::ShareAdvance& share, const contact::ShareRooms& all, const Floes& floes,
                         contact::ImpulseRecord* record) {
  return share_part(share, share.advance(all), floes, record);
}

AdvancePart share_part(const contact::ShareAdvance& share, contact::ShareOutcome outcome, const Floes& floes,
                       contact::ImpulseRecord* record) {
  AdvancePart part;
  part.outcome = std::move(outcome);
  part.stats = share.stats();
  part.report = share.report();
  if (part.outcome.conflict == ShareOutcome::Conflict::none) {
    for (const std::uint32_t i : part.outcome.moved) part.states.push_back(floes.state[i]);
    if (record) part.record = std::move(*record);
  } else {
    part.outcome.events.clear();
    part.outcome.warm.clear();
    part.outcome.warm_uses = 0;
  }
  return part;
}

const char* conflict_name(contact::ShareOutcome::Conflict conflict) {
  using C = contact::ShareOutcome::Conflict;
  switch (conflict) {
    case C::none: return "none";
    case C::foreign_cluster: return "foreign_cluster";
    case C::failed_lcp: return "failed_lcp";
    case C::error: return "error";
    case C::missing_pairs: return "missing_pairs";
    case C::missing_floe: return "missing_floe";
  }
  return "unknown";
}

namespace {
const char* refused_name(contact::ShareOutcome::Conflict conflict) {
  return conflict == ShareOutcome::Conflict::none ? nullptr : conflict_name(conflict);
}
}  // namespace

void count_conflicts(std::span<const AdvancePart> parts, AdvanceShareCounts& counts) {
  for (const std::string& k : refusals(parts, refused_name)) ++counts.conflicts[k];
}

// A set-up's conflicts (the gathered rooms' flags), each kind once.
static void count_set_up(std::span<const contact::ShareRooms> rooms, AdvanceShareCounts& counts) {
  std::vector<AdvancePart> parts(rooms.size());
  for (std::size_t r = 0; r < rooms.size(); ++r) parts[r].outcome.conflict = rooms[r].conflict;
  count_conflicts(parts, counts);
}

bool combine_parts(std::span<const AdvancePart> parts, Floes& floes, CollisionStats& stats, SubstepReport& report,
                   contact::ImpulseRecord* record, contact::WarmStart* warm) {
  if (!refusals(parts, refused_name).empty()) return false;
  if (warm)
    for (const AdvancePart& p : parts) hold_warm(p.outcome.warm, p.outcome.warm_uses, *warm);
  for (const AdvancePart& p : parts)
    for (std::size_t j = 0; j < p.states.size(); ++j) floes.state[p.outcome.moved[j]] = p.states[j];
  // Counts: sums, but the largest LCP and cluster (maxima) and the pair
  // list's rebuild, which every share did alike (taken once).
  const AdvancePart* floor = nullptr;
  for (const AdvancePart& p : parts) {
    contact::add_collision_counts(stats, p.stats);
    const auto rto = contact::substep_counts(report);
    const auto rfrom = contact::substep_counts(p.report);
    for (std::size_t k = 0; k < kReport; ++k) {
      if (rfrom[k].second == &p.report.rebuilt) continue;
      *rto[k].second = rfrom[k].second == &p.report.largest_cluster ? std::max(*rto[k].second, *rfrom[k].second)
                                                                    : *rto[k].second + *rfrom[k].second;
    }
    // The serial queue's last floor step: the largest key (tau, cluster).
    if (p.report.floor_steps > 0 &&
        (!floor || std::pair(p.outcome.floor_tau, p.outcome.floor_cluster) >
                       std::pair(floor->outcome.floor_tau, floor->outcome.floor_cluster)))
      floor = &p;
  }
  if (!parts.empty()) report.rebuilt += parts.front().report.rebuilt;
  if (floor) report.floor_pair = floor->report.floor_pair;
  if (record) {
    std::vector<contact::RecordPart> records;
    for (const AdvancePart& p : parts) records.push_back({&p.record, {}, p.outcome.events});
    contact::merge_advance_record(*record, records);
  }
  return true;
}

namespace {

// Which lists the parts' `outcome.pairs` count (each share's set-up
// counts the pairs of the list it saw): one list every share saw whole
// (the whole detection, or the list every rank rebuilt over every floe
// when a floe outran its reach), which every part counts alike, so the
// step's pairs are one part's; or each rank's own part of the detection,
// disjoint parts of the list, so the step's pairs are their sum.
enum class PairLists { whole_on_every_rank, one_part_a_rank };

struct Gathered {
  std::vector<AdvancePart> parts;  // every rank's, rank order
  bool combined = false;           // combine_parts took them
};

// Every rank's part (one allgather_bytes), then, a routed floe that came
// incomplete being a fault (check_routed_floes), their combination
// (combine_parts); when they combine, each rank's clusters and rooms and
// the step's pairs (by `lists`) are counted. On a conflict nothing is
// counted: the caller counts it, or tries again.
Gathered gather_and_combine(const Communicator& comm, const AdvancePart& mine, PairLists lists, Floes& floes,
                            CollisionStats& stats, SubstepReport& report, contact::ImpulseRecord* record,
                            contact::WarmStart* warm, AdvanceShareCounts& counts) {
  Gathered g;
  g.parts = comm.allgather_parts(pack(mine), unpack_advance_part);
  check_routed_floes(g.parts);
  counts.clusters.resize(g.parts.size(), 0);
  counts.rooms.resize(g.parts.size(), 0);
  g.combined = combine_parts(g.parts, floes, stats, report, record, warm);
  if (!g.combined) return g;
  for (std::size_t r = 0; r < g.parts.size(); ++r) {
    counts.clusters[r] += g.parts[r].outcome.clusters;
    counts.rooms[r] += g.parts[r].outcome.rooms;
    if (lists == PairLists::one_part_a_rank || r == 0) counts.pairs += g.parts[r].outcome.pairs;
  }
  return g;
}

}  // namespace

void advance_by_owner(const Communicator& comm, std::span<const int> owner, Floes& floes,
                      const contact::CollisionShapes& shapes, const contact::Detection& detection, double dt,
                      const contact::SubstepOptions& options, contact::CollisionStats& stats,
                      contact::SubstepReport& report, AdvanceShareCounts& counts,
                      const AdvanceShareOptions& share_options) {
  if (counts.whole_now()) {
    contact::advance_with_collisions(floes, shapes, detection, dt, options, stats, report);
    return;
  }
  const std::vector<FloeState> start = floes.state;
  bool combined = false;
  {
    // A run that keeps the impulse record: the share records into its own
    // (sent in its part), and every rank merges the parts in the serial order.
    contact::ImpulseRecord* const record = options.impulse.record;
    contact::ImpulseRecord own;
    contact::SubstepOptions own_options = options;
    if (record) own_options.impulse.record = &own;
    // The set-up by share, then the exchange of the tight pairs.
    contact::ShareAdvance share(floes, shapes, detection, dt, own_options, {owner, comm.rank()});
    const std::vector<contact::ShareRooms> rooms = comm.allgather_parts(pack(share.rooms()), unpack_share_rooms);
    contact::ShareRooms all;
    // Every rank sees the same gathered conflicts: all skip the second
    // exchange alike.
    if (combine_rooms(rooms, all)) {
      const AdvancePart mine = finish_share(share, all, floes, record ? &own : nullptr);
      const Gathered g = gather_and_combine(comm, mine, PairLists::whole_on_every_rank, floes, stats, report,
                                            record, options.impulse.warm, counts);
      combined = g.combined;
      if (!combined) count_conflicts(g.parts, counts);
    } else {
      count_set_up(rooms, counts);
    }
  }
  if (combined) {
    counts.combined();
    return;
  }
  // A conflict: the whole advance from the step's states, as the serial run.
  counts.fell_back(share_options);
  floes.state = start;
  contact::advance_with_collisions(floes, shapes, detection, dt, options, stats, report);
}

std::vector<contact::Detection> routed_pairs(const contact::Detection& part,
                                             std::span<const std::pair<int, std::uint32_t>> routes, int ranks) {
  std::vector<contact::Detection> out(static_cast<std::size_t>(ranks));
  std::vector<std::uint8_t> to(part.pairs.size());
  for (int s = 0; s < ranks; ++s) {
    std::fill(to.begin(), to.end(), 0);
    bool any = false;
    for (const auto& [r, p] : routes)
      if (r == s) {
        to[p] = 1;
        any = true;
      }
    if (!any) continue;
    std::size_t j = 0;
    out[static_cast<std::size_t>(s)] = select_pairs(part, [&](const contact::NearPair&) { return to[j++] != 0; });
  }
  return out;
}

RoutedShapes routed_shapes(const contact::CollisionShapes& shapes, std::span<const double> reach,
                           std::span<const std::uint32_t> floes) {
  RoutedShapes out;
  out.floe.assign(floes.begin(), floes.end());
  for (const std::uint32_t i : floes) {
    out.radius.push_back(shapes.radius[i]);
    out.reach.push_back(reach[i]);
    out.parts.push_back(static_cast<std::uint32_t>(shapes.parts_of(i)));
    for (std::size_t p = shapes.parts_begin(i); p < shapes.parts_end(i); ++p) {
      const std::span<const Vec2> v = shapes.part(p);
      out.vertices.push_back(static_cast<std::uint32_t>(v.size()));
      out.vertex.insert(out.vertex.end(), v.begin(), v.end());
    }
  }
  return out;
}

void hold(const RoutedShapes& routed, contact::CollisionShapes& shapes, std::span<double> reach) {
  std::size_t part = 0, vertex = 0;
  for (std::size_t k = 0; k < routed.floe.size(); ++k) {
    const std::uint32_t i = routed.floe[k];
    shapes.radius[i] = routed.radius[k];
    reach[i] = routed.reach[k];
    if (!shapes.has(i)) {
      // Not held here: its parts go to the arrays' end (as an entering
      // floe's, CollisionShapes::hold), kept until the next detection's hold.
      const std::span<const std::uint32_t> sizes(routed.vertices.data() + part, routed.parts[k]);
      std::size_t count = 0;
      for (const std::uint32_t s : sizes) count += s;
      shapes.append(i, sizes, std::span<const Vec2>(routed.vertex.data() + vertex, count));
      part += routed.parts[k];
      vertex += count;
      continue;
    }
    FLOESIM_ASSERT(shapes.parts_of(i) == routed.parts[k]);
    for (std::size_t p = shapes.parts_begin(i); p < shapes.parts_end(i); ++p, ++part) {
      FLOESIM_ASSERT(shapes.vertex_offsets[p + 1] - shapes.vertex_offsets[p] == routed.vertices[part]);
      std::copy_n(routed.vertex.begin() + static_cast<std::ptrdiff_t>(vertex), routed.vertices[part],
                  shapes.vertices.begin() + static_cast<std::ptrdiff_t>(shapes.vertex_offsets[p]));
      vertex += routed.vertices[part];
    }
  }
}

std::vector<std::byte> pack(const RoutedShapes& r) {
  const std::array<std::uint64_t, 3> n{r.floe.size(), r.vertices.size(), r.vertex.size()};
  std::vector<std::byte> out(sizeof(n) + r.floe.size() * (2 * sizeof(std::uint32_t) + 2 * sizeof(double)) +
                             r.vertices.size() * sizeof(std::uint32_t) + r.vertex.size() * sizeof(Vec2));
  std::byte* at = put(out.data(), n.data(), n.size());
  at = put(at, r.floe.data(), r.floe.size());
  at = put(at, r.radius.data(), r.radius.size());
  at = put(at, r.reach.data(), r.reach.size());
  at = put(at, r.parts.data(), r.parts.size());
  at = put(at, r.vertices.data(), r.vertices.size());
  put(at, r.vertex.data(), r.vertex.size());
  return out;
}

RoutedShapes unpack_routed_shapes(std::span<const std::byte> bytes) {
  const std::byte* in = bytes.data();
  RoutedShapes r;
  const std::vector<std::uint64_t> n = take<std::uint64_t>(in, 3);
  const auto floes = static_cast<std::size_t>(n[0]);
  r.floe = take<std::uint32_t>(in, floes);
  r.radius = take<double>(in, floes);
  r.reach = take<double>(in, floes);
  r.parts = take<std::uint32_t>(in, floes);
  r.vertices = take<std::uint32_t>(in, static_cast<std::size_t>(n[1]));
  r.vertex = take<Vec2>(in, static_cast<std::size_t>(n[2]));
  FLOESIM_ASSERT(in == bytes.data() + bytes.size());
  return r;
}

contact::Detection exchange_advance_pairs(const Communicator& comm, const contact::Detection& part,
                                          const std::vector<contact::Detection>& outgoing, Floes& floes,
                                          contact::CollisionShapes& shapes, long* shape_bytes) {
  // Two pieces with each message's pairs: their floes' states, their shapes.
  Carried carried{2, std::vector<Pieces>(outgoing.size()), {}};
  for (std::size_t s = 0; s < outgoing.size(); ++s) {
    if (outgoing[s].pairs.empty()) continue;
    const RoutedFloes routed = routed_floes(floes, {}, outgoing[s]);
    carried.outgoing[s] = {pack(routed), pack(routed_shapes(shapes, part.reach, routed.floe))};
    if (shape_bytes) *shape_bytes += static_cast<long>(carried.outgoing[s][1].size());
  }
  contact::Detection held = exchange_pairs(comm, part, outgoing, &carried);
  for (const Pieces& r : carried.received) {
    parallel::hold(unpack_routed_floes(r[0]), floes, {});
    hold(unpack_routed_shapes(r[1]), shapes, held.reach);
  }
  return held;
}

void check_routed_floes(std::span<const AdvancePart> parts) {
  for (std::size_t r = 0; r < parts.size(); ++r) {
    const contact::ShareOutcome& o = parts[r].outcome;
    if (o.conflict != contact::ShareOutcome::Conflict::missing_floe) continue;
    throw RunError("the advance's share on rank " + std::to_string(r) + ": floe " +
                   (o.moved.empty() ? std::string("?") : std::to_string(o.moved.front())) +
                   " of its routed pairs came without its state, mass, collision shape or reach "
                   "(not finite where the share holds it)");
  }
}

bool any_outrun(std::span<const contact::ShareRooms> rooms) {
  return std::any_of(rooms.begin(), rooms.end(), [](const contact::ShareRooms& r) { return r.outrun; });
}

void move_not_held(Floes& floes, std::span<const std::uint32_t> held, double dt) {
  // The formula of the share's free floes (contact::drifted from the step's
  // start): the same bits as the rank holding the floe computes.
  std::size_t k = 0;
  for (std::uint32_t i = 0; i < floes.size(); ++i) {
    if (k < held.size() && held[k] == i) {
      ++k;
      continue;
    }
    if (!floes.is_static[i]) floes.state[i] = drifted(floes.state[i], dt);
  }
}

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

void advance_on_part(const Communicator& comm, std::span<const int> owner, std::span<const std::uint32_t> mine,
                     Floes& floes, contact::CollisionShapes& shapes, const contact::Detection& part,
                     const WholeOnDemand& whole, double dt,
                     const contact::SubstepOptions& options, contact::CollisionStats& stats,
                     contact::SubstepReport& report, AdvanceShareCounts& counts,
                     const AdvanceShareOptions& share_options) {
  if (comm.serial())
    return advance_by_owner(comm, owner, floes, shapes, whole.detection(), dt, options, stats, report, counts,
                            share_options);
  // The advance reads the floes' states (W^+ of the collisions), never the
  // step-start copy: it asks for the states alone (96 B a floe the rank does
  // not hold, when they are not whole).
  // The whole paths below read every floe's shape: those this rank does not
  // hold (contact/shapes.hpp) built from their vertices first.
  if (counts.whole_now()) {
    whole.state(WholeState::state);
    shapes.ensure_every(floes);
    contact::advance_with_collisions(floes, shapes, whole.detection(), dt, options, stats, report);
    return;
  }
  std::vector<FloeState> start = floes.state;
  bool start_whole = false;  // `start` holds every floe's current state (the rebuild gathered it)
  bool combined = false;
  // A try whose parts refuse only because clusters of two runners meet is
  // tried again with those clusters joined on one rank (JoinedClusters),
  // from the step's start, on the rooms, contact edges and pad edges
  // gathered in the first try (functions of the step's start: the same).
  JoinedClusters joined;
  contact::ShareRooms all;
  std::vector<contact::ContactEdge> pad_edges;
  // A rank whose part had no conflict and none of whose clusters a try
  // again joins elsewhere or takes in keeps that part and its floes' states
  // (`kept`, `kept_state`): its share would run the same clusters on the
  // same pairs again. It still makes the try's set-up and routing (its
  // part's pairs may go to a joined group's runner).
  std::optional<AdvancePart> kept;
  std::vector<FloeState> kept_state;
  for (int round = 0;; ++round) {
    if (round > 0) floes.state = start;
    // A run that keeps the impulse record: as advance_by_owner (the events'
    // places are the queue's keys, which read no list of the detection).
    contact::ImpulseRecord* const record = options.impulse.record;
    contact::ImpulseRecord own;
    contact::SubstepOptions own_options = options;
    if (record) own_options.impulse.record = &own;
    contact::ShareAdvance share(floes, shapes, part, dt, own_options, {owner, comm.rank(), joined.runners()}, true,
                                mine);
    if (round == 0) {
      std::vector<contact::ShareRooms> rooms = comm.allgather_parts(pack(share.rooms()), unpack_share_rooms);
      // A floe outrunning its reach on some rank (the flags gathered with the
      // rooms: the same on every rank): every rank rebuilds the pair list and
      // gathers the rooms again.
      if (any_outrun(rooms)) {
        ++counts.rebuilds;
        // The rebuild detects over every floe (the serial set-up's, contact::
        // Stepper::set_up_rebuilt): every floe's straight path and place from
        // its state at the step's start, which the floes still are (rooms()
        // moves none), made whole here; the fallback below starts again from
        // it. And every floe's reach from its owner (a rank wrote only its
        // band's at the detection, band18; 8 bytes a floe, in such a step only).
        whole.state(WholeState::state);
        shapes.ensure_every(floes);
        start = floes.state;
        start_whole = true;
        std::vector<double> reach = part.reach;
        comm.complete_owned(reach, owner);
        rooms = comm.allgather_parts(pack(share.rooms_rebuilt(reach)), unpack_share_rooms);
      }
      // The gathered conflicts are the same on every rank: all skip the
      // next exchanges alike.
      if (!combine_rooms(rooms, all)) {
        count_set_up(rooms, counts);
        break;
      }
    } else {
      // The set-up of the same pairs from the same start: the same rooms
      // as the first try's, whose gathered `all` the clusters read.
      const contact::ShareRooms again = share.rooms();
      FLOESIM_ASSERT(again.conflict == contact::ShareOutcome::Conflict::none && !again.outrun);
    }
    // The clusters are the same on every rank, and so are their runners.
    contact::ShareAdvance::Routes routes = share.clusters(all);
    // A jam-sized cluster (the same on every rank): every rank's pad edges first.
    if (routes.conflict == contact::ShareOutcome::Conflict::none && routes.pads) {
      if (round == 0) {
        ++counts.pads;
        pad_edges = comm.allgather<contact::ContactEdge>(share.pad_edges());
      }
      routes = share.pads(pad_edges);
    }
    if (routes.conflict != contact::ShareOutcome::Conflict::none) {
      ++counts.conflicts[conflict_name(routes.conflict)];
      break;
    }
    // Every rank's join candidates (8 bytes each), then the pairs touching a
    // cluster's members or candidates to its runner; with no cluster
    // anywhere (the same on every rank) nothing to route.
    if (routes.any_cluster) {
      const std::vector<contact::JoinCandidate> candidates =
          comm.allgather<contact::JoinCandidate>(routes.candidates);
      counts.candidates += static_cast<long>(candidates.size());
      const std::vector<std::pair<int, std::uint32_t>> to = share.routes(candidates);
      // The pairs with their floes (state at the start, mass, inertia,
      // collision shape, reach), which the share then reads from the
      // message (ShareAdvance::hold takes their start states into its
      // straight paths).
      share.hold(exchange_advance_pairs(comm, part, routed_pairs(part, to, comm.size()), floes, shapes,
                                        &counts.shape_bytes));
    }
    AdvancePart done;
    if (kept) {
      done = std::move(*kept);
      floes.state = std::move(kept_state);
      ++counts.kept;
    } else {
      done = share_part(share, share.advance(), floes, record ? &own : nullptr);
      move_not_held(floes, share.held(), dt);
    }
    kept.reset();
    // The parts' lists: each rank's part, or after a rebuild the whole
    // rebuilt list on every rank.
    const Gathered g = gather_and_combine(
        comm, done, start_whole ? PairLists::whole_on_every_rank : PairLists::one_part_a_rank, floes, stats,
        report, record, options.impulse.warm, counts);
    const std::vector<AdvancePart>& parts = g.parts;
    combined = g.combined;
    if (combined) {
      if (round > 0) ++counts.joined;
      break;
    }
    // Joined on one rank when every conflict is clusters of two runners
    // meeting; a step whose pair list was rebuilt whole is left to the
    // whole advance (its set-up is not the part's), and so is the last
    // try's conflict, counted by kind.
    if (!start_whole && round + 1 < share_options.max_rounds && joined.add(parts, share)) {
      ++counts.rounds;
      const bool touched = std::any_of(joined.runners().begin(), joined.runners().end(), [&](const auto& kr) {
        return kr.second == comm.rank() || share.runner_of_cluster(kr.first) == comm.rank();
      });
      if (done.outcome.conflict == contact::ShareOutcome::Conflict::none && !touched) {
        kept = std::move(done);
        kept_state = floes.state;
      }
      continue;
    }
    count_conflicts(parts, counts);
    if (std::any_of(parts.begin(), parts.end(), [](const AdvancePart& p) {
          return p.outcome.conflict == contact::ShareOutcome::Conflict::missing_pairs;
        }))
      ++counts.missing;
    break;
  }
  if (combined) {
    counts.combined();
    return;
  }
  counts.fell_back(share_options);
  floes.state = start;
  // After a rebuild `start` is whole already: the fallback gathers nothing more.
  if (!start_whole) whole.state(WholeState::state);
  shapes.ensure_every(floes);
  contact::advance_with_collisions(floes, shapes, whole.detection(), dt, options, stats, report);
}

}  // namespace floesim::parallel
