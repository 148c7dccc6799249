// floesim run [CONFIG.toml] [-o OUT.h5] [--until T]: runs a scenario, writes
// the run file (and its .xmf for ParaView), shows progress on a terminal and
// prints a summary at the end.
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <sstream>

#include "apps/commands.hpp"
#include "core/config.hpp"
#include "core/error.hpp"
#include "coupling/run.hpp"

namespace floesim::apps {

namespace {

namespace fs = std::filesystem;

std::atomic<bool> g_interrupted{false};
extern "C" void on_sigint(int) { g_interrupted = true; }

std::string default_config() {
  const fs::path p = fs::path(FLOESIM_SOURCE_DIR) / "examples" / "floes_on_waves.toml";
  return p.string();
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
class ProgressLine {
public:
  explicit ProgressLine(bool enabled) : enabled_(enabled) {}
  void operator()(const RunProgress& p) {
    if (!enabled_) return;
    if (p.wall_seconds - last_ < 0.2 && p.t < p.t_end) return;
    last_ = p.wall_seconds;
    const double frac = p.t_end > 0 ? p.t / p.t_end : 1.0;
    const double rate = p.wall_seconds > 0 ? static_cast<double>(p.steps) / p.wall_seconds : 0.0;
    const double eta = frac > 0 ? p.wall_seconds * (1 - frac) / frac : 0.0;
    std::fprintf(stderr, "\r[%5.1f%%] t = %.6g / %.6g s | %zu steps | %.0f steps/s | ETA %s   ",
                 100 * frac, p.t, p.t_end, p.steps, rate, human_time(eta).c_str());
    std::fflush(stderr);
    shown_ = true;
  }
  void done() { if (shown_) std::fputs("\n", stderr); }

private:
  bool enabled_;
  bool shown_ = false;
  double last_ = -1.0;
};

}  // namespace

void add_run_command(CLI::App& app, Registry& registry) {
  struct Args {
    std::string config, output;
    double until = -1.0;
    int threads = -1;
    bool quiet = false, profile = false;
  };
  auto args = std::make_shared<Args>();
  CLI::App* sub = app.add_subcommand("run", "Run a scenario (default: examples/floes_on_waves.toml)");
  sub->add_option("CONFIG", args->config, "Configuration file (.toml)");
  sub->add_option("-o,--output", args->output, "Run file to write (default: CONFIG's name with .h5, here)");
  sub->add_option("--until", args->until, "Stop at this time (s) instead of [run] t_end")
      ->check(finite_non_negative());
  sub->add_option("--threads", args->threads, "Threads for the per-floe phases (default: [run] threads; 0: OMP_NUM_THREADS if set, else one per core)")
      ->check(CLI::Range(0, 1024));
  sub->add_flag("-q,--quiet", args->quiet, "No progress line");
  sub->add_flag("--profile", args->profile, "Print the time spent in each phase of the step");
  registry[sub] = [args] {
    const std::string config_path = args->config.empty() ? default_config() : args->config;
    if (!fs::exists(config_path)) throw InputError(config_path + ": configuration file not found");
    const std::string output =
        args->output.empty() ? fs::path(config_path).stem().string() + ".h5" : args->output;
    if (fs::exists(output) && fs::equivalent(output, config_path))
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
    Config config = load_config(config_path);
    if (args->threads >= 0) config.run.threads = args->threads;
    // --until replaces t_end: the bound on the records of [run] t_end holds for it too.
    if (args->until >= 0.0)
      for (auto [problem, key] : {std::pair{record_count_problem(args->until, config.run.output_interval), "output_interval"},
                                  std::pair{step_count_problem(args->until, config.run.dt_max), "dt_max"}})
        if (!problem.empty()) {
          std::ostringstream m;
          m << "--until " << args->until << ": " << problem << " (" << config_path << ": [run] " << key << ")";
          throw InputError(m.str());
        }
    Simulation sim(build_scenario(config));
    for (const std::string& note : sim.notes()) std::cerr << "floesim: note: " << note << "\n";

    ProgressLine progress(!args->quiet && isatty(STDERR_FILENO));
    g_interrupted = false;
    auto previous = std::signal(SIGINT, on_sigint);
    RunOptions options{output, args->until, [&](const RunProgress& p) { progress(p); },
                       [] { return g_interrupted.load(); }};
    RunSummary s;
    try {
      s = run_simulation(sim, options);
    } catch (const RunError&) {
      progress.done();
      std::signal(SIGINT, previous);
      throw;
    } catch (...) {
      progress.done();
      std::signal(SIGINT, previous);
      throw;
    }
    progress.done();
    std::signal(SIGINT, previous);

    std::ostream& o = std::cout;
    o << "status: " << s.status << "\nconfig: " << config_path << "\noutput: " << fs::absolute(s.output).string()
      << "\nparaview: " << fs::absolute(s.xdmf).string() << "\nfloes: " << sim.floes().size() << "\nsteps: " << s.steps
      << "\nrecords: " << s.records << "\nsimulated: " << s.t_end << " s\nwall_time: " << std::setprecision(4)
      << s.wall_seconds << " s\nsteps_per_second: " << (s.wall_seconds > 0 ? static_cast<double>(s.steps) / s.wall_seconds : 0.0)
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
      o << "fracture.checks: " << f->checks << "\nfracture.screened: " << f->screened
        << "\nfracture.initiations: " << f->initiations << "\nfracture.splits: " << f->splits << "\n";
    if (const FloeSeaContact* fs = sim.floe_sea(); fs && fs->implicit()) {
      const FloeSeaContact::ImplicitStats& st = fs->implicit_stats();
      const double steps = std::max<double>(1.0, static_cast<double>(st.steps));
      o << "implicit.newton_per_step: " << static_cast<double>(st.newton) / steps
        << "\nimplicit.cg_per_step: " << static_cast<double>(st.cg) / steps
        << "\nimplicit.sea_responses_per_step: " << static_cast<double>(st.g_products) / steps << "\n";
    }
    o << "warnings: " << s.warnings.size() << "\n";
    for (const auto& w : s.warnings) o << "  " << w << "\n";
    if (args->profile) {
      double total = 0;
      for (double x : s.profile.seconds) total += x;
      for (std::size_t k = 0; k < s.profile.seconds.size(); ++k)
        o << "profile." << kPhaseNames[k] << ": " << std::setprecision(4) << s.profile.seconds[k] << " s ("
          << std::setprecision(3) << (total > 0 ? 100 * s.profile.seconds[k] / total : 0.0) << "%)\n";
    }
    return s.status == "complete" ? 0 : 130;
  };
}

}  // namespace floesim::apps
