#pragma once
// The poison mode of the run (a test option of Simulation, not a user key;
// docs/parallel.md, "The poison mode of the run (piece 7; poison18)").
//
// The halo exchange that is to replace the drift's complete_owned (piece 8)
// leaves each rank with current values for the floes it holds only (its own
// floes and its band B_r); everything else is stale. This mode makes that
// visible on a real run: at the points where the exchanges will be, each
// rank overwrites its copies of the floes it does not hold with poison, and
// after each phase it looks for the poison in the floes it holds. A phase
// that reads a floe outside the held set then either carries NaN into a held
// floe (reported: phase, floe, field, rank) or, with the finite lure, gives
// another run file than the plain run.
//
// A window is opened (poison) where an exchange will send the held floes
// their values and closed (restore) before the next phase that is known to
// read every floe's place to decide owners (which would make the ranks
// disagree on the owners and stop the collectives instead of reporting):
//
//   after the drift's complete_owned  .. before the detection
//   after the detection               .. before the percussion
//   after the percussion              .. before the next drift
//
// A restore sends every floe's state from its owner (one complete_owned, by
// the owners of the window's start) and puts back the kept step-start copy
// and reaches; so what the run reads outside the windows is today's whole
// state, and each window tests the phases inside it only.
//
// What is poisoned, for the floes outside the window's held set: the state
// (12 columns), the step-start copy (StepContext::start: piece 8 leaves it
// stale too, it is taken from the state at the step's start) and the
// detection reach (set from the state by set_reach at the detection).
//
// Two poisons. NaN: a read that reaches a held floe shows up as NaN there
// (the check); but a NaN place that reaches an index computation (grid_row,
// a broad phase's cell) may crash before any check. The lure: finite values
// that are wrong (the floe moved by half the periodic box, or 1 km in the
// open plane, its rates changed, its reach grown): no crash, the run goes on,
// and a read shows as a run file that differs from the plain run.

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "contact/detection.hpp"
#include "core/floes.hpp"
#include "parallel/comm.hpp"

namespace floesim {

struct PoisonOptions {
  enum class Kind { nan, lure };
  Kind kind = Kind::nan;
  // The mutation of the tests: this rank's lowest held floe is poisoned too
  // (and never restored), so the first check must report it.
  bool mutant = false;
  // The mutation of the whole state on demand's test: the windows do not
  // say that the unheld floes are stale (Simulation::whole_state gathers
  // nothing), so a step that reads every floe reads the poison.
  bool stale = false;
  // Which windows are opened (above; all by default).
  bool after_drift = true, after_detect = true, after_percussion = true;
};

// Parses the test hook's value: "step" (NaN), "step-lure", "step-mutant",
// each optionally followed by "-stale" (PoisonOptions::stale:
// "step-lure-stale"), then optionally by "@" and the windows to open, of
// "drift", "detect" and "percussion" joined by '+' (e.g.
// "step-lure@drift+percussion"); all three without. Returns false if `text` is not of this form.
bool parse_poison_options(const std::string& text, PoisonOptions& options);

class UnheldPoison {
public:
  UnheldPoison(PoisonOptions options, int rank) : options_(options), rank_(rank) {}
  const PoisonOptions& options() const { return options_; }

  // Opens a window: every floe i with !held[i] gets the poison in `state`,
  // in `start` (if given) and in `reach`; their values are kept for the
  // restore, with `owner` (every floe's owner on every rank, alike).
  void poison(std::span<const std::uint8_t> held, std::span<const int> owner, std::vector<FloeState>& state,
              std::vector<FloeState>* start, std::vector<double>& reach, const contact::Domain& domain);
  // Closes the window (nothing if none is open): the unheld floes' states
  // from their owners (collective), the kept reaches, and in `start` (if
  // given) the kept step-start copy, or, with `start_from_state`, the state
  // kept at the window's opening (a window opened before the step's start
  // copy was taken, the state unchanged between).
  void restore(const parallel::Communicator& comm, std::vector<FloeState>& state, std::vector<FloeState>* start,
               std::vector<double>& reach, bool start_from_state = false);
  // Looks for NaN in the held floes' state, `start` (if given) and reach;
  // the first found after a phase is reported once a phase (stderr, and
  // reports()). Nothing when no window is open.
  void check(const char* phase, const std::vector<FloeState>& state, const std::vector<FloeState>* start,
             std::span<const double> reach);

  bool open() const { return open_; }
  // Windows opened and floes poisoned in them (summed over the windows).
  long long windows() const { return windows_; }
  long long poisoned() const { return poisoned_; }
  // The phase after which the last check was made (a run that fails or
  // crashes failed in the phase after it); empty before the first.
  const std::string& last_checked() const { return last_checked_; }
  const std::vector<std::string>& reports() const { return reports_; }

private:
  PoisonOptions options_;
  int rank_ = 0;
  bool open_ = false;
  long long windows_ = 0, poisoned_ = 0;
  std::string last_checked_;
  std::vector<std::uint8_t> held_;
  std::vector<int> owner_;
  std::vector<std::uint32_t> unheld_;
  std::vector<FloeState> kept_state_, kept_start_;
  std::vector<double> kept_reach_;
  std::vector<std::string> reported_phases_, reports_;
};

}  // namespace floesim
