#include "coupling/poison_mode.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>

namespace floesim {

namespace {
constexpr double kNan = std::numeric_limits<double>::quiet_NaN();

FloeState nan_state() { return FloeState{kNan, kNan, kNan, kNan, kNan, kNan, kNan, kNan, kNan, kNan, kNan, kNan}; }

// Finite and wrong: half the periodic box away (still in it), or 1 km in
// the open plane; rates changed so that a read of them changes momenta.
FloeState lured(FloeState s, const contact::Domain& d) {
  if (d.periodic) {
    s.x = d.xmin + std::fmod(s.x - d.xmin + 0.5 * d.width(), d.width());
    s.y = d.ymin + std::fmod(s.y - d.ymin + 0.5 * d.height(), d.height());
  } else {
    s.x += 1000.0;
    s.y += 1000.0;
  }
  s.vx += 0.5;
  s.vy -= 0.5;
  s.yaw_rate += 0.01;
  return s;
}

int first_nan(const FloeState& s) {
  const double* v = reinterpret_cast<const double*>(&s);
  for (int k = 0; k < kStateColumns; ++k)
    if (std::isnan(v[k])) return k;
  return -1;
}
}  // namespace

bool parse_poison_options(const std::string& text, PoisonOptions& options) {
  PoisonOptions o;
  std::string kind = text, window;
  if (const auto at = text.find('@'); at != std::string::npos) {
    kind = text.substr(0, at);
    window = text.substr(at + 1);
  }
  const std::string stale = "-stale";
  if (kind.size() > stale.size() && kind.ends_with(stale)) {
    o.stale = true;
    kind.resize(kind.size() - stale.size());
  }
  if (kind == "step-lure") o.kind = PoisonOptions::Kind::lure;
  else if (kind == "step-mutant") o.mutant = true;
  else if (kind != "step") return false;
  if (!window.empty()) {  // one or more windows, joined by '+'
    o.after_drift = o.after_detect = o.after_percussion = false;
    for (std::size_t at = 0; at <= window.size();) {
      const std::size_t end = std::min(window.find('+', at), window.size());
      const std::string w = window.substr(at, end - at);
      if (w == "drift") o.after_drift = true;
      else if (w == "detect") o.after_detect = true;
      else if (w == "percussion") o.after_percussion = true;
      else return false;
      at = end + 1;
    }
  }
  options = o;
  return true;
}

void UnheldPoison::poison(std::span<const std::uint8_t> held, std::span<const int> owner,
                          std::vector<FloeState>& state, std::vector<FloeState>* start, std::vector<double>& reach,
                          const contact::Domain& domain) {
  const std::size_t n = state.size();
  held_.assign(held.begin(), held.end());
  held_.resize(n, 0);
  owner_.assign(owner.begin(), owner.end());
  unheld_.clear();
  kept_state_.clear();
  kept_start_.clear();
  kept_reach_.clear();
  const bool lure = options_.kind == PoisonOptions::Kind::lure;
  for (std::size_t i = 0; i < n; ++i) {
    if (held_[i]) continue;
    unheld_.push_back(static_cast<std::uint32_t>(i));
    kept_state_.push_back(state[i]);
    state[i] = lure ? lured(state[i], domain) : nan_state();
    if (start) {
      kept_start_.push_back((*start)[i]);
      (*start)[i] = lure ? lured((*start)[i], domain) : nan_state();
    }
    if (i < reach.size()) {
      kept_reach_.push_back(reach[i]);
      reach[i] = lure ? reach[i] + 10.0 : kNan;
    }
  }
  if (options_.mutant) {
    const auto first = std::find(held_.begin(), held_.end(), std::uint8_t{1});
    if (first != held_.end()) state[static_cast<std::size_t>(first - held_.begin())] = nan_state();
  }
  open_ = true;
  ++windows_;
  poisoned_ += static_cast<long long>(unheld_.size());
}

void UnheldPoison::restore(const parallel::Communicator& comm, std::vector<FloeState>& state,
                           std::vector<FloeState>* start, std::vector<double>& reach, bool start_from_state) {
  if (!open_) return;
  open_ = false;
  // Every floe from its owner; only the unheld floes' values are taken, so
  // a poison that reached a held floe stays (in the run file: the lure).
  std::vector<FloeState> owners = state;
  comm.complete_owned(owners, owner_);
  for (std::size_t k = 0; k < unheld_.size(); ++k) {
    const std::size_t i = unheld_[k];
    state[i] = owners[i];
    if (start && start_from_state) (*start)[i] = kept_state_[k];
    else if (start && k < kept_start_.size()) (*start)[i] = kept_start_[k];
    if (k < kept_reach_.size() && i < reach.size()) reach[i] = kept_reach_[k];
  }
}

void UnheldPoison::check(const char* phase, const std::vector<FloeState>& state,
                         const std::vector<FloeState>* start, std::span<const double> reach) {
  if (!open_) return;
  last_checked_ = phase;
  if (std::find(reported_phases_.begin(), reported_phases_.end(), phase) != reported_phases_.end()) return;
  const std::size_t n = std::min(held_.size(), state.size());
  for (std::size_t i = 0; i < n; ++i) {
    if (!held_[i]) continue;
    std::string field;
    if (const int k = first_nan(state[i]); k >= 0) field = kStateColumnNames[k];
    else if (start && i < start->size() && first_nan((*start)[i]) >= 0)
      field = std::string("step-start ") + kStateColumnNames[first_nan((*start)[i])];
    else if (i < reach.size() && std::isnan(reach[i])) field = "reach";
    else continue;
    std::ostringstream m;
    m << "poison: rank " << rank_ << ": after " << phase << ": held floe " << i << "'s " << field << " is NaN";
    reports_.push_back(m.str());
    reported_phases_.emplace_back(phase);
    // stdio, not std::cerr: the command silences the other ranks' streams
    // (rank 0 speaks for the run), and each rank's report is wanted.
    std::fprintf(stderr, "floesim: %s\n", m.str().c_str());
    std::fflush(stderr);
    return;
  }
}

}  // namespace floesim

