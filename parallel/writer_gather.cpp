#include "parallel/writer_gather.hpp"

#include <cstring>

#include "core/error.hpp"

namespace floesim::parallel {

namespace {

struct Vertical {
  double heave, pitch, roll;
};
static_assert(sizeof(FloeState) == 96 && sizeof(Vertical) == 24);

int vertical_of(std::span<const int> owner, std::span<const int> vertical_owner, std::size_t i) {
  return vertical_owner.empty() ? owner[i] : vertical_owner[i];
}

}  // namespace

std::vector<std::size_t> writer_counts(std::span<const int> owner, std::span<const int> vertical_owner, int ranks,
                                       int writer) {
  FLOESIM_ASSERT(vertical_owner.empty() || vertical_owner.size() == owner.size());
  std::vector<std::size_t> counts(static_cast<std::size_t>(ranks), 0);
  for (std::size_t i = 0; i < owner.size(); ++i) {
    counts[static_cast<std::size_t>(owner[i])] += sizeof(FloeState);
    const int v = vertical_of(owner, vertical_owner, i);
    if (v != owner[i]) counts[static_cast<std::size_t>(v)] += sizeof(Vertical);
  }
  counts[static_cast<std::size_t>(writer)] = 0;
  return counts;
}

std::vector<std::byte> writer_message(std::span<const FloeState> states, std::span<const int> owner,
                                      std::span<const int> vertical_owner, int rank, int writer) {
  std::vector<std::byte> out;
  if (rank == writer) return out;
  auto put = [&](const void* p, std::size_t n) {
    const auto* b = static_cast<const std::byte*>(p);
    out.insert(out.end(), b, b + n);
  };
  for (std::size_t i = 0; i < owner.size(); ++i)
    if (owner[i] == rank) put(&states[i], sizeof(FloeState));
  for (std::size_t i = 0; i < owner.size(); ++i) {
    const int v = vertical_of(owner, vertical_owner, i);
    if (v != rank || owner[i] == rank) continue;
    const Vertical d{states[i].heave, states[i].pitch, states[i].roll};
    put(&d, sizeof(Vertical));
  }
  return out;
}

void writer_assemble(std::vector<FloeState>& states, std::span<const std::byte> received,
                     std::span<const int> owner, std::span<const int> vertical_owner, int ranks, int writer) {
  const std::vector<std::size_t> counts = writer_counts(owner, vertical_owner, ranks, writer);
  std::vector<std::size_t> at(counts.size(), 0);
  for (std::size_t r = 1; r < counts.size(); ++r) at[r] = at[r - 1] + counts[r - 1];
  FLOESIM_ASSERT(at.back() + counts.back() == received.size());
  // The writer's own vertical DOFs of floes whose state another rank holds,
  // read before those states overwrite its copy.
  std::vector<Vertical> own_vertical;
  for (std::size_t i = 0; i < owner.size(); ++i)
    if (vertical_of(owner, vertical_owner, i) == writer && owner[i] != writer)
      own_vertical.push_back({states[i].heave, states[i].pitch, states[i].roll});
  for (std::size_t i = 0; i < owner.size(); ++i) {
    if (owner[i] == writer) continue;
    std::size_t& from = at[static_cast<std::size_t>(owner[i])];
    std::memcpy(static_cast<void*>(&states[i]), received.data() + from, sizeof(FloeState));
    from += sizeof(FloeState);
  }
  std::size_t own = 0;
  for (std::size_t i = 0; i < owner.size(); ++i) {
    const int v = vertical_of(owner, vertical_owner, i);
    if (v == owner[i]) continue;
    Vertical d;
    if (v == writer) {
      d = own_vertical[own++];
    } else {
      std::size_t& from = at[static_cast<std::size_t>(v)];
      std::memcpy(&d, received.data() + from, sizeof(Vertical));
      from += sizeof(Vertical);
    }
    states[i].heave = d.heave;
    states[i].pitch = d.pitch;
    states[i].roll = d.roll;
  }
}

}  // namespace floesim::parallel
