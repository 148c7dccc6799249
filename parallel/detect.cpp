#include "parallel/detect.hpp"

#include <cstdint>
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

contact::Detection detect(const Communicator& comm, const Floes& floes, const contact::CollisionShapes& shapes,
                          contact::DetectionOptions options) {
  if (comm.serial()) return contact::detect(floes, shapes, options);
  options.part = static_cast<std::size_t>(comm.rank());
  options.parts = static_cast<std::size_t>(comm.size());
  contact::Detection mine = contact::detect(floes, shapes, options);
  // Three gathers (pairs, contacts, witnesses) and the counts that split them back into parts.
  const long long sizes[3] = {static_cast<long long>(mine.pairs.size()), static_cast<long long>(mine.contacts.size()),
                              static_cast<long long>(mine.witnesses.size())};
  const std::vector<long long> counts = comm.allgather(std::span<const long long>(sizes, 3));
  const std::vector<contact::NearPair> pairs = comm.allgather(std::span<const contact::NearPair>(mine.pairs));
  const std::vector<contact::ContactPoint> contacts =
      comm.allgather(std::span<const contact::ContactPoint>(mine.contacts));
  const std::vector<contact::Witness> witnesses = comm.allgather(std::span<const contact::Witness>(mine.witnesses));
  std::vector<contact::Detection> parts(static_cast<std::size_t>(comm.size()));
  std::size_t p = 0, c = 0, w = 0;
  for (std::size_t r = 0; r < parts.size(); ++r) {
    const auto np = static_cast<std::size_t>(counts[3 * r]), nc = static_cast<std::size_t>(counts[3 * r + 1]),
               nw = static_cast<std::size_t>(counts[3 * r + 2]);
    parts[r].pairs.assign(pairs.begin() + static_cast<std::ptrdiff_t>(p), pairs.begin() + static_cast<std::ptrdiff_t>(p + np));
    parts[r].contacts.assign(contacts.begin() + static_cast<std::ptrdiff_t>(c),
                             contacts.begin() + static_cast<std::ptrdiff_t>(c + nc));
    parts[r].witnesses.assign(witnesses.begin() + static_cast<std::ptrdiff_t>(w),
                              witnesses.begin() + static_cast<std::ptrdiff_t>(w + nw));
    p += np;
    c += nc;
    w += nw;
  }
  parts.front().reach = std::move(mine.reach);  // the same on every rank
  return concatenate(std::move(parts));
}

}  // namespace floesim::parallel
