#pragma once
// Each floesim subcommand lives in its own apps/cmd_*.cpp and registers itself
// on the CLI11 app here. A registered handler returns the process exit code
// (0 success, 1 the run failed numerically, 2 bad input or usage).

#include <CLI/CLI.hpp>
#include <functional>

namespace floesim::apps {

using Handler = std::function<int()>;

// Adds the subcommand and returns the function to call when it was chosen.
// (Add one line per command; keep alphabetical.)

}  // namespace floesim::apps
