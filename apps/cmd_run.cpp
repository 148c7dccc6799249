// floesim run [CONFIG.toml] [-o OUT.h5] [--until T] [--restart RUN.h5]: runs
// a scenario, writes the run file (and its .xmf for ParaView), shows progress
// on a terminal and prints a summary at the end. With --restart, continues
// RUN.h5 from its checkpoint (docs/formats.md, "Checkpoint and restart").
// Under mpirun every rank runs it; rank 0 writes the file and prints
// (docs/parallel.md).
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <sstream>
#include <thread>

#include "apps/commands.hpp"
#include "core/checkpoint.hpp"
#include "core/config.hpp"
#include "core/run_file.hpp"
#include "core/error.hpp"
#include "coupling/run.hpp"
#include "parallel/comm.hpp"

namespace floesim::apps {

namespace {

namespace fs = std::filesystem;

namespace {
// false, not an exception, for a path the system cannot look at (too long, say).
bool path_exists(const std::string& path) {
  std::error_code ec;
  return fs::exists(path, ec) && !ec;
}
}  // namespace

std::atomic<bool> g_interrupted{false};
extern "C" void on_signal(int) { g_interrupted = true; }

// Exit status of a run stopped by SIGINT or SIGTERM (after the step in
// progress, with a checkpoint written and the file closed).
constexpr int kInterruptedExit = 130;

// The configuration of a restart: CONFIG if given, else the one stored in the
// run file; refused if it differs from the run's in what changes its results.
Config restart_config(const std::string& run_path, const std::string& config_path, const RunInfo& info) {
  Config config = config_path.empty()
                      ? parse_config(info.config, run_path + ": config attribute",
                                     fs::absolute(run_path).parent_path().string())
                      : load_config(config_path);
  const std::vector<std::string> diff = physics_differences(info.config, resolved_toml(config), run_path);
  if (!diff.empty()) {
    std::ostringstream m;
    m << (config_path.empty() ? run_path + ": config attribute" : config_path)
      << ": the configuration differs from the run's (" << run_path
      << ": config attribute) in what changes the results, so the restart could not continue that run:";
    for (const std::string& d : diff) m << "\n  " << d << "  (run -> now)";
    m << "\n(only [run] t_end, checkpoint_interval and threads may change)";
    throw InputError(m.str());
  }
  return config;
}

// The example run when no file is given: an installed tool's copy
// (PREFIX/bin/floesim -> PREFIX/share/floesim/examples, cmake/FloesimInstall.cmake)
// when there is one, else the one in the sources it was built from.
std::string default_config() {
  const fs::path name = fs::path("examples") / "floes_on_waves.toml";
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (!ec) {
    const fs::path installed = exe.parent_path().parent_path() / "share" / "floesim" / name;
    if (fs::is_regular_file(installed, ec)) return installed.string();
  }
  return (fs::path(FLOESIM_SOURCE_DIR) / name).string();
}

std::string human_time(double s) {
  std::ostringstream o;
  o << std::fixed << std::setprecision(0);
  if (s < 120) o << s << " s";
  else if (s < 7200) o << s / 60 << " min";
  else o << std::setprecision(1) << s / 3600 << " h";
  return o.str();
}

// A single status line on stderr, refreshed at most 5 times a second.
// Progress of a run on stderr: on a terminal one line redrawn at most every
// 0.2 s; into a file or pipe (a batch job's log) one full line every
// `log_every` seconds of wall time (0: none), so that a long run in a queue
// still says how far it is.
class ProgressLine {
public:
  ProgressLine(bool enabled, bool terminal, double log_every)
      : enabled_(enabled && (terminal || log_every > 0.0)), terminal_(terminal),
        every_(terminal ? 0.2 : log_every), last_(terminal ? -1.0 : 0.0) {}
  void operator()(const RunProgress& p) {
    if (!enabled_) return;
    if (p.wall_seconds - last_ < every_ && (p.t < p.t_end || !terminal_)) return;
    last_ = p.wall_seconds;
    // The share done counts from t = 0; the rate and the time left from
    // where this run started (a restart goes on from its checkpoint).
    const double frac = p.t_end > 0 ? p.t / p.t_end : 1.0;
    const double rate = p.wall_seconds > 0 ? static_cast<double>(p.steps - p.steps_start) / p.wall_seconds : 0.0;
    const double done = p.t - p.t_start;
    const double eta = done > 0 ? p.wall_seconds * std::max(0.0, p.t_end - p.t) / done : 0.0;
    std::fprintf(stderr, "%s[%5.1f%%] t = %.6g / %.6g s | %zu steps | %.0f steps/s | ETA %s%s",
                 terminal_ ? "\r" : "floesim: ", 100 * frac, p.t, p.t_end, p.steps, rate, human_time(eta).c_str(),
                 terminal_ ? "   " : "\n");
    std::fflush(stderr);
    shown_ = terminal_;
  }
  void done() { if (shown_) std::fputs("\n", stderr); }

private:
  bool enabled_, terminal_;
  double every_;
  double last_;  // wall time of the last line (s)
  bool shown_ = false;
};

struct Args {
  std::string config, output, restart;
  double until = -1.0;
  int threads = -1;
  double log_every = 60.0;  // s of wall time between progress lines when stderr is not a terminal
  bool quiet = false, profile = false;
};

// [run] threads = 0 (one per core) in a run of several ranks on a node: the
// node's cores shared among its ranks, unless OMP_NUM_THREADS says.
void share_cores(Config& config, const parallel::Session& session) {
  if (session.world().serial() || config.run.threads != 0 || std::getenv("OMP_NUM_THREADS") != nullptr) return;
  const int cores = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  config.run.threads = std::max(1, cores / std::max(1, session.local_ranks()));
}

int run(const Args& args, const parallel::Session& session);

}  // namespace

void add_run_command(CLI::App& app, Registry& registry) {
  auto args = std::make_shared<Args>();
  CLI::App* sub = app.add_subcommand("run", "Run a scenario (default: examples/floes_on_waves.toml)");
  sub->add_option("CONFIG", args->config, "Configuration file (.toml)");
  sub->add_option("-o,--output", args->output, "Run file to write (default: CONFIG's name with .h5, here)");
  sub->add_option("--until", args->until, "Stop at this time (s) instead of [run] t_end")
      ->check(finite_non_negative());
  sub->add_option("--threads", args->threads, "Threads for the per-floe phases (default: [run] threads; 0: OMP_NUM_THREADS if set, else one per core; under mpirun, the node's cores over its ranks)")
      ->check(CLI::Range(0, 1024));
  sub->add_option("--restart", args->restart,
                  "Continue this run file from its checkpoint, bit for bit (CONFIG: by default the run's own; "
                  "the output: by default the run file itself)");
  sub->add_flag("-q,--quiet", args->quiet, "No progress line");
  sub->add_option("--log-every", args->log_every,
                  "With stderr not a terminal (a batch job's log): a progress line every this many seconds of "
                  "wall time (default 60; 0: none)")
      ->check(finite_non_negative());
  sub->add_flag("--profile", args->profile, "Print the time spent in each phase of the step");
  registry[sub] = [args] {
    // Under mpirun every rank runs this command (docs/parallel.md); serial otherwise.
    parallel::Session session;
    try {
      return run(*args, session);
    } catch (...) {
      // Said before the session ends: once another rank has left with an
      // error, mpirun may end this one at any moment (only rank 0 prints).
      const int code = report_failure(std::current_exception());
      session.abort_alone(std::current_exception(), code);  // a failure of one rank that the others could not hear of
      return code;
    }
  };
}

namespace {

// The poison mode's summary (a test option: Simulation::set_poison_test),
// every rank's: stdio, as the other ranks' streams are silenced by run().
void say_poison(const Simulation& sim) {
  if (const std::string poison = sim.poison_summary(); !poison.empty()) std::fprintf(stderr, "floesim: %s\n", poison.c_str());
}

int run(const Args& args, const parallel::Session& session) {
  const parallel::Communicator& comm = session.world();
  // Rank 0 speaks for the run: the other ranks' output would repeat it.
  if (!comm.writer()) {
    std::cout.rdbuf(nullptr);
    std::cerr.rdbuf(nullptr);
  }
  const bool restart = !args.restart.empty();
  std::string config_path, output;
  Config config;
  Checkpoint checkpoint;
  std::unique_ptr<Simulation> simulation;
  double setup_seconds = 0.0;  // s
  // Every rank reads and checks the input and builds the scenario before
  // any work is shared: bad input on any rank stops every rank with its
  // message (the same on each, as they read the same files).
  comm.together([&] {
    config_path = args.config.empty() && !restart ? default_config() : args.config;
    if (!config_path.empty() && !path_exists(config_path)) throw InputError(config_path + ": configuration file not found");
    output = args.output;
    if (output.empty()) output = restart ? args.restart : fs::path(config_path).stem().string() + ".h5";
    if (!config_path.empty() && path_exists(output) && fs::equivalent(output, config_path))
      throw InputError(output + ": the output would overwrite the configuration");

    {
      // An output that cannot be written is found before the scenario is built
      // (which may take long); the writer reports what this cannot foresee.
      const fs::path dir = fs::absolute(output).parent_path();
      if (access(dir.c_str(), W_OK) != 0) {
        const int err = errno;
        throw RunError(output + ": cannot write the run file in " + dir.string() + " (" + std::strerror(err) + ")");
      }
    }
    if (restart) {
      if (!path_exists(args.restart)) throw InputError(args.restart + ": run file not found (--restart)");
      const RunInfo info = read_run_info(args.restart);
      checkpoint = read_checkpoint(args.restart);
      config = restart_config(args.restart, config_path, info);
      const double t_end = args.until >= 0.0 ? args.until : config.run.t_end;
      if (t_end < checkpoint.time) {
        std::ostringstream m;
        m << args.restart << ": the checkpoint is at t = " << checkpoint.time << " s, after the end asked for ("
          << (args.until >= 0.0 ? "--until " : "[run] t_end = ") << t_end << " s): expected an end >= "
          << checkpoint.time << " s";
        throw InputError(m.str());
      }
    } else {
      config = load_config(config_path);
    }
    if (args.threads >= 0) config.run.threads = args.threads;
    // --until replaces t_end: the bounds on the records and steps of [run] t_end hold for it too.
    if (args.until >= 0.0)
      for (auto [problem, key] : {std::pair{record_count_problem(args.until, config.run.output_interval), "output_interval"},
                                  std::pair{step_count_problem(args.until, config.run.dt_max), "dt_max"}})
        if (!problem.empty()) {
          std::ostringstream m;
          m << "--until " << args.until << ": " << problem << " ("
            << (config_path.empty() ? args.restart : config_path) << ": [run] " << key << ")";
          throw InputError(m.str());
        }
    share_cores(config, session);
    Scenario scenario = build_scenario(config);
    const auto setup_begin = std::chrono::steady_clock::now();
    simulation = std::make_unique<Simulation>(std::move(scenario), comm);
    if (restart) simulation->restore(checkpoint);
    // The summary's setup_time: the run's set-up on this rank (shapes, the
    // start's detection, the sea), not the reading of the input.
    setup_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - setup_begin).count();
    if (restart) {
      release_restored(checkpoint);  // the simulation holds that state now; the run keeps the marks
      // A new output starts as a copy of the run; the records after the checkpoint are dropped from it.
      if (comm.writer() && !(path_exists(output) && fs::equivalent(output, args.restart))) {
        std::error_code ec;
        fs::copy_file(args.restart, output, fs::copy_options::overwrite_existing, ec);
        if (ec) throw InputError(output + ": cannot copy the run file " + args.restart + " to it: " + ec.message());
      }
    }
  });
  Simulation& sim = *simulation;
  // Test hook, not a user key (tests/parallel/check_writer_ranks.py): "1":
  // each rank's copy of the floes it does not hold is poisoned before the
  // writer's gathers, so the run file is right only if they read every
  // floe from its holder; "unread": the writer writes its poisoned copy
  // (Simulation::set_writer_test). Read here, by the command, so that the
  // library reads no environment.
  // "step", "step-lure", "step-mutant" (optionally "-stale", then optionally
  // "@drift", "@detect": the grammar is parse_poison_options'):
  // the poison mode of the run (Simulation::set_poison_test,
  // tests/parallel/check_poison_run.py), the writer's gathers as in a plain run.
  if (const char* test = std::getenv("FLOESIM_TEST_POISON_UNHELD")) {
    PoisonOptions poison;
    if (parse_poison_options(test, poison))
      sim.set_poison_test(poison);
    else
      sim.set_writer_test(std::string(test) == "unread" ? Simulation::WriterTest::poison_unread
                                                        : Simulation::WriterTest::poison);
  }
  // "warm": a step-start share that used the warm store falls back whole
  // (Simulation::set_collide_test, tests/parallel/check_ranks.py --fallback,
  // check_poison_run.py (d)).
  if (const char* test = std::getenv("FLOESIM_TEST_COLLIDE_FALLBACK")) {
    if (std::string(test) != "warm")
      throw InputError("FLOESIM_TEST_COLLIDE_FALLBACK (a test hook): expected \"warm\", got \"" +
                       std::string(test) + "\"");
    sim.set_collide_test(true);
  }
  for (const std::string& note : sim.notes()) std::cerr << "floesim: note: " << note << "\n";

