// floesim regress DIR [--rtol R --atol A] [--update] [--keep OUT]: runs every
// DIR/*.toml and compares each run with its committed reference run
// DIR/<case>.ref.h5 the way `floesim compare` does (docs/regression.md).
// Prints one table row per case (status, largest difference, where, at which
// simulated time). Exit 0 when all pass, 1 when any differs or fails to run,
// 2 for bad input (no cases, a missing reference, a bad configuration).
// --update rewrites the references from fresh runs instead.
#include <stdlib.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <sstream>

#include "apps/commands.hpp"
#include "core/error.hpp"
#include "core/floes.hpp"
#include "core/run_file.hpp"
#include "coupling/run.hpp"

namespace floesim::apps {

namespace {

namespace fs = std::filesystem;

struct Case {
  std::string name;      // file stem
  fs::path config, reference;
};

struct Row {
  std::string status;    // pass | DIFFERS | FAILED | new | updated | unchanged
  std::string max_diff = "-", where = "-", time = "-";
  double wall = 0.0;
  std::vector<std::string> details;  // one line per differing dataset, or the failure
};

std::string format_number(double v, int precision = 3) {
  std::ostringstream s;
  s << std::setprecision(precision) << v;
  return s.str();
}

// A temporary folder removed when it goes out of scope.
struct TempDir {
  fs::path path;
  TempDir() {
    std::string tmpl = (fs::temp_directory_path() / "floesim_regress_XXXXXX").string();
    if (!mkdtemp(tmpl.data())) throw InputError("cannot create a temporary folder in " + fs::temp_directory_path().string());
    path = tmpl;
  }
  ~TempDir() { std::error_code ec; fs::remove_all(path, ec); }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
};

std::vector<Case> find_cases(const fs::path& dir) {
  if (!fs::is_directory(dir)) throw InputError(dir.string() + ": not a folder (expected a folder of *.toml cases)");
  std::vector<Case> cases;
  for (const auto& e : fs::directory_iterator(dir))
    if (e.is_regular_file() && e.path().extension() == ".toml") {
      const std::string stem = e.path().stem().string();
      cases.push_back({stem, e.path(), dir / (stem + ".ref.h5")});
    }
  if (cases.empty()) throw InputError(dir.string() + ": no *.toml cases in this folder");
  std::sort(cases.begin(), cases.end(), [](const Case& a, const Case& b) { return a.name < b.name; });
  return cases;
}

// Datasets whose first dimension is the record (time) index, most telling first:
// a failing case is summed up by the first of these that differs.
const std::vector<std::string> kTimeSeries = {"/floes/state", "/sea/eta", "/diagnostics/energy",
                                              "/diagnostics/lcp", "/time", "/xdmf/vertices"};

// "dataset[record, ...]" and the record's time, for the flat index of the
// largest difference (shape and column names read from the reference).
std::pair<std::string, std::string> locate(const std::string& reference, const DatasetDifference& d) {
  const RunDataset ds = read_run_dataset(reference, d.dataset);
  std::vector<std::size_t> index(ds.shape.size());
  std::size_t rest = d.at;
  for (std::size_t k = ds.shape.size(); k-- > 0;) {
    index[k] = rest % ds.shape[k];
    rest /= ds.shape[k];
  }
  std::ostringstream where;
  where << d.dataset << "[";
  for (std::size_t k = 0; k < index.size(); ++k) {
    where << (k ? ", " : "");
    const bool last = k + 1 == index.size();
    if (last && d.dataset == "/floes/state" && index[k] < static_cast<std::size_t>(kStateColumns))
      where << kStateColumnNames[index[k]];
    else if (last && index.size() == 2 && index[k] < ds.columns.size())
      where << ds.columns[index[k]];
    else
      where << index[k];
  }
  where << "]";
  std::string time = "-";
  if (!index.empty() && std::find(kTimeSeries.begin(), kTimeSeries.end(), d.dataset) != kTimeSeries.end()) {
    const RunDataset t = read_run_dataset(reference, "/time");
    if (index[0] < t.values.size()) time = format_number(t.values[index[0]], 6);
  }
  return {where.str(), time};
}

void summarise(const CompareResult& r, const std::string& reference, Row& row) {
  for (const DatasetDifference& d : r.differences) {
    std::string line = d.dataset + ": " + d.what;
    if (d.what == "values")
      line += " (" + std::to_string(d.count) + " elements out of tolerance, max |a - b| = " + format_number(d.max_abs, 6) + ")";
    row.details.push_back(line);
  }
  if (r.equal()) return;
  auto rank = [](const DatasetDifference& d) {
    const auto it = std::find(kTimeSeries.begin(), kTimeSeries.end(), d.dataset);
    return d.what == "values" ? static_cast<std::size_t>(it - kTimeSeries.begin()) : kTimeSeries.size() + 1;
  };
  const DatasetDifference& worst = *std::min_element(
      r.differences.begin(), r.differences.end(), [&](const auto& a, const auto& b) { return rank(a) < rank(b); });
  if (worst.what != "values") {
    row.where = worst.dataset + " (" + worst.what + ")";
    return;
  }
  row.max_diff = format_number(worst.max_abs);
  std::tie(row.where, row.time) = locate(reference, worst);
}

Row run_case(const Case& c, const fs::path& out, const CompareOptions& opt, bool update) {
  Row row;
  const auto start = std::chrono::steady_clock::now();
  try {
    Simulation sim(build_scenario(load_config(c.config.string())));
    RunOptions options;
    options.output = out.string();
    run_simulation(sim, options);
  } catch (const RunError& e) {
    row.status = "FAILED";
    row.details.push_back(std::string("run failed: ") + e.what());
    return row;
  }
  row.wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (update) {
    // A reference equal to the fresh run within the tolerances is left as it
    // is (rewriting changes its bytes, not its numbers: churn in git).
    const bool existed = fs::exists(c.reference);
    if (existed) {
      const CompareResult r = compare_runs(out.string(), c.reference.string(), opt);
      summarise(r, c.reference.string(), row);
      if (r.equal()) {
        row.status = "unchanged";
        return row;
      }
    }
    fs::copy_file(out, c.reference, fs::copy_options::overwrite_existing);
    row.status = existed ? "updated" : "new";
    return row;
  }
  const CompareResult r = compare_runs(out.string(), c.reference.string(), opt);
  summarise(r, c.reference.string(), row);
  row.status = r.equal() ? "pass" : "DIFFERS";
  return row;
}

}  // namespace

void add_regress_command(CLI::App& app, Registry& registry) {
  struct Args {
    std::string dir, keep;
    CompareOptions opt;
    bool update = false;
  };
  auto args = std::make_shared<Args>();
  CLI::App* sub = app.add_subcommand(
      "regress", "Run every DIR/*.toml and compare each run with its reference DIR/<case>.ref.h5 "
                 "(exit 0 all pass, 1 any differs, 2 bad input)");
  sub->add_option("DIR", args->dir, "Folder of regression cases")->required();
  // The tolerances' rule (finite, >= 0) is validate(CompareOptions), checked first below.
  sub->add_option("--rtol", args->opt.rtol, "Relative tolerance (>= 0)")->capture_default_str();
  sub->add_option("--atol", args->opt.atol, "Absolute tolerance (>= 0)")->capture_default_str();
  sub->add_flag("--update", args->update, "Rewrite the references from fresh runs (after an intended change of results)");
  sub->add_option("--keep", args->keep, "Keep the fresh runs in this folder (default: a temporary folder, removed)");
  registry[sub] = [args] {
    validate(args->opt);
    const fs::path dir(args->dir);
    const std::vector<Case> cases = find_cases(dir);
    if (!args->update) {
      std::string missing;
      for (const Case& c : cases)
        if (!fs::exists(c.reference)) missing += (missing.empty() ? "" : ", ") + c.reference.string();
      if (!missing.empty())
        throw InputError("no reference run: " + missing + "; create references with `floesim regress " +
                         args->dir + " --update` (and commit them)");
    }
    for (const Case& c : cases) build_scenario(load_config(c.config.string()));  // bad input before any run

    TempDir temp;
    fs::path out_dir = temp.path;
    if (!args->keep.empty()) {
      out_dir = args->keep;
      std::error_code ec;
      fs::create_directories(out_dir, ec);
      if (!fs::is_directory(out_dir)) throw InputError(args->keep + ": cannot create this folder for --keep");
    }

    std::size_t width = 4;
    for (const Case& c : cases) width = std::max(width, c.name.size());
    std::cout << "regress " << args->dir << ": " << cases.size() << " case(s), rtol " << args->opt.rtol << ", atol "
              << args->opt.atol << (args->update ? ", updating references" : "") << "\n";
    auto line = [&](const std::string& name, const std::string& status, const std::string& diff,
                    const std::string& where, const std::string& time, const std::string& wall) {
      std::cout << std::left << std::setw(static_cast<int>(width) + 2) << name << std::setw(10) << status
                << std::setw(11) << diff << std::setw(36) << where << std::setw(12) << time << wall << "\n";
    };
    line("case", "status", "max |a-b|", "where", "t (s)", "wall (s)");
    std::size_t bad = 0;
    std::vector<std::pair<std::string, Row>> reports;
    for (const Case& c : cases) {
      const Row row = run_case(c, out_dir / (c.name + ".h5"), args->opt, args->update);
      line(c.name, row.status, row.max_diff, row.where, row.time, format_number(row.wall, 2));
      std::cout.flush();
      if (row.status == "DIFFERS" || row.status == "FAILED") ++bad;
      if (!row.details.empty()) reports.emplace_back(c.name, row);
    }
    for (const auto& [name, row] : reports) {
      std::cout << "\n" << name << (args->update ? " (new run against the old reference):" : ":") << "\n";
      for (const std::string& d : row.details) std::cout << "  " << d << "\n";
    }
    if (args->update) {
      std::cout << "\nreferences in " << args->dir
                << " (new, updated: written; unchanged: equal to the fresh run, left as they were); "
                   "commit them and say why the results changed\n";
      return bad ? 1 : 0;
    }
    std::cout << "\n" << cases.size() - bad << " of " << cases.size() << " case(s) pass\n";
    if (!args->keep.empty()) std::cout << "runs kept in " << out_dir.string() << "\n";
    return bad ? 1 : 0;
  };
}

}  // namespace floesim::apps
