#pragma once
// Runs a simulation to its end time, recording on the output schedule into a
// run file. Records are written at t = 0, at every multiple of
// output_interval and at the end time; steps are shortened to land on them.
//
// Checkpoints (core/checkpoint.hpp) go into the run file's /checkpoint: at
// the end of the first step at or after each multiple of [run]
// checkpoint_interval (> 0; after that step's record if it made one), at the
// end, and when should_stop() asks (after the step in progress). On a run
// error the state at the last record is written as the checkpoint. Writing
// one changes no bit of the run: a restart from it (RunOptions::resume)
// writes the records the run would have written.

#include <functional>
#include <string>
#include <vector>

#include "coupling/simulation.hpp"

namespace floesim {

struct RunProgress {
  double t = 0.0, t_end = 0.0;
  std::size_t steps = 0;
  double wall_seconds = 0.0;  // since this run_simulation started
  // Where this run_simulation started (a restart: its checkpoint), so that
  // rates and the time left count this run's steps only.
  double t_start = 0.0;
  std::size_t steps_start = 0;
};

struct RunOptions {
  std::string output;                       // run file path (.h5)
  double until = -1.0;                      // s; < 0: [run] t_end
  std::function<void(const RunProgress&)> progress;  // called after every step
  std::function<bool()> should_stop;        // polled after every step (e.g. Ctrl-C)
  // Continue the run file `output` from this checkpoint, which the
  // simulation was restored from (Simulation::restore): its records after
  // the checkpoint are dropped and the run goes on from there.
  const Checkpoint* resume = nullptr;
};

struct RunSummary {
  std::string output, xdmf, status;         // status: complete | interrupted
  double checkpoint_time = -1.0;            // s, of the last checkpoint written (< 0: none)
  std::size_t steps = 0, records = 0;
  double t_end = 0.0, wall_seconds = 0.0;
  Energies energy_first, energy_last;
  std::vector<std::string> notes;     // said once at the start (Simulation::notes: e.g. a calibrated blend)
  std::vector<std::string> warnings;  // what went wrong or was approximated (Simulation::warnings)
  Profile profile;
  contact::CollisionStats collisions;
};

// In a distributed run (Simulation::communicator() of several ranks) every
// rank calls this; rank 0 alone writes the run file (docs/parallel.md) and
// the ranks agree after every step on failures and on should_stop(), so an
// error on any rank ends every rank with that error and the file closed.
// Throws RunError when the numerics fail or the run file cannot be written
// (a full disk); the run file then says status = "failed: <reason>" and keeps
// every record written before. Any other exception is recorded so too, then
// passed on.
RunSummary run_simulation(Simulation& sim, const RunOptions& options);

}  // namespace floesim