  ProgressLine progress(!args.quiet && comm.writer(), isatty(STDERR_FILENO) != 0, args.log_every);
  g_interrupted = false;
  auto previous = std::signal(SIGINT, on_signal);
  auto previous_term = std::signal(SIGTERM, on_signal);
  auto restore_signals = [&] {
    std::signal(SIGINT, previous);
    std::signal(SIGTERM, previous_term);
  };
  RunOptions options{output, args.until, [&](const RunProgress& p) { progress(p); },
                     [] { return g_interrupted.load(); }, restart ? &checkpoint : nullptr};
  RunSummary s;
  try {
    s = run_simulation(sim, options);
  } catch (const RunError&) {
    progress.done();
    restore_signals();
    say_poison(sim);
    throw;
  } catch (...) {
    progress.done();
    restore_signals();
    say_poison(sim);
    throw;
  }
  progress.done();
  restore_signals();
  say_poison(sim);
  const int status = s.status == "complete" ? 0 : kInterruptedExit;
  // The run's collectives, read before the memory's gather below (the
  // summary's parallel.* figures are the run's alone).
  const parallel::Communicator::Traffic traffic = comm.traffic();
  // Each rank's per-floe structures (Simulation::floe_memory: every rank
  // names the same structures in the same order), gathered to every rank:
  // per rank its held floes, then per structure its bytes and its held
  // floes' entries' bytes.
  const Simulation::FloeMemory memory = sim.floe_memory();
  std::vector<std::uint64_t> memory_mine{memory.held};
  for (const auto& part : memory.parts) {
    memory_mine.push_back(part.second.whole);
    memory_mine.push_back(part.second.held);
  }
  const std::vector<std::uint64_t> memory_all =
      comm.serial() ? memory_mine : comm.allgather<std::uint64_t>(memory_mine);
  if (!comm.writer()) return status;  // rank 0 reports the run

