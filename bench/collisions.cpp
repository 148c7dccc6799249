// floesim_bench_collisions: the collision time loop (coupling/simulation.hpp:
// drift, contact LCPs, advance, detection, step limit) on named scenarios.
//
//   floedyn_100  FloeDyn's own example (examples/floedyn_100.toml: its 100
//                floes, Topaz forcing, constants) to 10^4 s.
//   pack_N       N = 500, 2000, 10000 floes from generate_pack: 50% cover,
//                equivalent diameters uniform in [a, 3a] with mean 100 m (the
//                box side is 130.4 sqrt(N) m so the cover holds), thickness
//                uniform in [0.5, 2] m, each floe started with a random
//                velocity (speed uniform in [0, 0.1] m/s, random direction);
//                periodic box, wind 10 m/s along x, Coriolis at 80.2 N,
//                FloeDyn's constants (restitution 0.4, friction 0.7,
//                collision distance 0.01 m, dt_max 10 s, rho_w 1024.071,
//                C_w 5e-3, C_a 1.7e-3, rho_a 1.341), to 10^3 s. The pack is
//                written once to a temporary pack file and read through the
//                [floes] pack key, like a user's run.
//   jam_N        N = 100, 500 floes at rest covering 50% of a 1 km box walled
//                on all sides, wind 15 m/s along x (the jam test of
//                tests/coupling: the pack drifts ~500 m, jams against the
//                downwind wall and stays there), to 10^4 s (100) / 3 10^3 s
//                (500); jam_2000: 2000 floes of jam_500's sizes in a 2 km
//                walled box (the downwind wall is the coast), to 3 10^3 s.
//                Not part of the cost-vs-N fit.
//
// Per scenario: a warm-up run (to 10% of the simulated time), then R timed
// runs (each a fresh Simulation; the minimum wall time is kept, the median is
// shown), taken round-robin over the scenarios; the steps follow `floesim run`
// (steps land on the output times) but nothing is written. Peak memory is
// measured in a separate process (this binary re-executed with --child NAME)
// that runs the scenario once and reports its own VmHWM, so pack generation
// and the timing runs do not count.
// A scenario that throws, or runs past --time-limit, is reported with its
// status and the simulated time it reached.
//
// FloeDyn side by side (--floedyn BIN, its FLOE program built from its public
// source): after each timed run of floedyn_100, FloeDyn runs the same input
// (data/floedyn/in_example_100_floes.h5) to the same end time, one thread,
// `BIN -i INPUT -t 10000 [--floedyn-arg ...]`, in its checkout (--floedyn-dir,
// default the folder above BIN's: waf builds into build/, and FloeDyn reads its
// default forcing from io/inputs/ there); its output goes to floedyn.log in the
// pack folder. floedyn_s is its least wall time, speedup = floedyn_s / wall_s,
// both measured in this run; without --floedyn both are empty.
//
// Usage: floesim_bench_collisions [--repeats R] [--repeats-large R] [--only NAME...]
//                                 [--csv FILE] [--time-limit S] [--note TEXT...] [--pack-dir DIR]
//                                 [--floedyn BIN [--floedyn-dir DIR] [--floedyn-arg ARG...]]
// To profile one scenario: run once with --pack-dir DIR --only NAME, then
//   perf record -g floesim_bench_collisions --child NAME --pack-dir DIR
// (--t-end S stops that child at S simulated seconds: a fixed piece of work
// for timing two builds against each other).
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <numbers>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "core/config.hpp"
#include "core/error.hpp"
#include "core/pack.hpp"
#include "core/pack_generator.hpp"
#include "coupling/scenario.hpp"
#include "coupling/simulation.hpp"
#include "external_run.hpp"

using namespace floesim;
namespace fs = std::filesystem;

