#pragma once
// Each floesim subcommand lives in its own apps/cmd_*.cpp and registers itself
// on the CLI11 app here. A registered handler returns the process exit code
// (0 success, 1 the run failed numerically, 2 bad input or usage).

#include <CLI/CLI.hpp>
#include <cmath>
#include <exception>
#include <functional>
#include <map>
#include <string>

namespace floesim::apps {

using Handler = std::function<int()>;
using Registry = std::map<CLI::App*, Handler>;

// Says a command's failure on stderr ("floesim: error: ..." for bad input,
// "floesim: run failed: ..." otherwise) and returns its exit code (2 or 1).
// apps/main.cpp says every command's failures so; a command that must say
// it before it ends (the run under mpirun: docs/parallel.md) calls it itself.
int report_failure(std::exception_ptr failure);

// Checks of option values shared by the subcommands; a failed check is a usage
// error (exit 2) "--OPTION: expected ..., got ...".
// A finite number >= 0: CLI::NonNegativeNumber lets nan and inf through.
inline CLI::Validator finite_non_negative() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        double v = 0.0;
        if (!CLI::detail::lexical_cast(text, v) || !std::isfinite(v) || v < 0.0)
          return "expected a finite number >= 0, got '" + text + "'";
        return {};
      },
      "NUMBER >= 0");
}
// A count for an unsigned option: digits only, since "-5" would wrap to 2^64 - 5.
inline CLI::Validator unsigned_count() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        if (text.empty() || text.find_first_not_of("0123456789") != std::string::npos)
          return "expected a whole number >= 0, got '" + text + "'";
        return {};
      },
      "COUNT");
}

// Each adds its subcommand to `app` and its handler to `registry`.
// (One line per command; keep alphabetical.)
void add_compare_command(CLI::App& app, Registry& registry);
void add_fracture_command(CLI::App& app, Registry& registry);
void add_info_command(CLI::App& app, Registry& registry);
void add_lcp_command(CLI::App& app, Registry& registry);
void add_pack_command(CLI::App& app, Registry& registry);
void add_plot_command(CLI::App& app, Registry& registry);
void add_regress_command(CLI::App& app, Registry& registry);
void add_render_command(CLI::App& app, Registry& registry);
void add_run_command(CLI::App& app, Registry& registry);

}  // namespace floesim::apps
