#include "coupling/poison_mode.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
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

// The state's columns from x to yaw_rate are its horizontal state; from
// heave on, its vertical DOFs (core/floes.hpp's order).
constexpr int kFirstVertical = 6;
static_assert(offsetof(FloeState, heave) == kFirstVertical * sizeof(double));

int first_nan(const FloeState& s, int from = 0) {
  const double* v = reinterpret_cast<const double*>(&s);
  for (int k = from; k < kStateColumns; ++k)
    if (std::isnan(v[k])) return k;
  return -1;
}

// `poisoned`'s horizontal state with `s`'s vertical DOFs.
FloeState keep_vertical(FloeState poisoned, const FloeState& s) {
  poisoned.heave = s.heave;
  poisoned.pitch = s.pitch;
  poisoned.roll = s.roll;
  poisoned.heave_rate = s.heave_rate;
  poisoned.pitch_rate = s.pitch_rate;
  poisoned.roll_rate = s.roll_rate;
  return poisoned;
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
  else if (kind == "step-mutant-sea") o.mutant_sea = true;
  else if (kind != "step") return false;
  if (!window.empty()) {  // one or both exchanges, joined by '+'
    o.after_drift = o.after_detect = false;
    for (std::size_t at = 0; at <= window.size();) {
      const std::size_t end = std::min(window.find('+', at), window.size());
      const std::string w = window.substr(at, end - at);
      if (w == "drift") o.after_drift = true;
      else if (w == "detect") o.after_detect = true;
      else return false;
      at = end + 1;
    }
  }
  options = o;
  return true;
}

void UnheldPoison::poison(std::span<const std::uint8_t> held, std::span<const std::uint8_t> kept,
                          std::vector<FloeState>& state, std::vector<FloeState>* start, std::vector<double>& reach,
                          const contact::Domain& domain) {
  const std::size_t n = state.size();
  held_.assign(held.begin(), held.end());
  held_.resize(n, 0);
  kept_.assign(kept.begin(), kept.end());
  kept_.resize(n, 0);
  const bool lure = options_.kind == PoisonOptions::Kind::lure;
  long long count = 0;
  const auto poisoned = [&](const FloeState& s) {
    const FloeState p = lure ? lured(s, domain) : nan_state();
    return vertical_held_ ? keep_vertical(p, s) : p;
  };
  for (std::size_t i = 0; i < n; ++i) {
    if (held_[i]) continue;
    ++count;
    state[i] = poisoned(state[i]);
    if (start && i < start->size()) (*start)[i] = poisoned((*start)[i]);
    if (i < reach.size()) reach[i] = lure ? reach[i] + 10.0 : kNan;
  }
  if (options_.mutant || options_.mutant_sea) {
    const auto first = std::find(held_.begin(), held_.end(), std::uint8_t{1});
    if (first != held_.end()) {
      FloeState& s = state[static_cast<std::size_t>(first - held_.begin())];
      if (options_.mutant) s = nan_state();
      else s.heave = kNan;
    }
  }
  open_ = true;
  ++windows_;
  poisoned_ += count;
}

void UnheldPoison::check(const char* phase, const std::vector<FloeState>& state,
                         const std::vector<FloeState>* start, std::span<const double> reach) {
  if (!open_) return;
  last_checked_ = phase;
  if (std::find(reported_phases_.begin(), reported_phases_.end(), phase) != reported_phases_.end()) return;
  const std::size_t n = std::min(held_.size(), state.size());
  for (std::size_t i = 0; i < n; ++i) {
    if (!held_[i] && !vertical_held_) continue;
    std::string field;
    if (const int k = first_nan(state[i], held_[i] ? 0 : kFirstVertical); k >= 0) field = kStateColumnNames[k];
    else if (!held_[i]) continue;
    else if (kept_[i] && start && i < start->size() && first_nan((*start)[i]) >= 0)
      field = std::string("step-start ") + kStateColumnNames[first_nan((*start)[i])];
    else if (kept_[i] && i < reach.size() && std::isnan(reach[i])) field = "reach";
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

void UnheldPoison::check_sea(const char* phase, bool sea_finite) {
  if (!open_ || sea_finite) return;
  if (std::find(reported_sea_phases_.begin(), reported_sea_phases_.end(), phase) != reported_sea_phases_.end())
    return;
  std::ostringstream m;
  m << "poison: rank " << rank_ << ": after " << phase << ": the sea's modal state is NaN";
  reports_.push_back(m.str());
  reported_sea_phases_.emplace_back(phase);
  std::fprintf(stderr, "floesim: %s\n", m.str().c_str());
  std::fflush(stderr);
}

}  // namespace floesim

// ---- Simulation's side: where the windows open and close in a step ----

#include "coupling/simulation.hpp"
#include "fluid/sea.hpp"

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
  const std::string at = phase;
  // Right after the exchanges (the drift's part (a); the detection's part
  // (b)), the floes this rank does not hold now (held_now(), which the
  // exchanges and whole_state use; with the implicit step every floe's
  // vertical DOFs besides). Every rank holds every floe before the first
  // detection.
  const bool exchanged = (at == "drift" && p.options().after_drift) || (at == "detect" && p.options().after_detect);
  // The step-start copies and reaches are checked in the detection's held
  // floes (its band and own floes, and the floes the rank owns now) only:
  // the coupling's own floes beyond them are held for their state alone
  // (UnheldPoison::poison).
  if (exchanged) {
    const std::vector<std::uint8_t> held = held_now();
    if (held.size() == state.size()) {
      p.hold_vertical(floe_sea_ && floe_sea_->implicit());
      std::vector<std::uint8_t> kept = held_.mask;
      kept.resize(held.size(), 0);
      for (const std::uint32_t i : owners_.mine())
        if (i < kept.size()) kept[i] = 1;
      p.poison(held, kept, state, &ctx.start, detection_options_.reach, detection_options_.domain);
    }
  }
  // The step-start copy is read until the detection (the collisions, the
  // advance, a rejected try's restore) and not after it (the explicit
  // kicks; the next step takes a new one): the floes that enter the held
  // set there do not get theirs, so it is checked until then only.
  const bool start_read = at != "detect" && at != "sea" && at != "second half kick" && at != "record" &&
                          at != "percussion" && at != "check";
  // The detection's reaches (detection_options_) are set at the detection
  // and read from it to the next drift; from the drift to the detection the
  // phases read the part's (the advance's outrun check and rebuild), which
  // a move of the cuts hands over (hand_over_moved): a floe that came to
  // the rank there has no detection reach here until set_reach writes it.
  const bool reach_read = at != "drift" && at != "collide" && at != "advance";
  p.check(phase, state, start_read ? &ctx.start : nullptr,
          reach_read ? std::span<const double>(detection_options_.reach) : std::span<const double>{});
  // The sea this rank steps (its slab's modes, or the whole sea on a sea
  // not in slabs, which every rank steps alike).
  if (sea_) p.check_sea(phase, sea_->finite_state());
}

}  // namespace floesim
