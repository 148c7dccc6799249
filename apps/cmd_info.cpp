// floesim info OUT.h5 [--json]: what a run file holds, with final diagnostics.
#include <iostream>
#include <sstream>

#include "apps/commands.hpp"
#include "core/run_file.hpp"

namespace floesim::apps {

namespace {
std::string fmt(double v) {
  std::ostringstream o;
  o << v;
  return o.str();
}

std::string json_string(const std::string& s) {
  std::ostringstream o;
  o << '"';
  for (char c : s) {
    switch (c) {
      case '"': o << "\\\""; break;
      case '\\': o << "\\\\"; break;
      case '\n': o << "\\n"; break;
      case '\t': o << "\\t"; break;
      default:
        if (static_cast<unsigned char>(c) < 0x20) o << "\\u00" << "0123456789abcdef"[c >> 4] << "0123456789abcdef"[c & 15];
        else o << c;
    }
  }
  o << '"';
  return o.str();
}
std::string shape(const std::vector<unsigned long long>& d) {
  std::string s;
  for (auto x : d) s += (s.empty() ? "" : ", ") + std::to_string(x);
  return "[" + s + "]";
}
}  // namespace

void add_info_command(CLI::App& app, Registry& registry) {
  struct Args { std::string file; bool json = false, config = false; };
  auto args = std::make_shared<Args>();
  CLI::App* sub = app.add_subcommand("info", "Show what a run file holds and its final diagnostics");
  sub->add_option("FILE", args->file, "Run file (.h5)")->required();
  sub->add_flag("--json", args->json, "Print JSON instead of key: value lines");
  sub->add_flag("--config", args->config, "Also print the resolved configuration");
  registry[sub] = [args] {
    const RunInfo r = read_run_info(args->file);
    std::ostream& o = std::cout;
    o.precision(10);
    if (args->json) {
      o << "{\n  \"file\": " << json_string(args->file) << ",\n  \"format\": " << json_string(r.format)
        << ",\n  \"status\": " << json_string(r.status) << ",\n  \"records\": " << r.records
        << ",\n  \"t_first\": " << r.t_first << ",\n  \"t_last\": " << r.t_last;
      if (r.checkpoint_time >= 0.0) o << ",\n  \"checkpoint\": " << r.checkpoint_time;
      else o << ",\n  \"checkpoint\": null";
      o << ",\n  \"floes\": " << r.floes
        << ",\n  \"vertices\": " << r.vertices << ",\n  \"energy\": {";
      for (std::size_t k = 0; k < r.energy_columns.size(); ++k)
      {
        o << (k ? ", " : "") << json_string(r.energy_columns[k]) << ": ";
        if (k < r.energy_last.size()) o << r.energy_last[k];
        else o << "null";
      }
      o << "},\n  \"lcp\": {\"solves\": " << r.lcp_last[0] << ", \"pivots\": " << r.lcp_last[1]
        << ", \"failures\": " << r.lcp_last[2] << ", \"fallbacks\": " << r.lcp_last[3] << "},\n  \"substeps\": {";
      for (int k = 0; k < kSubstepColumns; ++k)
        o << (k ? ", " : "") << json_string(kSubstepColumnNames[k]) << ": " << r.substeps_last[static_cast<std::size_t>(k)];
      o << "},\n  \"datasets\": {";
      for (std::size_t k = 0; k < r.datasets.size(); ++k)
        o << (k ? ", " : "") << json_string(r.datasets[k].first) << ": " << shape(r.datasets[k].second);
      o << "}";
      if (args->config) o << ",\n  \"config\": " << json_string(r.config);
      o << "\n}\n";
      return 0;
    }
    const std::string status = r.status == "running" ? "running (no end mark: still being written, or the run was killed)" : r.status;
    o << "file: " << args->file << "\nformat: " << r.format << "\nstatus: " << status
      << "\nrecords: " << r.records << "\ntime: " << r.t_first << " .. " << r.t_last << " s\ncheckpoint: "
      << (r.checkpoint_time >= 0.0 ? "t = " + fmt(r.checkpoint_time) + " s (floesim run --restart " + args->file + ")" : "none")
      << "\nfloes: " << r.floes
      << "\nvertices: " << r.vertices << "\n";
    for (std::size_t k = 0; k < r.energy_columns.size() && k < r.energy_last.size(); ++k)
      o << "energy." << r.energy_columns[k] << ": " << r.energy_last[k] << " J\n";
    o << "lcp.solves: " << r.lcp_last[0] << "\nlcp.pivots: " << r.lcp_last[1] << "\nlcp.failures: " << r.lcp_last[2]
      << "\nlcp.fallbacks: " << r.lcp_last[3] << "\n";
    for (int k = 0; k < kSubstepColumns; ++k)
      o << "substeps." << kSubstepColumnNames[k] << ": " << r.substeps_last[static_cast<std::size_t>(k)] << "\n";
    for (const auto& [p, d] : r.datasets) o << "dataset: " << p << " " << shape(d) << "\n";
    if (args->config) o << "config:\n" << r.config << "\n";
    return 0;
  };
}

}  // namespace floesim::apps
