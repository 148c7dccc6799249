#include "parallel/writer_gather.hpp"

#include <cstring>

#include "core/error.hpp"

namespace floesim::parallel {

static_assert(sizeof(FloeState) == 96);

std::vector<std::size_t> writer_counts(std::span<const int> owner, int ranks, int writer) {
  std::vector<std::size_t> counts(static_cast<std::size_t>(ranks), 0);
  for (const int o : owner) counts[static_cast<std::size_t>(o)] += sizeof(FloeState);
  counts[static_cast<std::size_t>(writer)] = 0;
  return counts;
}

std::vector<std::byte> writer_message(std::span<const FloeState> states, std::span<const int> owner, int rank,
                                      int writer) {
  std::vector<std::byte> out;
  if (rank == writer) return out;
  for (std::size_t i = 0; i < owner.size(); ++i) {
    if (owner[i] != rank) continue;
    const auto* b = reinterpret_cast<const std::byte*>(&states[i]);
    out.insert(out.end(), b, b + sizeof(FloeState));
  }
  return out;
}

void writer_assemble(std::vector<FloeState>& states, std::span<const std::byte> received,
                     std::span<const int> owner, int ranks, int writer) {
  const std::vector<std::size_t> counts = writer_counts(owner, ranks, writer);
  std::vector<std::size_t> at(counts.size(), 0);
  for (std::size_t r = 1; r < counts.size(); ++r) at[r] = at[r - 1] + counts[r - 1];
  FLOESIM_ASSERT(at.back() + counts.back() == received.size());
  // Rank r's states come in the order of its floes.
  for (std::size_t i = 0; i < owner.size(); ++i) {
    if (owner[i] == writer) continue;
    std::size_t& from = at[static_cast<std::size_t>(owner[i])];
    std::memcpy(static_cast<void*>(&states[i]), received.data() + from, sizeof(FloeState));
    from += sizeof(FloeState);
  }
}

}  // namespace floesim::parallel
