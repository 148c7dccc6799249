#pragma once
// The summary `floesim run` prints at a run's end: `key: value` lines that
// scripts and tests read (tests/parallel/*.py, tests/apps), one printer a
// block of them; print_summary prints them in their order.
#include <cstdint>
#include <iosfwd>
#include <string>
#include <vector>

#include "core/checkpoint.hpp"
#include "coupling/run.hpp"
#include "coupling/simulation.hpp"
#include "parallel/comm.hpp"

namespace floesim::apps {

// Each rank's per-floe structures (Simulation::floe_memory: every rank names
// the same structures in the same order), gathered to every rank: per rank
// (`stride` entries) its held floes, then per structure its bytes and its
// held floes' entries' bytes.
struct FloeMemoryAll {
  Simulation::FloeMemory memory;  // this rank's
  std::vector<std::uint64_t> all;
  std::size_t stride = 0;
};
// Collective: every rank calls it (serial: this rank's alone).
FloeMemoryAll gather_floe_memory(const Simulation& sim, const parallel::Communicator& comm);

struct SummaryInput {
  const RunSummary& run;
  const Simulation& sim;
  const parallel::Communicator& comm;
  parallel::Communicator::Traffic traffic;  // the run's collectives, read before the memory's gather
  FloeMemoryAll memory;
  std::string config;                  // the configuration's path, or "RUN (its config)" for a restart's own
  std::string restart_path;            // the run file a restart continued (empty: not a restart)
  const Checkpoint* restart = nullptr;  // and its checkpoint
  double setup_seconds = 0.0;          // s, the run's set-up on this rank, not the reading of the input
  bool profile = false;                // --profile: the time in each phase too
};

// Every block in order: the run, the energies, the collisions, the
// sub-steps, the fracture, the floe-sea contact, the memory, on several
// ranks the distribution (parallel.*), the notes and warnings, the profile.
void print_summary(std::ostream& o, const SummaryInput& in);

}  // namespace floesim::apps
