#pragma once
// One writer gathers the floes' states (docs/parallel.md, "One writer
// gathers the records and checkpoints"): the run file is written by the
// writer rank from the owners' copies, not from its own arrays, so that it
// stays right once a rank holds only its floes and a band.
//
// Who holds what: owner[i] holds floe i's whole state (the drift's owners
// by place, parallel::FloeOwners); vertical_owner[i], when given, holds its
// heave, pitch and roll (the coupling's owners, which drift them by owner
// and are not always the drift's: coupling/floe_sea.hpp complete_vertical).
// An empty vertical_owner means the drift's owners hold those too.
//
// Rank r's message to the writer: its floes' states (owner[i] == r, floe
// order, 96 B each), then the heave, pitch and roll of the floes it holds
// the vertical DOFs of but not the state (24 B each). The writer sends
// itself nothing. Plain data, so that simulated ranks can be tested in one
// process; Communicator::alltoall carries the messages (one call).

#include <cstddef>
#include <span>
#include <vector>

#include "core/floes.hpp"

namespace floesim::parallel {

// Bytes each rank sends to the writer (index: rank); zero for the writer itself.
std::vector<std::size_t> writer_counts(std::span<const int> owner, std::span<const int> vertical_owner, int ranks,
                                       int writer);

// Rank `rank`'s message to the writer, read from its copy `states` (only the
// entries it holds are read). Empty on the writer.
std::vector<std::byte> writer_message(std::span<const FloeState> states, std::span<const int> owner,
                                      std::span<const int> vertical_owner, int rank, int writer);

// On the writer: every floe's state from its holders. `states` is the
// writer's copy (its own floes' entries are read from it, the others'
// overwritten); `received` the messages of ranks 0..N-1 in rank order, as
// writer_counts sized them.
void writer_assemble(std::vector<FloeState>& states, std::span<const std::byte> received,
                     std::span<const int> owner, std::span<const int> vertical_owner, int ranks, int writer);

}  // namespace floesim::parallel
