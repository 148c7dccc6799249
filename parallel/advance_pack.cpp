// The advance's messages (parallel/advance_share.hpp): the bytes of a
// share's part (AdvancePart, with its impulse record and warm-store writes),
// of its set-up's rooms (contact::ShareRooms) and of the routed floes'
// shapes (RoutedShapes), and their reading back. The layouts are here only:
// the writer and the reader of each sit side by side.
#include "parallel/advance_share.hpp"

#include <array>
#include <tuple>
#include <utility>

#include "core/error.hpp"
#include "parallel/bytes.hpp"

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

}  // namespace floesim::parallel
