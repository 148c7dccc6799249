#pragma once
// Runs a simulation to its end time, recording on the output schedule into a
// run file. Records are written at t = 0, at every multiple of
// output_interval and at the end time; steps are shortened to land on them.

#include <functional>
#include <string>
#include <vector>

#include "coupling/simulation.hpp"

namespace floesim {

struct RunProgress {
  double t = 0.0, t_end = 0.0;
  std::size_t steps = 0;
  double wall_seconds = 0.0;
};

struct RunOptions {
  std::string output;                       // run file path (.h5)
  double until = -1.0;                      // s; < 0: [run] t_end
  std::function<void(const RunProgress&)> progress;  // called after every step
  std::function<bool()> should_stop;        // polled after every step (e.g. Ctrl-C)
};

struct RunSummary {
  std::string output, xdmf, status;         // status: complete | interrupted
  std::size_t steps = 0, records = 0;
  double t_end = 0.0, wall_seconds = 0.0;
  Energies energy_first, energy_last;
  std::vector<std::string> warnings;
  Profile profile;
  contact::CollisionStats collisions;
};

// Throws RunError when the numerics fail or the run file cannot be written
// (a full disk); the run file then says status = "failed: <reason>" and keeps
// every record written before. Any other exception is recorded so too, then
// passed on.
RunSummary run_simulation(Simulation& sim, const RunOptions& options);

}  // namespace floesim
