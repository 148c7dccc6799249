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
#include <optional>
#include <sstream>
#include <thread>

#include "apps/commands.hpp"
#include "apps/run_summary.hpp"
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

// The test hooks: environment variables the tests set (and pass to every
// rank with `mpirun -x`), not user keys; read here, by the command, in this
// one place, so that the library reads no environment.
struct TestHooks {
  // FLOESIM_TEST_POISON_UNHELD (tests/parallel/check_writer_ranks.py): "1":
  // each rank's copy of the floes it does not hold is poisoned before the
  // writer's gathers, so the run file is right only if they read every
  // floe from its holder; "unread": the writer writes its poisoned copy
  // (Simulation::set_writer_test).
  Simulation::WriterTest writer = Simulation::WriterTest::off;
  // The same variable, "step", "step-lure", "step-mutant" (optionally
  // "-stale", then optionally "@drift", "@detect": the grammar is
  // parse_poison_options'): the poison mode of the run
  // (Simulation::set_poison_test, tests/parallel/check_poison_run.py), the
  // writer's gathers as in a plain run.
  std::optional<PoisonOptions> poison;
  // FLOESIM_TEST_COLLIDE_FALLBACK = "warm": a step-start share that used the
  // warm store falls back whole (Simulation::set_collide_test,
  // tests/parallel/check_ranks.py --fallback, check_poison_run.py (d)).
  bool collide_fallback = false;
};

// InputError for a value a hook does not take.
TestHooks read_test_hooks() {
  TestHooks hooks;
  if (const char* text = std::getenv("FLOESIM_TEST_POISON_UNHELD")) {
    const std::string value = text;
    PoisonOptions poison;
    if (parse_poison_options(value, poison))
      hooks.poison = poison;
    else if (value == "1" || value == "unread")
      hooks.writer = value == "1" ? Simulation::WriterTest::poison : Simulation::WriterTest::poison_unread;
    else
      throw InputError("FLOESIM_TEST_POISON_UNHELD (a test hook): expected \"1\", \"unread\" or a poison mode "
                       "(\"step\", \"step-lure\", ...), got \"" + value + "\"");
  }
  if (const char* text = std::getenv("FLOESIM_TEST_COLLIDE_FALLBACK")) {
    if (std::string(text) != "warm")
      throw InputError("FLOESIM_TEST_COLLIDE_FALLBACK (a test hook): expected \"warm\", got \"" + std::string(text) +
                       "\"");
    hooks.collide_fallback = true;
  }
  return hooks;
}

void set_test_hooks(const TestHooks& hooks, Simulation& sim) {
  if (hooks.poison) sim.set_poison_test(*hooks.poison);
  if (hooks.writer != Simulation::WriterTest::off) sim.set_writer_test(hooks.writer);
  if (hooks.collide_fallback) sim.set_collide_test(true);
}

// What the set-up makes of the arguments: the configuration read and
// checked, the scenario built into a simulation (restored from the
// checkpoint for a restart).
struct SetUp {
  std::string config_path, output;
  Checkpoint checkpoint;  // a restart's (its restored state released)
  std::unique_ptr<Simulation> simulation;
  double setup_seconds = 0.0;  // s, the run's set-up on this rank (shapes, the start's detection, the sea)
};

