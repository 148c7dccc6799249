#pragma once
// One writer gathers the floes' states (docs/parallel.md, "One writer
// gathers the records and checkpoints"): the run file is written by the
// writer rank from the owners' copies, not from its own arrays, so that it
// stays right once a rank holds only its floes and a band.
//
// owner[i] is the rank holding floe i's state between two steps: the
// drift's owners by place (parallel::FloeOwners), whose states the next
// drift's exchange sends; the vertical DOFs too (every rank drifts every
// floe's). Rank r's message to the writer: its floes' states in floe order,
// 96 B each; the writer sends itself nothing. Plain data, so that simulated
// ranks can be tested in one process; Communicator::alltoall carries the
// messages (one call).

#include <cstddef>
#include <span>
#include <vector>

#include "core/floes.hpp"

namespace floesim::parallel {

// Bytes each rank sends to the writer (index: rank); zero for the writer itself.
std::vector<std::size_t> writer_counts(std::span<const int> owner, int ranks, int writer);

// Rank `rank`'s message to the writer, read from its copy `states` (only the
// entries it owns are read). Empty on the writer.
std::vector<std::byte> writer_message(std::span<const FloeState> states, std::span<const int> owner, int rank,
                                      int writer);

// On the writer: every floe's state from its owner. `states` is the
// writer's copy (its own floes' entries are kept, the others' overwritten);
// `received` the messages of ranks 0..N-1 in rank order, as writer_counts
// sized them.
void writer_assemble(std::vector<FloeState>& states, std::span<const std::byte> received,
                     std::span<const int> owner, int ranks, int writer);

}  // namespace floesim::parallel
