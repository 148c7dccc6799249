// Simulation::save and restore (coupling/simulation.hpp): which state each
// part of a run carries from one step to the next, and what is computed again
// from it (core/checkpoint.hpp); and the floes' states the writer writes,
// gathered from their holders (writer_states).
#include <algorithm>
#include <cmath>
#include <cstring>

#include "core/error.hpp"
#include "coupling/simulation.hpp"
#include "fluid/sea.hpp"
#include "parallel/writer_gather.hpp"

namespace floesim {

namespace {

// The cumulative statistics, by name (Checkpoint::counters).
struct Counters {
  std::vector<std::string> names;
  std::vector<double> values;
  void add(const std::string& name, double v) {
    names.push_back(name);
    values.push_back(v);
  }
};

WarmStartState save_warm(const contact::WarmStart& w) {
  WarmStartState s;
  s.clock = w.clock;
  // By key, so that equal states give equal files (the map's order is its history's).
  for (const auto& [key, pair] : w.pairs) s.keys.push_back(key);
  std::sort(s.keys.begin(), s.keys.end());
  for (std::uint64_t key : s.keys) {
    const contact::WarmStart::Pair& p = w.pairs.at(key);
    s.stored.push_back(p.stored);
    for (const contact::WarmStart::Entry& e : p.entries) {
      s.entries.insert(s.entries.end(), {e.body_point.x(), e.body_point.y(), e.body_normal.x(), e.body_normal.y()});
      for (std::uint8_t b : e.basic) s.entries.push_back(b);
      s.entries.push_back(e.vertex_of_b ? 1.0 : 0.0);
    }
    s.offsets.push_back(static_cast<long long>(s.entries.size() / WarmStartState::kWidth));
  }
  return s;
}

void restore_warm(const WarmStartState& s, contact::WarmStart& w) {
  w.pairs.clear();
  w.clock = s.clock;
  for (std::size_t k = 0; k < s.keys.size(); ++k) {
    contact::WarmStart::Pair p;
    p.stored = s.stored[k];
    for (auto e = static_cast<std::size_t>(s.offsets[k]); e < static_cast<std::size_t>(s.offsets[k + 1]); ++e) {
      const double* x = &s.entries[WarmStartState::kWidth * e];
      contact::WarmStart::Entry entry;
      entry.body_point = Vec2{x[0], x[1]};
      entry.body_normal = Vec2{x[2], x[3]};
      for (int b = 0; b < 4; ++b) entry.basic[static_cast<std::size_t>(b)] = x[4 + b] != 0.0 ? 1 : 0;
      entry.vertex_of_b = x[8] != 0.0;
      p.entries.push_back(entry);
    }
    w.pairs.emplace(s.keys[k], std::move(p));
  }
}

}  // namespace

static FloeState unheld_state() {  // a floe this rank does not hold
  const double nan = std::nan("");
  return FloeState{nan, nan, nan, nan, nan, nan, nan, nan, nan, nan, nan, nan};
}

std::vector<std::uint8_t> Simulation::kept_on_restore() const {
  // The rule (docs/parallel.md, "One writer gathers the records and
  // checkpoints"): a rank holds its floes by place and the band B_r about
  // its strip. Until the arrays are held by band (the halo plan's piece 9)
  // every rank holds every floe; that piece changes only this set.
  return std::vector<std::uint8_t>(scenario_.floes.size(), 1);
}

std::vector<FloeState> Simulation::writer_states() const {
  const std::vector<FloeState>& whole = scenario_.floes.state;
  if (comm_.serial()) return whole;
  const std::size_t n = whole.size();
  // The drift's owners by place hold the states between two steps (the
  // next drift's complete_owned sends theirs; the vertical DOFs too, which
  // every rank drifts); once a split has added floes the owners do not
  // cover yet, the shares by index (as for_owned's).
  std::vector<int> owner;
  if (owners_.owner().size() == n) {
    owner.assign(owners_.owner().begin(), owners_.owner().end());
  } else {
    owner.resize(n);
    for (int r = 0; r < comm_.size(); ++r) {
      const parallel::Range share = parallel::share(n, r, comm_.size());
      for (std::size_t i = share.begin; i < share.end; ++i) owner[i] = r;
    }
  }
  const int writer = 0;
  std::vector<FloeState> states = whole;
  if (writer_test_ != WriterTest::off)
    for (std::size_t i = 0; i < n; ++i)
      if (owner[i] != comm_.rank()) states[i] = unheld_state();
  const std::vector<std::byte> message = parallel::writer_message(states, owner, comm_.rank(), writer);
  std::vector<std::size_t> send(static_cast<std::size_t>(comm_.size()), 0), receive(send.size(), 0);
  send[static_cast<std::size_t>(writer)] = message.size();
  if (comm_.rank() == writer) receive = parallel::writer_counts(owner, comm_.size(), writer);
  std::size_t total = 0;
  for (const std::size_t c : receive) total += c;
  std::vector<std::byte> received(total);
  comm_.alltoall(message, send, received, receive);
  if (comm_.rank() != writer) return {};
  if (writer_test_ == WriterTest::poison_unread) return states;
  parallel::writer_assemble(states, received, owner, comm_.size(), writer);
  return states;
}

Checkpoint Simulation::save() { return save(writer_states()); }

Checkpoint Simulation::save(std::vector<FloeState> states) {
  Checkpoint c;
  c.time = t_;
  c.steps = static_cast<long long>(steps_);
  c.equal_dt = equal_dt_;
  c.floes = scenario_.floes;
  // The writer keeps the checkpoint: its floes' states come from their
  // holders, as a record's. The rest of the checkpoint is whole on every
  // rank today (docs/parallel.md, "One writer gathers").
  if (comm_.writer()) {
    FLOESIM_ASSERT(states.size() == c.floes.size());
    c.floes.state = std::move(states);
  }
  if (sea_) c.sea = save_modal(*sea_);
  if (incident_) c.incident = incident_->saved_state();
  if (floe_sea_) c.floe_sea = floe_sea_->saved_state();
  c.warm = save_warm(*warm_);
  Counters k;
  for (const auto& [name, v] : contact::collision_counts(stats_))
    k.add(std::string("collisions.") + name, static_cast<double>(*v));
  const contact::SubstepReport& r = substeps_;
  for (const auto& [name, v] : contact::substep_counts(r)) k.add(std::string("substeps.") + name, static_cast<double>(*v));
  c.floor_pair = r.floor_pair;
  k.add("rejected_steps", static_cast<double>(rejected_steps_));
  k.add("budget.external_x", budget_.external.x());
  k.add("budget.external_y", budget_.external.y());
  k.add("budget.collisions_x", budget_.collisions.x());
  k.add("budget.collisions_y", budget_.collisions.y());
  if (percussion_) {
    const PercussionStats& p = percussion_->stats();
    for (auto [name, v] : {std::pair{"checks", p.counts.checks}, {"screened", p.counts.screened},
                           {"initiations", p.initiations}, {"splits", p.splits}, {"failed_splits", p.failed_splits},
                           {"sustained", p.counts.sustained}})
      k.add(std::string("fracture.") + name, static_cast<double>(v));
    k.add("fracture.bounded", static_cast<double>(p.counts.bounded));
    k.add("fracture.cut_short", static_cast<double>(p.counts.cut_short));
    k.add("fracture.refused_small", static_cast<double>(p.refused_small));
    k.add("fracture.refused_overlap", static_cast<double>(p.refused_overlap));
    k.add("fracture.splits_redone", static_cast<double>(p.splits_redone));
    k.add("fracture.loop_steps", static_cast<double>(p.counts.loop_steps));
    k.add("fracture.models", static_cast<double>(p.models));
    k.add("fracture.model_seconds", p.model_seconds);
    k.add("fracture.seconds", p.seconds);
    k.add("fracture.split_seconds", p.split_seconds);
    k.add("fracture.phase_seconds", p.phase_seconds);
    k.add("fracture.mesh_seconds", p.mesh_seconds);
    k.add("fracture.bound_seconds", p.bound_seconds);
    k.add("fracture.factor_seconds", p.factor_seconds);
    k.add("fracture.lattice_meshes", static_cast<double>(p.lattice_meshes));
  }
  c.counter_names = std::move(k.names);
  c.counters = std::move(k.values);
  return c;
}

void Simulation::restore(const Checkpoint& c) {
  auto fail = [](const std::string& what) { throw InputError("checkpoint: " + what); };
  if (c.sea.present != (sea_ != nullptr)) fail("it has " + std::string(c.sea.present ? "a" : "no") + " sea, this run has " + (sea_ ? "one" : "none"));
  if (c.incident.present != (incident_ != nullptr)) fail("its incident waves do not match this run's sea");
  if (c.floe_sea.present != (floe_sea_ != nullptr)) fail("its floe–sea contact does not match this run's");
  if (c.floe_sea.present && c.floe_sea.bottom0.size() != c.floes.size()) fail("floe_sea/bottom0: one entry per floe expected");
  for (std::size_t i = 0; i < c.floes.size(); ++i)
    if (!(c.floes.mass[i] > 0.0 && c.floes.area[i] > 0.0)) fail("floe " + std::to_string(i) + " has no mass or area");
  auto counter = [&](const std::string& name) {
    const auto it = std::find(c.counter_names.begin(), c.counter_names.end(), name);
    if (it == c.counter_names.end()) fail("counter '" + name + "' is missing");
    return c.counters[static_cast<std::size_t>(it - c.counter_names.begin())];
  };
  auto count = [&](const std::string& name) { return static_cast<long>(counter(name)); };

  scenario_.floes = c.floes;
  t_ = c.time;
  steps_ = static_cast<std::size_t>(c.steps);
  equal_dt_ = c.equal_dt;
  // What the floes determine: collision shapes, drag quadrature, the pair
  // list and contacts as detect_and_check left them at the end of the step.
  // (the quadrature on several ranks: the held floes' only, at the detection below)
  if (comm_.serial())
    quadrature_ = build_footprint_quadrature(scenario_.floes);
  else
    quadrature_.forget();
  build_shapes();
  // The owners by place start again from the restored places, as at a
  // run's start (the strips by equal counts, or the sea's slabs), and the
  // detection is made by place.
  start_owners();
  // Every rank has read the whole checkpoint (the file on every rank) and
  // keeps the floes it holds at the restored places; the others' states are
  // let go (NaN), so that a reader of a floe it does not hold is seen.
  const std::vector<std::uint8_t> held = kept_on_restore();
  for (std::size_t i = 0; i < held.size(); ++i)
    if (!held[i]) scenario_.floes.state[i] = unheld_state();
  detect_in_place();
  if (sea_) restore_modal(*sea_, c.sea, "the sea");
  if (incident_) incident_->restore(c.incident);
  if (floe_sea_) floe_sea_->restore(c.floe_sea, scenario_.floes, *sea_, incident_.get());
  restore_warm(c.warm, *warm_);

  for (const auto& [name, v] : contact::collision_counts(stats_)) *v = count(std::string("collisions.") + name);
  contact::SubstepReport& r = substeps_;
  for (const auto& [name, v] : contact::substep_counts(r)) *v = count(std::string("substeps.") + name);
  r.floor_pair = c.floor_pair;
  rejected_steps_ = count("rejected_steps");
  budget_.external = Vec2{counter("budget.external_x"), counter("budget.external_y")};
  budget_.collisions = Vec2{counter("budget.collisions_x"), counter("budget.collisions_y")};
  if (percussion_) {
    PercussionStats p;
    for (auto [name, v] : {std::pair{"checks", &p.counts.checks}, {"screened", &p.counts.screened},
                           {"initiations", &p.initiations}, {"splits", &p.splits},
                           {"failed_splits", &p.failed_splits}, {"sustained", &p.counts.sustained}})
      *v = count(std::string("fracture.") + name);
    // Counters that checkpoints written before them lack keep their zeros.
    auto has = [&](const char* name) {
      return std::find(c.counter_names.begin(), c.counter_names.end(), name) != c.counter_names.end();
    };
    // Absent before the stress bound.
    if (has("fracture.bounded"))
      p.counts.bounded = count("fracture.bounded");
    // Absent before the energy bound in the time loop.
    if (has("fracture.cut_short")) {
      p.counts.cut_short = count("fracture.cut_short");
      p.counts.loop_steps = count("fracture.loop_steps");
      p.models = count("fracture.models");
      p.model_seconds = counter("fracture.model_seconds");
    }
    // Absent before the refusals were told apart.
    if (has("fracture.refused_small")) {
      p.refused_small = count("fracture.refused_small");
      p.refused_overlap = count("fracture.refused_overlap");
    }
    // Absent before the splits were decided by the analysing share.
    if (has("fracture.splits_redone")) p.splits_redone = count("fracture.splits_redone");
    // Absent before the phase's time was split up.
    if (has("fracture.phase_seconds")) {
      p.phase_seconds = counter("fracture.phase_seconds");
      p.mesh_seconds = counter("fracture.mesh_seconds");
      p.bound_seconds = counter("fracture.bound_seconds");
      p.factor_seconds = counter("fracture.factor_seconds");
      p.lattice_meshes = count("fracture.lattice_meshes");
    }
    p.seconds = counter("fracture.seconds");
    p.split_seconds = counter("fracture.split_seconds");
    percussion_->restore_stats(p);
  }
}

}  // namespace floesim