// Every rank reads and checks the input and builds the scenario before any
// work is shared: bad input on any rank stops every rank with its message
// (the same on each, as they read the same files). Called by every rank
// within comm.together.
void set_up(const Args& args, const parallel::Session& session, SetUp& u) {
  const parallel::Communicator& comm = session.world();
  const bool restart = !args.restart.empty();
  Config config;
  u.config_path = args.config.empty() && !restart ? default_config() : args.config;
  if (!u.config_path.empty() && !path_exists(u.config_path))
    throw InputError(u.config_path + ": configuration file not found");
  u.output = args.output;
  if (u.output.empty()) u.output = restart ? args.restart : fs::path(u.config_path).stem().string() + ".h5";
  if (!u.config_path.empty() && path_exists(u.output) && fs::equivalent(u.output, u.config_path))
    throw InputError(u.output + ": the output would overwrite the configuration");
  {
    // An output that cannot be written is found before the scenario is built
    // (which may take long); the writer reports what this cannot foresee.
    const fs::path dir = fs::absolute(u.output).parent_path();
    if (access(dir.c_str(), W_OK) != 0) {
      const int err = errno;
      throw RunError(u.output + ": cannot write the run file in " + dir.string() + " (" + std::strerror(err) + ")");
    }
  }
  if (restart) {
    if (!path_exists(args.restart)) throw InputError(args.restart + ": run file not found (--restart)");
    const RunInfo info = read_run_info(args.restart);
    u.checkpoint = read_checkpoint(args.restart);
    config = restart_config(args.restart, u.config_path, info);
    const double t_end = args.until >= 0.0 ? args.until : config.run.t_end;
    if (t_end < u.checkpoint.time) {
      std::ostringstream m;
      m << args.restart << ": the checkpoint is at t = " << u.checkpoint.time << " s, after the end asked for ("
        << (args.until >= 0.0 ? "--until " : "[run] t_end = ") << t_end << " s): expected an end >= "
        << u.checkpoint.time << " s";
      throw InputError(m.str());
    }
  } else {
    config = load_config(u.config_path);
  }
  if (args.threads >= 0) config.run.threads = args.threads;
  // --until replaces t_end: the bounds on the records and steps of [run] t_end hold for it too.
  if (args.until >= 0.0)
    for (auto [problem, key] : {std::pair{record_count_problem(args.until, config.run.output_interval), "output_interval"},
                                std::pair{step_count_problem(args.until, config.run.dt_max), "dt_max"}})
      if (!problem.empty()) {
        std::ostringstream m;
        m << "--until " << args.until << ": " << problem << " ("
          << (u.config_path.empty() ? args.restart : u.config_path) << ": [run] " << key << ")";
        throw InputError(m.str());
      }
  share_cores(config, session);
  Scenario scenario = build_scenario(config);
  const auto setup_begin = std::chrono::steady_clock::now();
  u.simulation = std::make_unique<Simulation>(std::move(scenario), comm);
  if (restart) u.simulation->restore(u.checkpoint);
  u.setup_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - setup_begin).count();
  if (restart) {
    release_restored(u.checkpoint);  // the simulation holds that state now; the run keeps the marks
    // A new output starts as a copy of the run; the records after the checkpoint are dropped from it.
    if (comm.writer() && !(path_exists(u.output) && fs::equivalent(u.output, args.restart))) {
      std::error_code ec;
      fs::copy_file(args.restart, u.output, fs::copy_options::overwrite_existing, ec);
      if (ec) throw InputError(u.output + ": cannot copy the run file " + args.restart + " to it: " + ec.message());
    }
  }
}

// The poison mode's summary (a test hook), every rank's: stdio, as the
// other ranks' streams are silenced by run().
void say_poison(const Simulation& sim) {
  if (const std::string poison = sim.poison_summary(); !poison.empty()) std::fprintf(stderr, "floesim: %s\n", poison.c_str());
}

// Runs the simulation to its end with the progress line, SIGINT and SIGTERM
// stopping it after the step in progress; however it ends, the progress line
// is closed, the signals' handlers put back and the poison mode's summary said.
RunSummary run_with_progress(const Args& args, SetUp& u, const parallel::Communicator& comm) {
  Simulation& sim = *u.simulation;
  ProgressLine progress(!args.quiet && comm.writer(), isatty(STDERR_FILENO) != 0, args.log_every);
  g_interrupted = false;
  auto previous = std::signal(SIGINT, on_signal);
  auto previous_term = std::signal(SIGTERM, on_signal);
  const auto end = [&] {
    progress.done();
    std::signal(SIGINT, previous);
    std::signal(SIGTERM, previous_term);
    say_poison(sim);
  };
  const RunOptions options{u.output, args.until, [&](const RunProgress& p) { progress(p); },
                           [] { return g_interrupted.load(); }, args.restart.empty() ? nullptr : &u.checkpoint};
  RunSummary s;
  try {
    s = run_simulation(sim, options);
  } catch (...) {
    end();
    throw;
  }
  end();
  return s;
}

int run(const Args& args, const parallel::Session& session) {
  const parallel::Communicator& comm = session.world();
  // Rank 0 speaks for the run: the other ranks' output would repeat it.
  if (!comm.writer()) {
    std::cout.rdbuf(nullptr);
    std::cerr.rdbuf(nullptr);
  }
  SetUp u;
  TestHooks hooks;
  comm.together([&] {
    hooks = read_test_hooks();
    set_up(args, session, u);
  });
  Simulation& sim = *u.simulation;
  set_test_hooks(hooks, sim);
  for (const std::string& note : sim.notes()) std::cerr << "floesim: note: " << note << "\n";

  const RunSummary s = run_with_progress(args, u, comm);
  const int status = s.status == "complete" ? 0 : kInterruptedExit;
  // The run's collectives, read before the memory's gather (the summary's
  // parallel.* figures are the run's alone); the gather, on every rank.
  const parallel::Communicator::Traffic traffic = comm.traffic();
  FloeMemoryAll memory = gather_floe_memory(sim, comm);
  if (!comm.writer()) return status;  // rank 0 reports the run

  const bool restart = !args.restart.empty();
  print_summary(std::cout, {s, sim, comm, traffic, std::move(memory),
                            u.config_path.empty() ? args.restart + " (its config)" : u.config_path, args.restart,
                            restart ? &u.checkpoint : nullptr, u.setup_seconds, args.profile});
  if (s.status != "complete")
    std::cerr << "floesim: interrupted; continue with: floesim run --restart " << u.output << "\n";
  return status;
}

}  // namespace

}  // namespace floesim::apps
