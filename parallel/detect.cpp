#include "parallel/detect.hpp"

#include <cstdint>
#include <cstring>
#include <type_traits>

namespace floesim::parallel {

static_assert(kSentAsBytes<contact::NearPair>);
static_assert(kSentAsBytes<contact::ContactPoint>);
static_assert(kSentAsBytes<contact::Witness>);

contact::Detection concatenate(std::vector<contact::Detection> parts) {
  contact::Detection out;
  if (parts.empty()) return out;
  out.reach = std::move(parts.front().reach);
  for (contact::Detection& part : parts) {
    const auto contacts = static_cast<std::uint32_t>(out.contacts.size());
    const auto witnesses = static_cast<std::uint32_t>(out.witnesses.size());
    for (contact::NearPair& p : part.pairs) {
      p.first_contact += contacts;
      p.first_witness += witnesses;
      out.pairs.push_back(p);
    }
    out.contacts.insert(out.contacts.end(), part.contacts.begin(), part.contacts.end());
    out.witnesses.insert(out.witnesses.end(), part.witnesses.begin(), part.witnesses.end());
  }
  return out;
}

namespace {
// A rank's part as one message: three counts, then the pairs, contact points
// and witnesses, each as bytes (copied in and out with memcpy, so the
// buffer's alignment does not matter).
template <class T>
void put(std::vector<std::byte>& out, const std::vector<T>& values) {
  const auto* bytes = reinterpret_cast<const std::byte*>(values.data());
  out.insert(out.end(), bytes, bytes + values.size() * sizeof(T));
}

template <class T>
std::vector<T> take(const std::byte*& at, std::uint64_t count) {
  std::vector<T> values(count);
  std::memcpy(static_cast<void*>(values.data()), at, count * sizeof(T));
  at += count * sizeof(T);
  return values;
}
}  // namespace

contact::Detection detect(const Communicator& comm, const Floes& floes, const contact::CollisionShapes& shapes,
                          contact::DetectionOptions options) {
  if (comm.serial()) return contact::detect(floes, shapes, options);
  options.part = static_cast<std::size_t>(comm.rank());
  options.parts = static_cast<std::size_t>(comm.size());
  contact::Detection mine = contact::detect(floes, shapes, options);
  const std::uint64_t sizes[3] = {mine.pairs.size(), mine.contacts.size(), mine.witnesses.size()};
  std::vector<std::byte> message(reinterpret_cast<const std::byte*>(sizes),
                                 reinterpret_cast<const std::byte*>(sizes) + sizeof(sizes));
  put(message, mine.pairs);
  put(message, mine.contacts);
  put(message, mine.witnesses);
  std::vector<std::size_t> counts;
  const std::vector<std::byte> all = comm.allgather_bytes(message, counts);
  std::vector<contact::Detection> parts(counts.size());
  const std::byte* at = all.data();
  for (contact::Detection& part : parts) {
    std::uint64_t n[3];
    std::memcpy(n, at, sizeof(n));
    at += sizeof(n);
    part.pairs = take<contact::NearPair>(at, n[0]);
    part.contacts = take<contact::ContactPoint>(at, n[1]);
    part.witnesses = take<contact::Witness>(at, n[2]);
  }
  parts.front().reach = std::move(mine.reach);  // the same on every rank
  return concatenate(std::move(parts));
}

}  // namespace floesim::parallel
