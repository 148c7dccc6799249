#include "parallel/detect.hpp"

#include <algorithm>
#include <cstdint>
#include <numeric>
#include <utility>

#include "core/error.hpp"

#include "parallel/bytes.hpp"

namespace floesim::parallel {

static_assert(kSentAsBytes<contact::NearPair>);
static_assert(kSentAsBytes<contact::ContactPoint>);
static_assert(kSentAsBytes<contact::Witness>);

contact::Detection merge(std::vector<contact::Detection> parts) {
  contact::Detection out;
  if (parts.empty()) return out;
  out.reach = std::move(parts.front().reach);
  std::size_t pairs = 0, contacts = 0, witnesses = 0;
  for (const contact::Detection& part : parts) {
    pairs += part.pairs.size();
    contacts += part.contacts.size();
    witnesses += part.witnesses.size();
  }
  out.pairs.reserve(pairs);
  out.contacts.reserve(contacts);
  out.witnesses.reserve(witnesses);
  // A merge of sorted lists: the next pair is the first of the parts' next
  // ones (a scan of the parts: few ranks).
  std::vector<std::size_t> next(parts.size(), 0);
  for (std::size_t taken = 0; taken < pairs; ++taken) {
    std::size_t from = parts.size();
    for (std::size_t k = 0; k < parts.size(); ++k)
      if (next[k] < parts[k].pairs.size() &&
          (from == parts.size() || contact::pair_before(parts[k].pairs[next[k]], parts[from].pairs[next[from]])))
        from = k;
    append_pair(out, parts[from], parts[from].pairs[next[from]++]);
  }
  return out;
}

void append_pair(contact::Detection& to, const contact::Detection& from, const contact::NearPair& p) {
  const auto c0 = from.contacts.begin() + p.first_contact;
  const auto w0 = from.witnesses.begin() + p.first_witness;
  contact::NearPair q = p;
  q.first_contact = static_cast<std::uint32_t>(to.contacts.size());
  q.first_witness = static_cast<std::uint32_t>(to.witnesses.size());
  to.contacts.insert(to.contacts.end(), c0, c0 + p.contact_count);
  to.witnesses.insert(to.witnesses.end(), w0, w0 + p.witness_count);
  to.pairs.push_back(q);
}

RoutedFloes routed_floes(const Floes& floes, std::span<const FloeState> start, const contact::Detection& pairs) {
  RoutedFloes out;
  for (const contact::NearPair& p : pairs.pairs) {
    out.floe.push_back(p.a);
    out.floe.push_back(p.b);
  }
  std::sort(out.floe.begin(), out.floe.end());
  out.floe.erase(std::unique(out.floe.begin(), out.floe.end()), out.floe.end());
  for (const std::uint32_t i : out.floe) {
    out.now.push_back(floes.state[i]);
    if (!start.empty()) out.start.push_back(start[i]);
    out.mass.push_back(floes.mass[i]);
    out.inertia_z.push_back(floes.inertia_z[i]);
  }
  return out;
}

void hold(const RoutedFloes& routed, Floes& floes, std::span<FloeState> start) {
  for (std::size_t k = 0; k < routed.floe.size(); ++k) {
    const std::uint32_t i = routed.floe[k];
    floes.state[i] = routed.now[k];
    if (!routed.start.empty()) start[i] = routed.start[k];
    floes.mass[i] = routed.mass[k];
    floes.inertia_z[i] = routed.inertia_z[k];
  }
}

std::vector<std::byte> pack(const RoutedFloes& r) {
  const std::uint64_t n[2] = {r.floe.size(), r.start.size()};
  std::vector<std::byte> out;
  append(out, std::span<const std::uint64_t>(n, 2));
  append(out, std::span<const std::uint32_t>(r.floe));
  append(out, std::span<const FloeState>(r.now));
  append(out, std::span<const FloeState>(r.start));
  append(out, std::span<const double>(r.mass));
  append(out, std::span<const double>(r.inertia_z));
  return out;
}

RoutedFloes unpack_routed_floes(std::span<const std::byte> bytes) {
  const std::byte* at = bytes.data();
  RoutedFloes r;
  const std::vector<std::uint64_t> counts = take<std::uint64_t>(at, 2);
  const auto n = static_cast<std::size_t>(counts[0]);
  r.floe = take<std::uint32_t>(at, n);
  r.now = take<FloeState>(at, n);
  r.start = take<FloeState>(at, static_cast<std::size_t>(counts[1]));
  r.mass = take<double>(at, n);
  r.inertia_z = take<double>(at, n);
  FLOESIM_ASSERT(at == bytes.data() + bytes.size());
  return r;
}

std::vector<std::byte> pack_routed(const contact::Detection& pairs, const Pieces& pieces) {
  const std::vector<std::byte> bytes = pack(pairs);
  std::vector<std::uint64_t> sizes;
  for (std::size_t k = 0; k < pieces.size(); ++k) sizes.push_back(k == 0 ? bytes.size() : pieces[k - 1].size());
  std::vector<std::byte> out;
  append(out, std::span<const std::uint64_t>(sizes));
  out.insert(out.end(), bytes.begin(), bytes.end());
  for (const std::vector<std::byte>& piece : pieces) out.insert(out.end(), piece.begin(), piece.end());
  return out;
}

contact::Detection unpack_routed(std::span<const std::byte> message, std::size_t count, Pieces& pieces) {
  const std::byte* at = message.data();
  const std::byte* const end = at + message.size();
  // The sizes written (the pairs' and every piece's but the last), then the
  // last's: the rest of the message (the pairs' without pieces).
  std::vector<std::uint64_t> sizes = take<std::uint64_t>(at, count);
  const std::uint64_t written = std::accumulate(sizes.begin(), sizes.end(), std::uint64_t{0});
  FLOESIM_ASSERT(static_cast<std::uint64_t>(end - at) >= written);
  sizes.push_back(static_cast<std::uint64_t>(end - at) - written);
  contact::Detection pairs = unpack_detection(std::span<const std::byte>(at, static_cast<std::size_t>(sizes[0])));
  at += sizes[0];
  pieces.clear();
  for (std::size_t k = 1; k <= count; ++k) {
    pieces.emplace_back(at, at + sizes[k]);
    at += sizes[k];
  }
  return pairs;
}

contact::Detection exchange_pairs(const Communicator& comm, const contact::Detection& part,
                                  const std::vector<contact::Detection>& outgoing, Carried* carried) {
  const std::size_t count = carried ? carried->pieces : 0;
  static const Pieces none;
  std::vector<std::byte> send;
  std::vector<std::size_t> send_counts;
  for (std::size_t s = 0; s < outgoing.size(); ++s) {
    if (outgoing[s].pairs.empty()) {
      send_counts.push_back(0);
      continue;
    }
    const Pieces& pieces = count > 0 ? std::as_const(carried->outgoing[s]) : none;
    FLOESIM_ASSERT(pieces.size() == count);
    const std::vector<std::byte> message = pack_routed(outgoing[s], pieces);
    send.insert(send.end(), message.begin(), message.end());
    send_counts.push_back(message.size());
  }
  std::vector<std::byte> got;
  std::vector<std::size_t> got_counts;
  comm.alltoall_bytes(send, send_counts, got, got_counts);
  std::vector<contact::Detection> parts{part};
  if (carried) carried->received.clear();
  std::size_t from = 0;
  for (const std::size_t n : got_counts) {
    if (n) {
      Pieces pieces;
      parts.push_back(unpack_routed(std::span<const std::byte>(got.data() + from, n), count, pieces));
      if (carried) carried->received.push_back(std::move(pieces));
    }
    from += n;
  }
  return merge(std::move(parts));
}

contact::Detection detect_part(const FloeOwners& owners, int rank, const Floes& floes,
                               const contact::CollisionShapes& shapes, contact::DetectionOptions options,
                               const HeldFloes* held) {
  options.subset = detection_subset(owners, rank, floes, shapes, options, held);
  // The shapes may be held by band (contact/shapes.hpp): a floe posed
  // without its parts would have an empty box and no pair, silently.
  for (const std::uint32_t i : options.subset.posed)
    if (!shapes.has(i))
      throw RunError("the detection of rank " + std::to_string(rank) + "'s part: floe " + std::to_string(i) +
                     " is posed without its collision shape (not built where it is held)");
  return contact::detect(floes, shapes, options);
}

std::vector<std::byte> pack(const contact::Detection& d) {
  const std::uint64_t sizes[3] = {d.pairs.size(), d.contacts.size(), d.witnesses.size()};
  std::vector<std::byte> message(sizeof(sizes) + d.pairs.size() * sizeof(contact::NearPair) +
                                 d.contacts.size() * sizeof(contact::ContactPoint) +
                                 d.witnesses.size() * sizeof(contact::Witness));
  std::byte* at = put(message.data(), sizes, 3);
  at = put(at, d.pairs.data(), d.pairs.size());
  at = put(at, d.contacts.data(), d.contacts.size());
  put(at, d.witnesses.data(), d.witnesses.size());
  return message;
}

contact::Detection unpack_detection(std::span<const std::byte> bytes) {
  const std::byte* at = bytes.data();
  contact::Detection part;
  const std::vector<std::uint64_t> n = take<std::uint64_t>(at, 3);
  part.pairs = take<contact::NearPair>(at, n[0]);
  part.contacts = take<contact::ContactPoint>(at, n[1]);
  part.witnesses = take<contact::Witness>(at, n[2]);
  return part;
}

contact::Detection gather(const Communicator& comm, const contact::Detection& part,
                          std::span<const std::uint32_t> own) {
  if (comm.serial()) return part;
  // One message a rank: its part, then its own floes and their reaches.
  std::vector<std::byte> message = pack(part);
  const std::uint64_t count = own.size();
  append(message, std::span<const std::uint64_t>(&count, 1));
  append(message, own);
  std::vector<double> reach(own.size());
  for (std::size_t k = 0; k < own.size(); ++k) reach[k] = part.reach[own[k]];
  append(message, std::span<const double>(reach));
  struct Received {
    contact::Detection part;
    std::vector<std::uint32_t> own;
    std::vector<double> reach;
  };
  std::vector<Received> got = comm.allgather_parts(message, [](std::span<const std::byte> bytes) {
    Received r;
    const std::byte* at = bytes.data();
    const std::vector<std::uint64_t> n = take<std::uint64_t>(at, 3);
    r.part.pairs = take<contact::NearPair>(at, n[0]);
    r.part.contacts = take<contact::ContactPoint>(at, n[1]);
    r.part.witnesses = take<contact::Witness>(at, n[2]);
    const auto k = static_cast<std::size_t>(take<std::uint64_t>(at, 1)[0]);
    r.own = take<std::uint32_t>(at, k);
    r.reach = take<double>(at, k);
    FLOESIM_ASSERT(at == bytes.data() + bytes.size());
    return r;
  });
  std::vector<contact::Detection> parts;
  parts.reserve(got.size());
  for (Received& r : got) parts.push_back(std::move(r.part));
  // Every floe's reach from its owner at the detection (the ranks' own
  // floes partition the pack); a rank holds only its band's others.
  parts.front().reach = part.reach;
  for (const Received& r : got)
    for (std::size_t k = 0; k < r.own.size(); ++k) parts.front().reach[r.own[k]] = r.reach[k];
  return merge(std::move(parts));
}

long long overlap_key(const contact::Detection& part) {
  for (const contact::NearPair& p : part.pairs)
    if (p.overlap) return static_cast<long long>(p.a) << 32 | p.b;
  return kNoOverlap;
}

bool distance_before(const contact::Detection& previous, std::uint32_t a, std::uint32_t b, double& distance) {
  bool found = false;
  for (const contact::NearPair& q : previous.pairs)
    if (q.a == a && q.b == b) {
      distance = q.distance;
      found = true;
    }
  return found;
}

Overlap first_overlap(const Communicator& comm, const contact::Detection& part, const contact::Detection& previous) {
  const long long key = comm.min(overlap_key(part));
  Overlap o;
  if (key == kNoOverlap) return o;
  o.any = true;
  o.a = static_cast<std::uint32_t>(key >> 32);
  o.b = static_cast<std::uint32_t>(key & 0xffffffffLL);
  struct Found {
    double distance = -1.0;
    long long found = 0;
  };
  Found mine;
  mine.found = distance_before(previous, o.a, o.b, mine.distance) ? 1 : 0;
  for (const Found& f : comm.allgather<Found>(std::span<const Found>(&mine, 1)))
    if (f.found) {
      o.before = f.distance;
      break;
    }
  return o;
}

contact::Detection detect(const Communicator& comm, FloeOwners& owners, const Floes& floes,
                          const contact::CollisionShapes& shapes, contact::DetectionOptions options,
                          contact::Detection* part, bool whole_too, const HeldFloes* held) {
  if (comm.serial()) {
    contact::Detection whole = contact::detect(floes, shapes, options);
    if (part) *part = whole;
    return whole;
  }
  const double start = thread_seconds();
  contact::Detection mine = detect_part(owners, comm.rank(), floes, shapes, std::move(options), held);
  owners.charge(thread_seconds() - start);
  contact::Detection whole = whole_too || !part ? gather(comm, mine, owners.mine()) : contact::Detection{};
  if (part) *part = std::move(mine);
  return whole;
}

}  // namespace floesim::parallel
