// floesim command line: dispatches to one subcommand per apps/cmd_*.cpp.
#include <unistd.h>

#include <cstdlib>
#include <iostream>
#include <map>
#include <string>

#include "apps/commands.hpp"

namespace {

// OpenMP's idle threads wait for the next parallel loop by spinning (libgomp's
// default). On cores shared with other work every loop then waits for the
// spinning threads' scheduler slices (docs/coupling.md, "Threads"). The
// runtime reads OMP_WAIT_POLICY once, as it loads, so unless the user chose a
// policy the command line sets "passive" and starts itself again, once.
void prefer_passive_waits(char** argv) {
  if (std::getenv("OMP_WAIT_POLICY") != nullptr) return;
  if (setenv("OMP_WAIT_POLICY", "passive", 0) != 0) return;
  execv("/proc/self/exe", argv);  // returns only on failure: go on as we are
}

}  // namespace

int main(int argc, char** argv) {
  prefer_passive_waits(argv);
  CLI::App app{"floesim: sea-ice floes on waves (rigid floes, Lemke collisions, "
               "penalised capillary-gravity sea)"};
  app.require_subcommand(1);
  app.set_version_flag("--version", std::string(FLOESIM_VERSION));

  floesim::apps::Registry handlers;
  // registrations (one line per command, alphabetical)
  floesim::apps::add_compare_command(app, handlers);
  floesim::apps::add_fracture_command(app, handlers);
  floesim::apps::add_info_command(app, handlers);
  floesim::apps::add_lcp_command(app, handlers);
  floesim::apps::add_pack_command(app, handlers);
  floesim::apps::add_plot_command(app, handlers);
  floesim::apps::add_regress_command(app, handlers);
  floesim::apps::add_render_command(app, handlers);
  floesim::apps::add_run_command(app, handlers);

  // CLI11 answers an unknown word (or none) with "A subcommand is required": name it and list ours.
  if (argc == 1 || argv[1][0] != '-') {
    std::string names;
    bool known = false;
    for (const CLI::App* sub : app.get_subcommands([](CLI::App*) { return true; })) {
      names += (names.empty() ? "" : ", ") + sub->get_name();
      known = known || (argc > 1 && sub->check_name(argv[1]));
    }
    if (!known) {
      std::cerr << "floesim: error: "
                << (argc == 1 ? std::string("a subcommand is required")
                              : "unknown subcommand '" + std::string(argv[1]) + "'")
                << "; expected one of: " << names << " (floesim --help)\n";
      return 2;
    }
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return code == 0 ? 0 : 2;
  }
  try {
    for (auto& [sub, handler] : handlers)
      if (sub->parsed()) return handler();
  } catch (...) {
    return floesim::apps::report_failure(std::current_exception());
  }
  return 2;
}