  // steps counts the run's steps from its start; the rate, this process's
  // (a restart's steps before its checkpoint took none of its wall time).
  const std::size_t before = restart ? static_cast<std::size_t>(checkpoint.steps) : 0;
  const std::size_t run_steps = s.steps >= before ? s.steps - before : 0;
  std::ostream& o = std::cout;
  o << "status: " << s.status << "\nconfig: " << (config_path.empty() ? args.restart + " (its config)" : config_path);
  if (restart) o << "\nrestarted_from: " << args.restart << " at t = " << checkpoint.time << " s";
  o << "\ncheckpoint: " << (s.checkpoint_time >= 0.0 ? std::to_string(s.checkpoint_time) + " s" : "none") << "\noutput: " << fs::absolute(s.output).string()
    << "\nparaview: " << fs::absolute(s.xdmf).string() << "\nfloes: " << sim.floes().size() << "\nsteps: " << s.steps
    << "\nsteps_redone: " << sim.rejected_steps()  // tries redone with half the dt after an overlap (this process)
    << "\nrecords: " << s.records << "\nsimulated: " << s.t_end << " s\nwall_time: " << std::setprecision(4)
    << s.wall_seconds << " s\nsetup_time: " << setup_seconds << " s\nsteps_per_second: " << (s.wall_seconds > 0 ? static_cast<double>(run_steps) / s.wall_seconds : 0.0)
    << "\n";
  o << std::setprecision(8);
  for (std::size_t k = 0; k < s.energy_last.names.size(); ++k)
    o << "energy." << s.energy_last.names[k] << ": " << s.energy_first.values[k] << " -> "
      << s.energy_last.values[k] << " J\n";
  const contact::CollisionStats& c = s.collisions;
  o << "collisions.lcps: " << c.lcps << "\ncollisions.contacts: " << c.contacts << "\ncollisions.pivots: " << c.pivots
    << "\ncollisions.largest_lcp: " << c.largest << "\ncollisions.failures: " << c.failures
    << "\ncollisions.fallbacks: " << c.fallbacks << "\ncollisions.gauss_seidel: " << c.gauss_seidel
    << "\ncollisions.tolerated: " << c.tolerated << "\n";
  {
    const LcpCounters counters = sim.lcp_counters();  // the sub-stepper's counts, as in /diagnostics/substeps
    for (int k = 0; k < kSubstepColumns; ++k)
      o << "substeps." << kSubstepColumnNames[k] << ": " << counters.substeps[static_cast<std::size_t>(k)] << "\n";
  }
  if (const PercussionStats* f = sim.percussion_stats())
    o << "fracture.checks: " << f->counts.checks << "\nfracture.screened: " << f->counts.screened
      << "\nfracture.bounded: " << f->counts.bounded << "\nfracture.cut_short: " << f->counts.cut_short
      << "\nfracture.loop_steps: " << f->counts.loop_steps
      << "\nfracture.sustained: " << f->counts.sustained << "\nfracture.initiations: " << f->initiations
      << "\nfracture.splits: " << f->splits << "\nfracture.failed_splits: " << f->failed_splits
      << "\nfracture.refused_small: " << f->refused_small << "\nfracture.refused_overlap: " << f->refused_overlap
      << "\nfracture.splits_redone: " << f->splits_redone
      << "\nfracture.seconds: " << f->seconds << "\nfracture.models: " << f->models
      << "\nfracture.model_seconds: " << f->model_seconds
      << "\nfracture.split_seconds: " << f->split_seconds << "\nfracture.phase_seconds: " << f->phase_seconds
      << "\nfracture.mesh_seconds: " << f->mesh_seconds << "\nfracture.bound_seconds: " << f->bound_seconds
      << "\nfracture.factor_seconds: " << f->factor_seconds << "\nfracture.lattice_meshes: " << f->lattice_meshes
      << "\n";
  if (const FloeSeaContact* fs = sim.floe_sea())
    o << "footprints.placements: " << fs->footprint_placements() << "\nfootprints.rebuilds: " << fs->footprint_rebuilds()
      << "\n";
  if (const FloeSeaContact* fs = sim.floe_sea(); fs && fs->implicit()) {
    const FloeSeaContact::ImplicitStats& st = fs->implicit_stats();
    const double steps = std::max<double>(1.0, static_cast<double>(st.steps));
    o << "implicit.newton_per_step: " << static_cast<double>(st.newton) / steps
      << "\nimplicit.cg_per_step: " << static_cast<double>(st.cg) / steps
      << "\nimplicit.sea_responses_per_step: " << static_cast<double>(st.g_products) / steps << "\n";
  }
  {
    // The per-floe structures' bytes (capacity) on each rank, in rank order,
    // and the bytes their held floes' entries would take (core/floe_bytes.hpp;
    // docs/parallel.md, "The arrays held by band: measured (mem27)").
    const std::size_t stride = memory_mine.size(), ranks = memory_all.size() / stride;
    o << "memory.floes.held:";
    for (std::size_t r = 0; r < ranks; ++r) o << " " << memory_all[r * stride];
    o << " of " << memory.floes << "\n";
    for (std::size_t k = 0; k < memory.parts.size(); ++k) {
      o << "memory.floes." << memory.parts[k].first << ":";
      for (std::size_t r = 0; r < ranks; ++r) o << " " << memory_all[r * stride + 1 + 2 * k];
      o << " bytes; held";
      for (std::size_t r = 0; r < ranks; ++r) o << " " << memory_all[r * stride + 2 + 2 * k];
      o << "\n";
    }
  }
  if (!comm.serial()) {
    // Rank 0's collectives: bytes it received and the time in them, waits for the other ranks included.
    const parallel::Communicator::Traffic& t = traffic;
    o << "parallel.ranks: " << comm.size() << "\nparallel.collectives: " << t.calls << "\nparallel.bytes_received: " << t.bytes
      << "\nparallel.collective_seconds: " << t.seconds << "\n";
    // The same by phase (Profile): the calls and bytes of each phase that
    // made any, then the rest (the run loop's agreements, the set-up, the summary).
    long long calls = t.calls, bytes = t.bytes;
    for (std::size_t k = 0; k < kPhaseNames.size(); ++k) {
      calls -= s.profile.calls[k];
      bytes -= s.profile.bytes[k];
      if (s.profile.calls[k] > 0)
        o << "parallel.phase." << kPhaseNames[k] << ": " << s.profile.calls[k] << " calls, " << s.profile.bytes[k]
          << " bytes\n";
    }
    o << "parallel.phase.other: " << calls << " calls, " << bytes << " bytes\n";
    // The floes' strips (stage six): the cuts in y, the floes in each strip
    // now, the cuts' moves by measured cost and each rank's by-place seconds
    // (CPU) over the window before the last move and over all windows.
    const parallel::FloeOwners& owners = sim.floe_owners();
    std::vector<std::size_t> in_strip(static_cast<std::size_t>(comm.size()), 0);
    for (const int r : owners.owner()) ++in_strip[static_cast<std::size_t>(r)];
    o << "parallel.strip_cuts:";
    for (const double cut : owners.cuts()) o << " " << cut;
    o << "\nparallel.strip_floes:";
    for (const std::size_t k : in_strip) o << " " << k;
    o << "\nparallel.strip_moves: " << owners.moves() << "\nparallel.strip_seconds:";
    for (const double x : owners.window_seconds()) o << " " << x;
    o << "\nparallel.strip_seconds_total:";
    for (const double x : owners.charged_seconds()) o << " " << x;
    // The advances by cluster owner (stage seven): tried, redone whole after
    // a conflict, done whole at once after fallbacks (the back-off), and the
    // clusters each rank ran and the pair rooms it computed in the steps not
    // redone, against the pairs of those steps (a replicated set-up computes
    // every one).
    const parallel::AdvanceShareCounts& share = sim.advance_share();
    o << "\nparallel.advance_steps: " << share.steps << "\nparallel.advance_fallbacks: " << share.fallbacks
      << "\nparallel.advance_whole: " << share.whole << "\nparallel.advance_clusters:";
    for (const long k : share.clusters) o << " " << k;
    o << "\nparallel.advance_rooms:";
    for (const long k : share.rooms) o << " " << k;
    o << "\nparallel.advance_pairs: " << share.pairs;
    // From the rank's part ([run] advance_on_part): the tries redone for a
    // join the share did not hold, the tries with a jam-sized cluster's pads
    // gathered, the join candidates gathered, the tries where a floe
    // would outrun its reach (the pair list rebuilt on every rank), and the
    // bytes of the shapes this rank sent with the routed floes.
    o << "\nparallel.advance_missing: " << share.missing << "\nparallel.advance_pads: " << share.pads
      << "\nparallel.advance_candidates: " << share.candidates << "\nparallel.advance_rebuilds: " << share.rebuilds
      << "\nparallel.advance_shape_bytes: " << share.shape_bytes;
    // From the rank's part: the tries that combined once the clusters of
    // two runners that met were joined on one rank, and the tries made
    // again for it.
    o << "\nparallel.advance_joined: " << share.joined << "\nparallel.advance_rounds: " << share.rounds
      << "\nparallel.advance_kept: " << share.kept;
    // The tries that fell back by what made them, one line a kind (a try
    // counts under each kind its parts said; none: no line).
    for (const auto& [kind, n] : share.conflicts) o << "\nparallel.advance_conflicts." << kind << ": " << n;
    // The collisions at the step's start by owner, the same way: tried,
    // redone whole, done whole by the back-off, each rank's step groups.
    const parallel::AdvanceShareCounts& collide = sim.collide_share();
    o << "\nparallel.collide_steps: " << collide.steps << "\nparallel.collide_fallbacks: " << collide.fallbacks
      << "\nparallel.collide_whole: " << collide.whole << "\nparallel.collide_groups:";
    for (const long k : collide.clusters) o << " " << k;
    for (const auto& [kind, n] : collide.conflicts) o << "\nparallel.collide_conflicts." << kind << ": " << n;
    // Every floe's state gathered from the owners (Simulation::whole_state),
    // for any reader, and rank 0's bytes received in those gathers.
    const Simulation::WholeStateCounts& whole = sim.whole_state_counts();
    o << "\nparallel.whole_state_gathers: " << whole.gathers << " (" << whole.bytes << " bytes)";
    // The fracture analyses by owner: the steps that exchanged them, each
    // rank's checks (they sum to fracture.checks) and its wall time in them.
    if (sim.percussion_stats()) {
      const PercussionRanks& fr = sim.percussion_ranks();
      o << "\nparallel.fracture_steps: " << fr.steps << "\nparallel.fracture_checks:";
      for (const long k : fr.checks) o << " " << k;
      o << "\nparallel.fracture_seconds:";
      for (const double x : fr.seconds) o << " " << x;
      // The CPU seconds of those analyses charged to the strips' moves (part
      // of strip_seconds_total), over every window.
      o << "\nparallel.fracture_charged:";
      for (const double x : owners.fracture_seconds()) o << " " << x;
      // Of those gathers, the ones before a split (a crack through a floe).
      o << "\nparallel.fracture_whole_state: " << fr.whole_gathers << " steps, " << fr.whole_bytes << " bytes";
    }
    o << "\n";
    // Stage eight: the slabs the coupling's floe owners followed at the
    // footprints' last rebuild.
    if (const FloeSeaContact* fs = sim.floe_sea(); fs && !fs->owner_slabs().empty()) {
      o << "parallel.coupling_slab_rows:";
      for (const int r : fs->owner_slabs()) o << " " << r;
      o << "\n";
    }
    // Rank 0's cells outside its slab's interior (every cell of its pieces
    // on a sea not in slabs), summed over the evaluations: sent as pieces
    // (their pieces), summed alone here (owned here, or sent as totals).
    if (const FloeSeaContact* fs = sim.floe_sea(); fs) {
      const FloeSeaContact::RoutedCells& cells = fs->routed_cells();
      if (cells.shared + cells.alone_here + cells.alone_sent > 0)
        o << "parallel.coupling_cells: " << cells.shared << " shared (" << cells.pieces << " pieces), "
          << cells.alone_here << " alone owned, " << cells.alone_sent << " alone sent\n";
    }
    // Stage seven: with a sea in slabs the strips are its slabs, their first
    // rows (then the row count) now.
    if (owners.has_slabs()) {
      o << "parallel.slab_rows:";
      for (const int row : owners.slabs().first_row) o << " " << row;
      // Each rank's CPU seconds in the coupling's per-floe work charged to
      // the slabs' moves (part of strip_seconds_total), over every window.
      o << "\nparallel.coupling_seconds:";
      for (const double x : owners.coupling_seconds()) o << " " << x;
      o << "\n";
    }
  }
  o << "notes: " << s.notes.size() << "\n";
  for (const auto& n : s.notes) o << "  " << n << "\n";
  o << "warnings: " << s.warnings.size() << "\n";
  for (const auto& w : s.warnings) o << "  " << w << "\n";
  if (args.profile) {
    double total = 0;
    for (double x : s.profile.seconds) total += x;
    for (std::size_t k = 0; k < s.profile.seconds.size(); ++k)
      o << "profile." << kPhaseNames[k] << ": " << std::setprecision(4) << s.profile.seconds[k] << " s ("
        << std::setprecision(3) << (total > 0 ? 100 * s.profile.seconds[k] / total : 0.0) << "%)\n";
  }
  if (s.status != "complete")
    std::cerr << "floesim: interrupted; continue with: floesim run --restart " << output << "\n";
  return status;
}

}  // namespace

}  // namespace floesim::apps