namespace {

struct BenchScenario {
  std::string name;
  std::size_t floes = 0;      // 0: FloeDyn's example
  double t_end = 0.0;         // s simulated
  std::string floedyn_input;  // FloeDyn's input for the same case (under the source folder); empty: none
  bool jam = false;           // a walled pack pushed by the wind against the downwind wall
  double jam_box = 1000.0;    // m, side of a jam's walled box
};

const std::vector<BenchScenario> kScenarios = {
    {"floedyn_100", 0, 1.0e4, "data/floedyn/in_example_100_floes.h5"},
    {"pack_500", 500, 1.0e3, ""},
    {"pack_2000", 2000, 1.0e3, ""},
    {"pack_10000", 10000, 1.0e3, ""},
    {"jam_100", 100, 1.0e4, "", true},
    {"jam_500", 500, 3.0e3, "", true},
    {"jam_2000", 2000, 3.0e3, "", true, 2000.0},
};

constexpr double kMeanDiameter = 100.0;  // m
constexpr double kSizeRatio = 3.0;       // d ~ U[a, 3a]
constexpr double kConcentration = 0.5;

std::string pack_file(const std::string& dir, const BenchScenario& s) { return dir + "/" + s.name + ".h5"; }

// Box side for N floes of mean diameter 100 m at 50% cover: for d ~ U[a, r a],
// E[d^2] = a^2 (r^3 - 1) / (3 (r - 1)), with a = 2 mean / (1 + r).
double box_side(std::size_t n) {
  const double a = 2.0 * kMeanDiameter / (1.0 + kSizeRatio);
  const double mean_d2 = a * a * (std::pow(kSizeRatio, 3) - 1.0) / (3.0 * (kSizeRatio - 1.0));
  const double mean_area = std::numbers::pi / 4.0 * mean_d2;
  return std::sqrt(static_cast<double>(n) * mean_area / kConcentration);
}

// The pack of a jam_N scenario: N floes at rest covering 50% of a walled box
// (1 km, 2 km for jam_2000) walled on all sides (20 m walls), default sizes and thickness (1 m) as in
// the jam test of tests/coupling/test_collisions.cpp.
std::string write_jam_pack(const BenchScenario& s, const std::string& dir) {
  PackOptions o;
  o.floes = s.floes;
  o.concentration = kConcentration;
  o.width = o.height = s.jam_box;
  o.seed = 11;
  o.wall_width = 20.0;
  GeneratedPack pack = generate_pack(o);
  write_pack(pack_file(dir, s), pack.floes, pack.window);
  std::ostringstream m;
  m << s.name << ": walled box " << o.width << " m, mean diameter " << pack.mean_size << " m, cover "
    << pack.concentration << ", min gap " << pack.min_gap << " m";
  return m.str();
}

// Generates the pack of a pack_N scenario and writes it; returns a one-line description.
std::string write_scenario_pack(const BenchScenario& s, const std::string& dir) {
  if (s.jam) return write_jam_pack(s, dir);
  PackOptions o;
  o.floes = s.floes;
  o.concentration = kConcentration;
  o.width = o.height = box_side(s.floes);
  o.seed = 1;
  o.sizes.kind = SizeDistribution::Kind::uniform;
  o.sizes.min_size = 1.0;
  o.sizes.max_size = kSizeRatio;
  o.thickness_min = 0.5;
  o.thickness_max = 2.0;
  GeneratedPack pack = generate_pack(o);
  std::mt19937_64 rng(2);
  for (FloeState& st : pack.floes.state) {
    // Own mapping to [0, 1) (53 high bits), like the pack generator, so the
    // velocities do not depend on the standard library.
    const double u1 = static_cast<double>(rng() >> 11) * 0x1.0p-53;
    const double u2 = static_cast<double>(rng() >> 11) * 0x1.0p-53;
    const double speed = 0.1 * u1, dir_rad = 2.0 * std::numbers::pi * u2;
    st.vx = speed * std::cos(dir_rad);
    st.vy = speed * std::sin(dir_rad);
  }
  write_pack(pack_file(dir, s), pack.floes, pack.window);
  std::ostringstream m;
  m << s.name << ": box " << o.width << " m, mean diameter " << pack.mean_size << " m, cover "
    << pack.concentration << ", min gap " << pack.min_gap << " m";
  return m.str();
}

Config scenario_config(const BenchScenario& s, const std::string& pack_dir) {
  if (s.floes == 0) return load_config(std::string(FLOESIM_BENCH_SOURCE_DIR) + "/examples/floedyn_100.toml");
  std::ostringstream t;
  if (s.jam) {
    t << "[run]\nt_end = " << s.t_end << "\ndt_max = 10.0\noutput_interval = 60.0\n"
      << "[floes]\npack = \"" << pack_file(pack_dir, s) << "\"\n"
      << "[contact]\nrestitution = 0.4\nfriction = 0.7\n[forcing]\nwind = [15.0, 0.0]\n";
    return parse_config(t.str(), s.name, pack_dir);
  }
  t << "[run]\nt_end = " << s.t_end << "\ndt_max = 10.0\noutput_interval = 60.0\n"
    << "[sea]\nmodel = \"none\"\nrho = 1024.071\n"
    << "[floes]\npack = \"" << pack_file(pack_dir, s) << "\"\ndensity = 917.0\n"
    << "[contact]\ncollision_distance = 0.01\nrestitution = 0.4\nfriction = 0.7\ndomain = \"periodic\"\n"
    << "[forcing]\nwind = [10.0, 0.0]\ncoriolis = 1.4370225e-4\nocean_drag = 5.0e-3\n"
    << "air_drag = 1.7e-3\nair_density = 1.341\n";
  return parse_config(t.str(), s.name, pack_dir);
}

struct RunResult {
  std::string status = "ok";
  std::size_t floes = 0;
  double simulated = 0.0;  // s reached
  double wall = 0.0;       // s: Simulation construction + steps
  double setup = 0.0;      // s: Simulation construction (shapes, quadrature, first detection)
  std::size_t steps = 0;
  contact::CollisionStats stats;
  contact::SubstepReport substeps;
  long rejected_steps = 0;
  Profile profile;
  std::vector<std::string> warnings;
};

struct TimeLimitReached {};

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// One run to t_end, stepping to the output times as `floesim run` does, with no output.
RunResult run_once(const Config& config, double t_end, double time_limit) {
  RunResult r;
  Scenario scenario = build_scenario(config);  // reads the files: not timed
  r.floes = scenario.floes.size();
  const auto t0 = std::chrono::steady_clock::now();
  try {
    Simulation sim(std::move(scenario));
    r.setup = seconds_since(t0);
    const double interval = config.run.output_interval;
    try {
      for (std::size_t next = 1; sim.time() < t_end; ++next) {
        double t_record = std::min(static_cast<double>(next) * interval, t_end);
        if (t_end - t_record < 1e-9 * std::max(1.0, t_end)) t_record = t_end;
        while (sim.time() < t_record) {
          sim.step(t_record);
          if (seconds_since(t0) > time_limit) throw TimeLimitReached{};
        }
      }
    } catch (const TimeLimitReached&) {
      std::ostringstream m;
      m << "timeout: " << time_limit << " s wall reached at t = " << sim.time() << " s";
      r.status = m.str();
    } catch (const RunError& e) {
      r.status = std::string("RunError: ") + e.what();
    } catch (const std::exception& e) {
      r.status = std::string("exception: ") + e.what();
    }
    r.wall = seconds_since(t0);
    r.simulated = sim.time();
    r.steps = sim.steps();
    r.stats = sim.collision_stats();
    r.substeps = sim.substep_report();
    r.rejected_steps = sim.rejected_steps();
    r.profile = sim.profile();
    r.warnings = sim.warnings();
  } catch (const std::exception& e) {  // construction (e.g. floes overlapping at t = 0)
    r.status = std::string("setup failed: ") + e.what();
    r.wall = seconds_since(t0);
  }
  return r;
}

// Runs this binary with --child NAME; returns its peak resident set (MiB),
// or -1 when it could not run or failed. The child reads it from its own
// /proc/self/status (VmHWM) and writes it to its stdout, a pipe. (wait4's
// ru_maxrss would not do: exec records the hiwater mark of the memory it
// replaces, the forked copy of this process, so a child forked after a large
// scenario would report that scenario's memory.)
double child_peak_rss_mb(const std::vector<std::string>& args) {
  std::vector<char*> argv;
  for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  std::fflush(stdout);
  int fd[2];
  if (pipe(fd) != 0) return -1.0;
  const pid_t pid = fork();
  if (pid < 0) return -1.0;
  if (pid == 0) {
    dup2(fd[1], STDOUT_FILENO);
    close(fd[0]);
    close(fd[1]);
    execv("/proc/self/exe", argv.data());
    _exit(127);
  }
  close(fd[1]);
  std::string text;
  char buf[256];
  for (ssize_t n; (n = read(fd[0], buf, sizeof buf)) > 0;) text.append(buf, static_cast<std::size_t>(n));
  close(fd[0]);
  int status = 0;
  if (waitpid(pid, &status, 0) != pid) return -1.0;
  if (!WIFEXITED(status) || WEXITSTATUS(status) == 127) return -1.0;
  const std::size_t at = text.find("vmhwm_kib ");
  if (at == std::string::npos) return -1.0;
  return std::stod(text.substr(at + 10)) / 1024.0;
}

// The child's answer: its peak resident set (VmHWM of /proc/self/status, KiB).
void print_own_peak_rss() {
  std::ifstream status("/proc/self/status");
  for (std::string line; std::getline(status, line);)
    if (line.rfind("VmHWM:", 0) == 0) {
      std::printf("vmhwm_kib %s\n", line.substr(6).c_str());
      return;
    }
}

std::string csv_field(const std::string& s) {
  if (s.find_first_of(",\"\n") == std::string::npos) return s;
  std::string q = "\"";
  for (char c : s) q += c == '"' ? std::string("\"\"") : std::string(1, c);
  return q + "\"";
}

std::string machine_line() {
  std::ifstream cpu("/proc/cpuinfo");
  std::string line, model = "unknown cpu";
  while (std::getline(cpu, line))
    if (line.rfind("model name", 0) == 0) {
      model = line.substr(line.find(':') + 2);
      break;
    }
  double load[3] = {0, 0, 0};
  if (getloadavg(load, 3) != 3) load[0] = load[1] = load[2] = -1;
  char date[32];
  const std::time_t now = std::time(nullptr);
  std::strftime(date, sizeof date, "%Y-%m-%d %H:%M", std::localtime(&now));
  std::ostringstream m;
  m << model << ", " << sysconf(_SC_NPROCESSORS_ONLN) << " cores (shared); load before: " << load[0] << " "
    << load[1] << " " << load[2] << "; g++ " << __VERSION__ << "; " << date;
  return m.str();
}

struct Row {
  const BenchScenario* scenario = nullptr;
  RunResult best;
  int repeats = 0;
  double wall_median = 0.0;
  double peak_rss_mb = -1.0;
  std::vector<double> floedyn_walls;  // s, FloeDyn's runs that exited 0, one after each timed run
  std::string floedyn_status;         // the first failure of a FloeDyn run; empty: none failed
  double floedyn_min() const { return *std::min_element(floedyn_walls.begin(), floedyn_walls.end()); }
};

// FloeDyn's program and how to run it (--floedyn ...); bin empty: not run.
struct FloedynCommand {
  std::string bin, dir;
  std::vector<std::string> extra;
  std::vector<std::string> argv(const BenchScenario& s) const {
    std::vector<std::string> a = {bin, "-i", std::string(FLOESIM_BENCH_SOURCE_DIR) + "/" + s.floedyn_input, "-t",
                                  std::to_string(static_cast<long>(s.t_end))};
    a.insert(a.end(), extra.begin(), extra.end());
    return a;
  }
};

// Least-squares slope of log y against log x.
double loglog_slope(const std::vector<double>& x, const std::vector<double>& y) {
  const double n = static_cast<double>(x.size());
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    const double lx = std::log(x[i]), ly = std::log(y[i]);
    sx += lx; sy += ly; sxx += lx * lx; sxy += lx * ly;
  }
  return (n * sxy - sx * sy) / (n * sxx - sx * sx);
}

