#pragma once
// What a per-floe structure allocates on a rank, against what the entries of
// the floes the rank holds would take of it (docs/parallel.md, "The arrays
// held by band: measured (mem27)"). Issue 21 asks each rank to keep its own
// floes and its halo band; a structure indexed by every floe costs each rank
// the whole pack, which at 10^6 floes and 1024 ranks is what every rank pays
// for a share of about 1/1000 of it. The figures say which structure to hold
// by band first.
//
//   whole: the bytes its arrays hold now: their capacity (what the allocator
//          gave), not their size;
//   held:  the bytes of the held floes' entries alone, as a layout that
//          stores only them would size them: the count of their entries
//          times an entry's bytes; for a CSR structure (offsets into item
//          arrays) one offset a held floe, plus one, and the items of the
//          held floes' ranges.
// A held mask is per floe, 1 if held; empty: every floe (one rank).

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace floesim {

struct FloeBytes {
  std::size_t whole = 0, held = 0;
  FloeBytes& operator+=(const FloeBytes& o) {
    whole += o.whole;
    held += o.held;
    return *this;
  }
};

template <class T>
std::size_t capacity_bytes(const std::vector<T>& v) {
  return v.capacity() * sizeof(T);
}

// How many floes of n a mask holds (empty: every floe).
inline std::size_t held_count(std::span<const std::uint8_t> held, std::size_t n) {
  if (held.empty()) return n;
  std::size_t k = 0;
  for (const std::uint8_t h : held) k += h != 0;
  return k;
}

// An array of one entry a floe, of which `held` floes' entries are needed
// (none when it is empty: a run that does not use it).
template <class T>
FloeBytes per_floe_bytes(const std::vector<T>& v, std::size_t held) {
  return {capacity_bytes(v), v.empty() ? 0 : held * sizeof(T)};
}

// The items the held floes' ranges [offsets[i], offsets[i + 1]) span (every
// floe's with an empty mask; floes past the offsets' end own none).
inline std::size_t held_items(std::span<const std::size_t> offsets, std::span<const std::uint8_t> held) {
  if (offsets.empty()) return 0;
  const std::size_t n = offsets.size() - 1;
  if (held.empty()) return offsets[n] - offsets[0];
  std::size_t k = 0;
  for (std::size_t i = 0; i < n && i < held.size(); ++i)
    if (held[i]) k += offsets[i + 1] - offsets[i];
  return k;
}

// A CSR structure: `offsets` (one a floe and one more) into item arrays
// whose capacities sum to `item_capacity` bytes, an item taking
// `item_bytes` bytes over them.
inline FloeBytes csr_bytes(const std::vector<std::size_t>& offsets, std::size_t item_capacity,
                           std::size_t item_bytes, std::span<const std::uint8_t> held) {
  const std::size_t n = offsets.empty() ? 0 : offsets.size() - 1;
  return {capacity_bytes(offsets) + item_capacity,
          (held_count(held, n) + 1) * sizeof(std::size_t) + held_items(offsets, held) * item_bytes};
}

}  // namespace floesim
