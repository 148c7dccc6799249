// The run's summary, block by block (apps/run_summary.hpp). Each line is
// `key: value`; the keys are a contract with the scripts and tests that read
// them.
#include "apps/run_summary.hpp"

#include <algorithm>
#include <filesystem>
#include <iomanip>
#include <ostream>

namespace floesim::apps {

namespace {

namespace fs = std::filesystem;

// " a b c": a per-rank list's values after its key.
template <class Range>
void values(std::ostream& o, const Range& r) {
  for (const auto& x : r) o << " " << x;
}

// Where the run came from and what it did: status, input and output, steps,
// records, time. steps counts the run's steps from its start; the rate,
// this process's (a restart's steps before its checkpoint took none of its
// wall time).
void print_run(std::ostream& o, const SummaryInput& in) {
  const RunSummary& s = in.run;
  const std::size_t before = in.restart ? static_cast<std::size_t>(in.restart->steps) : 0;
  const std::size_t run_steps = s.steps >= before ? s.steps - before : 0;
  o << "status: " << s.status << "\nconfig: " << in.config;
  if (in.restart) o << "\nrestarted_from: " << in.restart_path << " at t = " << in.restart->time << " s";
  o << "\ncheckpoint: " << (s.checkpoint_time >= 0.0 ? std::to_string(s.checkpoint_time) + " s" : "none")
    << "\noutput: " << fs::absolute(s.output).string() << "\nparaview: " << fs::absolute(s.xdmf).string()
    << "\nfloes: " << in.sim.floes().size() << "\nsteps: " << s.steps
    << "\nsteps_redone: " << in.sim.rejected_steps()  // tries redone with half the dt after an overlap (this process)
    << "\nrecords: " << s.records << "\nsimulated: " << s.t_end << " s\n";
  o << std::setprecision(4) << "wall_time: " << s.wall_seconds << " s\nsetup_time: " << in.setup_seconds
    << " s\nsteps_per_second: " << (s.wall_seconds > 0 ? static_cast<double>(run_steps) / s.wall_seconds : 0.0)
    << "\n";
}

// Each energy part at the start and the end.
void print_energy(std::ostream& o, const RunSummary& s) {
  for (std::size_t k = 0; k < s.energy_last.names.size(); ++k)
    o << "energy." << s.energy_last.names[k] << ": " << s.energy_first.values[k] << " -> " << s.energy_last.values[k]
      << " J\n";
}

void print_collisions(std::ostream& o, const contact::CollisionStats& c) {
  o << "collisions.lcps: " << c.lcps << "\ncollisions.contacts: " << c.contacts << "\ncollisions.pivots: " << c.pivots
    << "\ncollisions.largest_lcp: " << c.largest << "\ncollisions.failures: " << c.failures
    << "\ncollisions.fallbacks: " << c.fallbacks << "\ncollisions.gauss_seidel: " << c.gauss_seidel
    << "\ncollisions.tolerated: " << c.tolerated << "\n";
}

// The sub-stepper's counts, as in /diagnostics/substeps.
void print_substeps(std::ostream& o, const Simulation& sim) {
  const LcpCounters counters = sim.lcp_counters();
  for (int k = 0; k < kSubstepColumns; ++k)
    o << "substeps." << kSubstepColumnNames[k] << ": " << counters.substeps[static_cast<std::size_t>(k)] << "\n";
}

// The percussion's counts and times (a run with fracture only).
void print_fracture(std::ostream& o, const Simulation& sim) {
  const PercussionStats* f = sim.percussion_stats();
  if (!f) return;
  o << "fracture.checks: " << f->counts.checks << "\nfracture.screened: " << f->counts.screened
    << "\nfracture.bounded: " << f->counts.bounded << "\nfracture.cut_short: " << f->counts.cut_short
    << "\nfracture.loop_steps: " << f->counts.loop_steps << "\nfracture.sustained: " << f->counts.sustained
    << "\nfracture.initiations: " << f->initiations << "\nfracture.splits: " << f->splits
    << "\nfracture.failed_splits: " << f->failed_splits << "\nfracture.refused_small: " << f->refused_small
    << "\nfracture.refused_overlap: " << f->refused_overlap << "\nfracture.splits_redone: " << f->splits_redone
    << "\nfracture.seconds: " << f->seconds << "\nfracture.models: " << f->models
    << "\nfracture.model_seconds: " << f->model_seconds << "\nfracture.split_seconds: " << f->split_seconds
    << "\nfracture.phase_seconds: " << f->phase_seconds << "\nfracture.mesh_seconds: " << f->mesh_seconds
    << "\nfracture.bound_seconds: " << f->bound_seconds << "\nfracture.factor_seconds: " << f->factor_seconds
    << "\nfracture.lattice_meshes: " << f->lattice_meshes << "\n";
}

// The floe-sea contact (a run with a sea): its footprints, and the implicit
// step's iterations a step.
void print_floe_sea(std::ostream& o, const Simulation& sim) {
  const FloeSeaContact* fs = sim.floe_sea();
  if (!fs) return;
  o << "footprints.placements: " << fs->footprint_placements() << "\nfootprints.rebuilds: " << fs->footprint_rebuilds()
    << "\n";
  if (!fs->implicit()) return;
  const FloeSeaContact::ImplicitStats& st = fs->implicit_stats();
  const double steps = std::max<double>(1.0, static_cast<double>(st.steps));
  o << "implicit.newton_per_step: " << static_cast<double>(st.newton) / steps
    << "\nimplicit.cg_per_step: " << static_cast<double>(st.cg) / steps
    << "\nimplicit.sea_responses_per_step: " << static_cast<double>(st.g_products) / steps << "\n";
}

// The per-floe structures' bytes (capacity) on each rank, in rank order, and
// the bytes their held floes' entries would take (core/floe_bytes.hpp;
// docs/parallel.md, "The arrays held by band: measured (mem27)").
void print_memory(std::ostream& o, const FloeMemoryAll& m) {
  const std::size_t ranks = m.all.size() / m.stride;
  o << "memory.floes.held:";
  for (std::size_t r = 0; r < ranks; ++r) o << " " << m.all[r * m.stride];
  o << " of " << m.memory.floes << "\n";
  for (std::size_t k = 0; k < m.memory.parts.size(); ++k) {
    o << "memory.floes." << m.memory.parts[k].first << ":";
    for (std::size_t r = 0; r < ranks; ++r) o << " " << m.all[r * m.stride + 1 + 2 * k];
    o << " bytes; held";
    for (std::size_t r = 0; r < ranks; ++r) o << " " << m.all[r * m.stride + 2 + 2 * k];
    o << "\n";
  }
}

// ---- parallel.*: a run of several ranks ----

// Rank 0's collectives: bytes it received and the time in them, waits for
// the other ranks included; then the same by phase (Profile): the calls and
// bytes of each phase that made any, then the rest (the run loop's
// agreements, the set-up, the summary).
void print_traffic(std::ostream& o, const SummaryInput& in) {
  const parallel::Communicator::Traffic& t = in.traffic;
  const Profile& profile = in.run.profile;
  o << "parallel.ranks: " << in.comm.size() << "\nparallel.collectives: " << t.calls
    << "\nparallel.bytes_received: " << t.bytes << "\nparallel.collective_seconds: " << t.seconds << "\n";
  long long calls = t.calls, bytes = t.bytes;
  for (std::size_t k = 0; k < kPhaseNames.size(); ++k) {
    calls -= profile.calls[k];
    bytes -= profile.bytes[k];
    if (profile.calls[k] > 0)
      o << "parallel.phase." << kPhaseNames[k] << ": " << profile.calls[k] << " calls, " << profile.bytes[k]
        << " bytes\n";
  }
  o << "parallel.phase.other: " << calls << " calls, " << bytes << " bytes\n";
}

// The floes' strips: the cuts in y, the floes in each strip now, the cuts'
// moves by measured cost and each rank's by-place seconds (CPU) over the
// window before the last move and over all windows.
void print_strips(std::ostream& o, const SummaryInput& in) {
  const parallel::FloeOwners& owners = in.sim.floe_owners();
  std::vector<std::size_t> in_strip(static_cast<std::size_t>(in.comm.size()), 0);
  for (const int r : owners.owner()) ++in_strip[static_cast<std::size_t>(r)];
  o << "parallel.strip_cuts:";
  values(o, owners.cuts());
  o << "\nparallel.strip_floes:";
  values(o, in_strip);
  o << "\nparallel.strip_moves: " << owners.moves() << "\nparallel.strip_seconds:";
  values(o, owners.window_seconds());
  o << "\nparallel.strip_seconds_total:";
  values(o, owners.charged_seconds());
  o << "\n";
}

// The advances by cluster owner: tried, redone whole after a conflict, done
// whole at once after fallbacks (the back-off), and the clusters each rank
// ran and the pair rooms it computed in the steps not redone, against the
// pairs of those steps (a replicated set-up computes every one).
void print_advance_share(std::ostream& o, const parallel::AdvanceShareCounts& share) {
  o << "parallel.advance_steps: " << share.steps << "\nparallel.advance_fallbacks: " << share.fallbacks
    << "\nparallel.advance_whole: " << share.whole << "\nparallel.advance_clusters:";
  values(o, share.clusters);
  o << "\nparallel.advance_rooms:";
  values(o, share.rooms);
  o << "\nparallel.advance_pairs: " << share.pairs << "\n";
  // From the rank's part ([run] advance_on_part): the tries redone for a
  // join the share did not hold, the tries with a jam-sized cluster's pads
  // gathered, the join candidates gathered, the tries where a floe would
  // outrun its reach (the pair list rebuilt on every rank), and the bytes
  // of the shapes this rank sent with the routed floes.
  o << "parallel.advance_missing: " << share.missing << "\nparallel.advance_pads: " << share.pads
    << "\nparallel.advance_candidates: " << share.candidates << "\nparallel.advance_rebuilds: " << share.rebuilds
    << "\nparallel.advance_shape_bytes: " << share.shape_bytes << "\n";
  // From the rank's part: the tries that combined once the clusters of two
  // runners that met were joined on one rank, and the tries made again for it.
  o << "parallel.advance_joined: " << share.joined << "\nparallel.advance_rounds: " << share.rounds
    << "\nparallel.advance_kept: " << share.kept << "\n";
  // The tries that fell back by what made them, one line a kind (a try
  // counts under each kind its parts said; none: no line).
  for (const auto& [kind, n] : share.conflicts) o << "parallel.advance_conflicts." << kind << ": " << n << "\n";
}

// The collisions at the step's start by owner, the same way: tried, redone
// whole, done whole by the back-off, each rank's step groups.
void print_collide_share(std::ostream& o, const parallel::AdvanceShareCounts& collide) {
  o << "parallel.collide_steps: " << collide.steps << "\nparallel.collide_fallbacks: " << collide.fallbacks
    << "\nparallel.collide_whole: " << collide.whole << "\nparallel.collide_groups:";
  values(o, collide.clusters);
  o << "\n";
  for (const auto& [kind, n] : collide.conflicts) o << "parallel.collide_conflicts." << kind << ": " << n << "\n";
}

// Every floe's state gathered from the owners (Simulation::whole_state), for
// any reader, and rank 0's bytes received in those gathers.
void print_whole_state(std::ostream& o, const Simulation& sim) {
  const Simulation::WholeStateCounts& whole = sim.whole_state_counts();
  o << "parallel.whole_state_gathers: " << whole.gathers << " (" << whole.bytes << " bytes)\n";
}

// The fracture analyses by owner (a run with fracture only): the steps that
// exchanged them, each rank's checks (they sum to fracture.checks) and its
// wall time in them; the CPU seconds of those analyses charged to the
// strips' moves (part of strip_seconds_total), over every window; the
// gathers of the states a split reads (its parents and their neighbours),
// in the steps where a split may be made, and rank 0's bytes in them.
void print_fracture_ranks(std::ostream& o, const Simulation& sim) {
  if (!sim.percussion_stats()) return;
  const PercussionRanks& fr = sim.percussion_ranks();
  o << "parallel.fracture_steps: " << fr.steps << "\nparallel.fracture_checks:";
  values(o, fr.checks);
  o << "\nparallel.fracture_seconds:";
  values(o, fr.seconds);
  o << "\nparallel.fracture_charged:";
  values(o, sim.floe_owners().fracture_seconds());
  o << "\nparallel.split_gathers: " << fr.split_gathers << " steps, " << fr.split_bytes << " bytes\n";
}

// The floe-sea contact by owner (a run with a sea): the slabs the
// coupling's floe owners followed at the footprints' last rebuild, and rank
// 0's cells outside its slab's interior (every cell of its pieces on a sea
// not in slabs), summed over the evaluations: sent as pieces (their
// pieces), summed alone here (owned here, or sent as totals).
void print_coupling_ranks(std::ostream& o, const Simulation& sim) {
  const FloeSeaContact* fs = sim.floe_sea();
  if (!fs) return;
  if (!fs->owner_slabs().empty()) {
    o << "parallel.coupling_slab_rows:";
    values(o, fs->owner_slabs());
    o << "\n";
  }
  const FloeSeaContact::RoutedCells& cells = fs->routed_cells();
  if (cells.shared + cells.alone_here + cells.alone_sent > 0)
    o << "parallel.coupling_cells: " << cells.shared << " shared (" << cells.pieces << " pieces), " << cells.alone_here
      << " alone owned, " << cells.alone_sent << " alone sent\n";
  if (cells.boxes_sent + cells.boxes_received > 0)
    o << "parallel.coupling_boxes: " << cells.boxes_sent << " sent, " << cells.boxes_received << " received\n";
  const FloeSeaContact::SharedLoads& loads = fs->shared_loads();
  if (loads.asked + loads.whole > 0)
    o << "parallel.coupling_loads: " << loads.asked << " by request (" << loads.asked_floes << " floes), "
      << loads.whole << " to every rank (" << loads.whole_floes << " floes)\n";
}

// With a sea in slabs the strips are its slabs: their first rows (then the
// row count) now, and each rank's CPU seconds in the coupling's per-floe
// work charged to the slabs' moves (part of strip_seconds_total), over
// every window.
void print_slabs(std::ostream& o, const parallel::FloeOwners& owners) {
  if (!owners.has_slabs()) return;
  o << "parallel.slab_rows:";
  values(o, owners.slabs().first_row);
  o << "\nparallel.coupling_seconds:";
  values(o, owners.coupling_seconds());
  o << "\n";
}

void print_parallel(std::ostream& o, const SummaryInput& in) {
  if (in.comm.serial()) return;
  print_traffic(o, in);
  print_strips(o, in);
  print_advance_share(o, in.sim.advance_share());
  print_collide_share(o, in.sim.collide_share());
  print_whole_state(o, in.sim);
  print_fracture_ranks(o, in.sim);
  print_coupling_ranks(o, in.sim);
  print_slabs(o, in.sim.floe_owners());
}

void print_notes(std::ostream& o, const RunSummary& s) {
  o << "notes: " << s.notes.size() << "\n";
  for (const auto& n : s.notes) o << "  " << n << "\n";
  o << "warnings: " << s.warnings.size() << "\n";
  for (const auto& w : s.warnings) o << "  " << w << "\n";
}

// The seconds in each phase and their share of the step's.
void print_profile(std::ostream& o, const Profile& profile) {
  double total = 0;
  for (double x : profile.seconds) total += x;
  for (std::size_t k = 0; k < profile.seconds.size(); ++k)
    o << "profile." << kPhaseNames[k] << ": " << std::setprecision(4) << profile.seconds[k] << " s ("
      << std::setprecision(3) << (total > 0 ? 100 * profile.seconds[k] / total : 0.0) << "%)\n";
}

}  // namespace

FloeMemoryAll gather_floe_memory(const Simulation& sim, const parallel::Communicator& comm) {
  FloeMemoryAll m{sim.floe_memory(), {}, 0};
  std::vector<std::uint64_t> mine{m.memory.held};
  for (const auto& part : m.memory.parts) {
    mine.push_back(part.second.whole);
    mine.push_back(part.second.held);
  }
  m.stride = mine.size();
  m.all = comm.serial() ? mine : comm.allgather<std::uint64_t>(mine);
  return m;
}

void print_summary(std::ostream& o, const SummaryInput& in) {
  print_run(o, in);
  o << std::setprecision(8);  // every figure after the run's lines
  print_energy(o, in.run);
  print_collisions(o, in.run.collisions);
  print_substeps(o, in.sim);
  print_fracture(o, in.sim);
  print_floe_sea(o, in.sim);
  print_memory(o, in.memory);
  print_parallel(o, in);
  print_notes(o, in.run);
  if (in.profile) print_profile(o, in.run.profile);
}

}  // namespace floesim::apps