// ---- Simulation's side: where the windows open and close in a step ----

#include "coupling/simulation.hpp"

namespace floesim {

void Simulation::set_poison_test(PoisonOptions options) {
  // One rank holds every floe: nothing to poison.
  poison_ = comm_.serial() ? nullptr : std::make_unique<UnheldPoison>(options, comm_.rank());
}

std::vector<std::string> Simulation::poison_reports() const {
  return poison_ ? poison_->reports() : std::vector<std::string>{};
}

std::string Simulation::poison_summary() const {
  if (!poison_) return {};
  return "poison: rank " + std::to_string(comm_.rank()) + ": " + std::to_string(poison_->windows()) +
         " windows, " + std::to_string(poison_->poisoned()) + " floes poisoned in them, " +
         std::to_string(poison_->reports().size()) + " phases reported, the last check after " +
         (poison_->last_checked().empty() ? std::string("none") : poison_->last_checked());
}

void Simulation::poison_step(const char* phase, StepContext& ctx) {
  UnheldPoison& p = *poison_;
  std::vector<FloeState>& state = scenario_.floes.state;
  std::vector<double>& reach = detection_options_.reach;
  const std::string at = phase;
  // The held set of a window: the band at the last detection (held_) and
  // the floes this rank owns now (after the drift's update a floe may have
  // come to it from a strip whose cut moved: piece 8 sends it then).
  const auto open = [&](std::vector<FloeState>* start) {
    const std::size_t n = state.size();
    if (held_.mask.size() != n || owners_.owner().size() != n) return;
    std::vector<std::uint8_t> held = held_.mask;
    for (const std::uint32_t i : owners_.mine()) held[i] = 1;
    p.poison(held, owners_.owner(), state, start, reach, detection_options_.domain);
  };
  // A window leaves the unheld floes stale, as the halo exchange will: a
  // step that reads every floe gathers them (whole_state). Set on every
  // rank alike (open() may return without poisoning on none or all); not
  // with the mutation `stale`.
  const auto open_window = [&](std::vector<FloeState>* start) {
    if (!p.options().stale) state_whole_ = false;
    open(start);
  };
  const auto restore = [&](bool start_from_state) {
    p.restore(comm_, state, &ctx.start, reach, start_from_state);
    state_whole_ = true;
  };
  // Opening: where an exchange of piece 8 gives the held floes their values.
  if (at == "drift" && p.options().after_drift) open_window(&ctx.start);
  if (at == "detect" && p.options().after_detect) open_window(&ctx.start);
  // After the percussion the step's start copy is not read again; the next
  // step's is taken from the (poisoned) state and put back at the restore.
  if (at == "percussion" && p.options().after_percussion) open_window(nullptr);
  p.check(phase, state, &ctx.start, reach);
  // Closing: before the phases that read every floe's place for its owner.
  if (at == "advance" || at == "record") restore(false);
  if (at == "first half kick") restore(true);
}

}  // namespace floesim
