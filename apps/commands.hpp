#pragma once
// Each floesim subcommand lives in its own apps/cmd_*.cpp and registers itself
// on the CLI11 app here. A registered handler returns the process exit code
// (0 success, 1 the run failed numerically, 2 bad input or usage).

#include <CLI/CLI.hpp>
#include <functional>
#include <map>

namespace floesim::apps {

using Handler = std::function<int()>;
using Registry = std::map<CLI::App*, Handler>;

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