const BenchScenario* find_scenario(const std::string& name) {
  for (const BenchScenario& s : kScenarios)
    if (s.name == name) return &s;
  return nullptr;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"floesim collision benchmarks (named scenarios; CSV with --csv)"};
  int repeats = 3, repeats_large = 1;
  double time_limit = 600.0;
  std::vector<std::string> only, notes;
  std::string csv, child, pack_dir_arg;
  double child_t_end = 0.0;
  FloedynCommand floedyn;
  app.add_option("--repeats", repeats, "timed runs per scenario after the warm-up (minimum kept)")
      ->check(CLI::PositiveNumber);
  app.add_option("--repeats-large", repeats_large, "timed runs for scenarios of 10^4 floes or more, and jams of 500 floes or more")
      ->check(CLI::PositiveNumber);
  app.add_option("--only", only, "scenarios to run (default: all)");
  app.add_option("--csv", csv, "write the results as CSV to this file");
  app.add_option("--time-limit", time_limit, "wall seconds after which a run is stopped and reported");
  app.add_option("--note", notes, "extra comment lines for the CSV header");
  app.add_option("--child", child, "internal: run one scenario once (peak memory)");
  app.add_option("--t-end", child_t_end, "with --child: simulated seconds to run (default: the scenario's end), "
                 "so that two builds can be timed on the same piece of a scenario")
      ->check(CLI::PositiveNumber);
  app.add_option("--pack-dir", pack_dir_arg, "keep the generated packs in this folder (default: a temporary one)");
  app.add_option("--floedyn", floedyn.bin, "FloeDyn's FLOE program: time it side by side on floedyn_100")
      ->check(CLI::ExistingFile);
  app.add_option("--floedyn-dir", floedyn.dir, "folder FloeDyn runs in (default: the one above --floedyn's folder)")
      ->check(CLI::ExistingDirectory);
  app.add_option("--floedyn-arg", floedyn.extra, "extra arguments for FloeDyn (e.g. --floedyn-arg=--fext=FILE)");
  CLI11_PARSE(app, argc, argv);
  if (!floedyn.bin.empty()) {
    floedyn.bin = fs::absolute(floedyn.bin).string();
    if (access(floedyn.bin.c_str(), X_OK) != 0) {
      std::fprintf(stderr, "--floedyn %s: not an executable file\n", floedyn.bin.c_str());
      return 1;
    }
    if (floedyn.dir.empty()) floedyn.dir = fs::path(floedyn.bin).parent_path().parent_path().string();
  }

  if (child == "none") {  // the baseline: a process that only starts
    print_own_peak_rss();
    return 0;
  }
  if (!child.empty()) {
    const BenchScenario* s = find_scenario(child);
    if (!s) return 3;
    const double t_end = child_t_end > 0.0 ? std::min(child_t_end, s->t_end) : s->t_end;
    const RunResult r = run_once(scenario_config(*s, pack_dir_arg), t_end, time_limit);
    // For a profiled run: where it got, on stderr (the parent reads stdout).
    std::fprintf(stderr, "%s: %s, t = %g s in %.1f s, %ld LCPs, %ld pivots, %ld warm (%ld missed), %ld failures\n",
                 s->name.c_str(), r.status.c_str(), r.simulated, r.wall, r.stats.lcps, r.stats.pivots, r.stats.warm,
                 r.stats.warm_missed, r.stats.failures);
    print_own_peak_rss();
    return r.status == "ok" ? 0 : 2;
  }

  for (const std::string& name : only)
    if (!find_scenario(name)) {
      std::fprintf(stderr, "unknown scenario %s\n", name.c_str());
      return 1;
    }
  std::string command;
  for (int i = 0; i < argc; ++i) command += (i ? " " : "") + std::string(argv[i]);
  const std::string machine = machine_line();

  // The packs go to a temporary folder, removed at the end, unless --pack-dir
  // names one to keep them (e.g. to profile a single `--child NAME` run).
  std::string pack_dir = pack_dir_arg;
  if (pack_dir.empty()) {
    char tmpl[] = "/tmp/floesim_bench_collisions_XXXXXX";
    if (!mkdtemp(tmpl)) {
      std::perror("mkdtemp");
      return 1;
    }
    pack_dir = tmpl;
  } else {
    fs::create_directories(pack_dir);
    pack_dir = fs::absolute(pack_dir).string();
  }
  const std::string self = fs::read_symlink("/proc/self/exe").string();
  const double base_rss = child_peak_rss_mb({self, "--child", "none"});
  std::printf("# machine: %s\n# process baseline (start and exit, no scenario): %.1f MiB\n", machine.c_str(),
              base_rss);

  // Set-up and warm-up of every scenario, then the timed runs round-robin
  // (repeat k of every scenario before repeat k + 1 of any), so a change in the
  // machine's speed during the bench (other jobs, clock) falls on all the
  // scenarios alike instead of on the ones that ran while it lasted: the cost
  // exponent compares their times.
  std::vector<Row> rows;
  std::vector<Config> configs;
  std::vector<std::vector<double>> walls;
  for (const BenchScenario& s : kScenarios) {
    if (!only.empty() && std::find(only.begin(), only.end(), s.name) == only.end()) continue;
    if (s.floes > 0) {
      const auto t0 = std::chrono::steady_clock::now();
      const std::string d = write_scenario_pack(s, pack_dir);
      std::printf("# %s (generated and written in %.2f s)\n", d.c_str(), seconds_since(t0));
    }
    configs.push_back(scenario_config(s, pack_dir));
    Row row;
    row.scenario = &s;
    row.repeats = s.floes >= 10000 || (s.jam && s.floes >= 500) ? repeats_large : repeats;
    const RunResult warm = run_once(configs.back(), 0.1 * s.t_end, time_limit);
    if (warm.status != "ok") {
      row.best = warm;  // failed already in the warm-up: report that
      row.repeats = 0;
    }
    rows.push_back(std::move(row));
    walls.emplace_back();
  }
  const int most = std::max(repeats, repeats_large);
  for (int k = 0; k < most; ++k)
    for (std::size_t i = 0; i < rows.size(); ++i) {
      Row& row = rows[i];
      if (k >= row.repeats || (k > 0 && row.best.status != "ok")) continue;  // a failure or a timeout is not repeated
      RunResult r = run_once(configs[i], row.scenario->t_end, time_limit);
      walls[i].push_back(r.wall);
      const bool better = k == 0 || (r.status == "ok" && (row.best.status != "ok" || r.wall < row.best.wall));
      if (better) row.best = std::move(r);
      if (!floedyn.bin.empty() && !row.scenario->floedyn_input.empty() && row.floedyn_status.empty()) {
        const bench::ExternalRun f =
            bench::run_external(floedyn.argv(*row.scenario), floedyn.dir, pack_dir + "/floedyn.log");
        std::printf("# FloeDyn on %s, run %d: %s, %.3f s\n", row.scenario->name.c_str(), k + 1, f.status.c_str(),
                    f.wall);
        if (f.ok) row.floedyn_walls.push_back(f.wall);
        else row.floedyn_status = f.status + " (its output: " + pack_dir + "/floedyn.log)";
      }
    }
  for (std::size_t i = 0; i < rows.size(); ++i) {
    Row& row = rows[i];
    const BenchScenario& s = *row.scenario;
    if (!walls[i].empty()) {
      std::sort(walls[i].begin(), walls[i].end());
      row.wall_median = walls[i][walls[i].size() / 2];
      row.repeats = static_cast<int>(walls[i].size());
    }
    row.peak_rss_mb = child_peak_rss_mb({self, "--child", s.name, "--pack-dir", pack_dir, "--time-limit",
                                         std::to_string(time_limit)});
    const RunResult& b = row.best;
    std::printf("# %s: %s, %zu floes, t = %g s, wall %.3f s (min of %d), %zu steps (%ld redone), %ld LCPs, peak %.1f MiB\n"
                "#   %ld clusters, %ld sub-steps, largest %ld floes, %ld joined, %ld merges, %ld sub-steps redone, "
                "%ld at the floor, %ld pair lists rebuilt, %ld jam time steps\n"
                "#   %ld LCPs solved from a warm start, %ld warm starts redone from scratch, %ld pivots, %ld failures\n",
                s.name.c_str(), b.status.c_str(), b.floes, b.simulated, b.wall, row.repeats, b.steps, b.rejected_steps,
                b.stats.lcps, row.peak_rss_mb, b.substeps.clusters, b.substeps.substeps, b.substeps.largest_cluster,
                b.substeps.joined, b.substeps.merges, b.substeps.rejected, b.substeps.floor_steps,
                b.substeps.rebuilt, b.substeps.time_steps, b.stats.warm, b.stats.warm_missed, b.stats.pivots,
                b.stats.failures);
    for (const std::string& w : b.warnings) std::printf("#   warning: %s\n", w.c_str());
    if (!row.floedyn_status.empty()) std::printf("#   FloeDyn failed: %s\n", row.floedyn_status.c_str());
    std::fflush(stdout);
  }
  // A failed FloeDyn run keeps the folder, for its log.
  bool floedyn_failed = false;
  for (const Row& row : rows) floedyn_failed = floedyn_failed || !row.floedyn_status.empty();
  if (pack_dir_arg.empty() && !floedyn_failed) fs::remove_all(pack_dir);

  // Table and CSV.
  std::ostringstream out;
  out << "scenario,status,floes,simulated_s,repeats,wall_s,wall_s_median,setup_s,steps,lcps,pivots,failures,"
         "fallbacks,contacts,largest_lcp,rejected_steps,clusters,substeps,largest_cluster,joined,merges,"
         "rejected_substeps,floor_substeps,pairs_rebuilt,peak_rss_mb,floedyn_s,floedyn_s_median,speedup";
  for (const char* p : kPhaseNames) out << "," << p << "_s";
  out << "\n";
  for (const Row& row : rows) {
    const RunResult& b = row.best;
    char buf[512];
    const contact::SubstepReport& sr = b.substeps;
    std::snprintf(buf, sizeof buf, "%s,%s,%zu,%g,%d,%.3f,%.3f,%.4f,%zu,%ld,%ld,%ld,%ld,%ld,%ld,%ld,%ld,%ld,%ld,%ld,%ld,%ld,%ld,%ld,%.1f,",
                  row.scenario->name.c_str(), csv_field(b.status).c_str(), b.floes, b.simulated, row.repeats, b.wall,
                  row.wall_median, b.setup, b.steps, b.stats.lcps, b.stats.pivots, b.stats.failures, b.stats.fallbacks,
                  b.stats.contacts, b.stats.largest, b.rejected_steps, sr.clusters, sr.substeps, sr.largest_cluster,
                  sr.joined, sr.merges, sr.rejected, sr.floor_steps, sr.rebuilt, row.peak_rss_mb);
    out << buf;
    if (!row.floedyn_walls.empty()) {
      std::vector<double> f = row.floedyn_walls;
      std::sort(f.begin(), f.end());
      std::snprintf(buf, sizeof buf, "%.3f,%.3f,", f.front(), f[f.size() / 2]);
      out << buf;
      if (b.status == "ok") {
        std::snprintf(buf, sizeof buf, "%.1f", f.front() / b.wall);
        out << buf;
      }
    } else {
      out << ",,";
    }
    for (double sec : b.profile.seconds) {
      std::snprintf(buf, sizeof buf, ",%.4f", sec);
      out << buf;
    }
    out << "\n";
  }

  std::printf("\n%-12s %-8s %6s %8s %9s %7s %7s %9s %5s %8s %8s  %s\n", "scenario", "status", "floes", "sim_s",
              "wall_s", "steps", "lcps", "pivots", "fail", "rss_MiB", "speedup", "top phases (s)");
  for (const Row& row : rows) {
    const RunResult& b = row.best;
    std::vector<std::size_t> order(b.profile.seconds.size());
    for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
    std::sort(order.begin(), order.end(),
              [&](std::size_t i, std::size_t j) { return b.profile.seconds[i] > b.profile.seconds[j]; });
    std::string phases;
    for (std::size_t k = 0; k < 3; ++k) {
      char buf[64];
      std::snprintf(buf, sizeof buf, "%s%s %.3f", k ? ", " : "", kPhaseNames[order[k]], b.profile.seconds[order[k]]);
      phases += buf;
    }
    char speed[32] = "-";
    if (!row.floedyn_walls.empty() && b.status == "ok")
      std::snprintf(speed, sizeof speed, "%.1fx", row.floedyn_min() / b.wall);
    std::printf("%-12s %-8s %6zu %8g %9.3f %7zu %7ld %9ld %5ld %8.1f %8s  %s\n", row.scenario->name.c_str(),
                b.status == "ok" ? "ok" : "FAILED", b.floes, b.simulated, b.wall, b.steps, b.stats.lcps,
                b.stats.pivots, b.stats.failures, row.peak_rss_mb, speed, phases.c_str());
    if (b.status != "ok") std::printf("%-12s   %s\n", "", b.status.c_str());
  }

  // Scaling of the cost per simulated second with N, from the pack cases that completed.
  std::vector<double> n, cost;
  for (const Row& row : rows)
    if (row.scenario->floes > 0 && !row.scenario->jam && row.best.status == "ok" && row.best.simulated > 0) {
      n.push_back(static_cast<double>(row.best.floes));
      cost.push_back(row.best.wall / row.best.simulated);
    }
  std::ostringstream scaling;
  if (n.size() >= 2) {
    scaling << "cost per simulated second ~ N^" << std::setprecision(3) << loglog_slope(n, cost) << " (least squares over";
    for (double v : n) scaling << " " << static_cast<long>(v);
    scaling << " floes; pairwise:";
    for (std::size_t i = 1; i < n.size(); ++i)
      scaling << " " << static_cast<long>(n[i - 1]) << "->" << static_cast<long>(n[i]) << " N^"
              << std::log(cost[i] / cost[i - 1]) / std::log(n[i] / n[i - 1]);
    scaling << "; target <= 1.1)";
  } else {
    scaling << "cost scaling: fewer than two completed pack scenarios";
  }
  std::printf("\n%s\n", scaling.str().c_str());

  if (!csv.empty()) {
    std::ofstream f(csv);
    f << "# command: " << command << "\n# machine: " << machine << "\n";
    for (const std::string& note : notes) f << "# " << note << "\n";
    f << "# wall_s: minimum over `repeats` runs after a warm-up run to 10% of simulated_s (Simulation construction + "
         "steps, no output; the repeats round-robin over the scenarios); phases from Simulation::profile() of that run\n"
      << "# peak_rss_mb: MiB, VmHWM of a separate process running the scenario once (baseline of a process "
         "that only starts: "
      << std::fixed << std::setprecision(1) << base_rss << " MiB)\n"
      << "# floedyn_s: FloeDyn's least wall time, one thread, run after each timed run of the same case "
         "(--floedyn); speedup = floedyn_s / wall_s; empty: not run\n";
    if (!floedyn.bin.empty()) {
      f << "# FloeDyn:";
      for (const std::string& a : floedyn.argv(*find_scenario("floedyn_100"))) f << " " << a;
      f << " (in " << floedyn.dir << ")\n";
    }
    for (const Row& row : rows)
      if (!row.floedyn_status.empty()) f << "# FloeDyn failed on " << row.scenario->name << ": " << row.floedyn_status << "\n";
    f << "# " << scaling.str() << "\n" << out.str();
    if (!f) {
      std::fprintf(stderr, "cannot write %s\n", csv.c_str());
      return 1;
    }
    std::printf("wrote %s\n", csv.c_str());
  }
  return floedyn_failed ? 1 : 0;
}
