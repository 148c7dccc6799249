#pragma once
// The poison mode of the run (a test option of Simulation, not a user key;
// docs/parallel.md, "The poison mode of the run (piece 7; poison18)").
//
// With the state held by owner (the halo exchange, docs/parallel.md "The
// halo exchange (halo26)") each rank's copies of the floes it does not hold
// (its own floes, its band B_r, its coupling's own floes: held_now()) are
// stale between the exchanges. This mode makes them visibly wrong: right
// after each exchange (a, after the drift; b, at the detection) each rank
// overwrites its copies of the floes it does not hold with poison, and
// after each phase it looks for the poison in the floes it holds. A phase
// that reads a floe outside the held set then either carries NaN into a
// held floe (reported: phase, floe, field, rank) or, with the finite lure,
// gives another run file than the plain run.
//
// Nothing is restored: what takes the poison away is the run's own
// traffic, the exchanges (which write the held floes) and the gathers of
// the whole state where a step reads every floe (Simulation::whole_state:
// the pair list's rebuild, the fallbacks, a split). So a run in the mode
// equals the plain run exactly when no phase reads an unheld floe. Where
// the run keeps the whole state (the implicit step,
// the advance from the whole detection: Simulation::halo_exchange() false)
// the drift still sends every state to every rank and the poison after it
// is read: those runs fail or differ, by design (their readers are known).
// With the implicit step every rank holds every floe's vertical DOFs
// (heave, pitch, roll and their rates: the replicated solve writes them
// alike on every rank, Simulation::held_now) besides its held floes' whole
// state: there the mode poisons the other columns only (the horizontal
// state: place, yaw and their rates, in the state and the step-start copy)
// and checks every floe's vertical DOFs too.
//
// What is poisoned, for the floes outside the held set: the state (12
// columns), the step-start copy (StepContext::start, taken from the state at
// the step's start: as stale) and the detection reach (the band's come with
// the notices; the others are not written).
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

namespace floesim {

struct PoisonOptions {
  enum class Kind { nan, lure };
  Kind kind = Kind::nan;
  // The mutation of the tests: this rank's lowest held floe is poisoned too,
  // so the first check must report it.
  bool mutant = false;
  // The mutation of the sea's check ("step-mutant-sea"): this rank's lowest
  // held floe's heave is NaN too, its place left finite, so that the
  // coupling poses it where it is and its penalty pressure, NaN, reaches
  // the sea at the next kick (check_sea must report it).
  bool mutant_sea = false;
  // The mutation of the whole state on demand's test: Simulation::whole_state
  // gathers nothing, so a step that reads every floe reads the poison.
  bool stale = false;
  // After which exchange the unheld floes are poisoned (both by default).
  bool after_drift = true, after_detect = true;
};

// Parses the test hook's value: "step" (NaN), "step-lure", "step-mutant",
// "step-mutant-sea",
// each optionally followed by "-stale" (PoisonOptions::stale:
// "step-lure-stale"), then optionally by "@" and the exchanges after which
// to poison, "drift" and "detect" joined by '+' (e.g. "step-lure@drift");
// both without. Returns false if `text` is not of this form.
bool parse_poison_options(const std::string& text, PoisonOptions& options);

class UnheldPoison {
public:
  UnheldPoison(PoisonOptions options, int rank) : options_(options), rank_(rank) {}
  const PoisonOptions& options() const { return options_; }

  // With the implicit step (set before the first poison): every floe's
  // vertical DOFs are held, the unheld floes' horizontal state only is
  // poisoned.
  void hold_vertical(bool every_floe) { vertical_held_ = every_floe; }

  // Poisons every floe i with !held[i] in `state`, in `start` (if given)
  // and in `reach` (where it has a value), and keeps `held` for the checks,
  // with `kept` (a subset of `held`, the same size): the held floes whose
  // step-start copy and reach the run keeps current too; the others are
  // held for their state alone (a flume's floes of its rank's share of the
  // columns outside its band: the coupling reads their state only, and
  // the drift's exchange that brings it to a new holder carries no
  // step-start copy and no reach).
  void poison(std::span<const std::uint8_t> held, std::span<const std::uint8_t> kept, std::vector<FloeState>& state,
              std::vector<FloeState>* start, std::vector<double>& reach, const contact::Domain& domain);
  // Looks for NaN in the held floes' state and the kept floes' `start` (if
  // given) and reach (and with hold_vertical, in every floe's vertical
  // DOFs); the first found after a phase is reported once a
  // phase (stderr, and reports()). Nothing before the first poison.
  void check(const char* phase, const std::vector<FloeState>& state, const std::vector<FloeState>* start,
             std::span<const double> reach);

  // The sea's check after a phase: `sea_finite` is the sea's
  // fluid::Sea::finite_state() on this rank (its slab's modes, or the whole
  // sea on a sea not in slabs). A NaN there came from a floe a phase read
  // (the pressures are made from the floes): reported once a phase as for
  // a floe, "sea's modal state is NaN". Nothing before the first poison.
  // A NaN a rank carries into its sea may reach no held floe and no file
  // (on a rank that does not write it), so the floes' check alone would
  // not see it.
  void check_sea(const char* phase, bool sea_finite);

  bool open() const { return open_; }
  // Times the unheld floes were poisoned (windows) and floes poisoned (summed over them).
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
  bool vertical_held_ = false;  // hold_vertical
  long long windows_ = 0, poisoned_ = 0;
  std::string last_checked_;
  std::vector<std::uint8_t> held_, kept_;
  std::vector<std::string> reported_phases_, reported_sea_phases_, reports_;
};

}  // namespace floesim
