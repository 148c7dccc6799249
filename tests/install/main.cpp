// A program outside floesim that uses the installed library: one floe pushed
// by a steady wind, stepped for 600 s; with a file argument, that scenario is
// loaded as well (reading the files it names) and its floes counted.
#include <iostream>

#include <floesim/core/config.hpp>
#include <floesim/coupling/scenario.hpp>
#include <floesim/coupling/simulation.hpp>

int main(int argc, char** argv) {
  const char* text = R"(
[run]
t_end = 600.0
dt_max = 10.0
output_interval = 60.0

[sea]
model = "none"

[[floes.floe]]
vertices = [[0, 0], [40, 0], [45, 30], [5, 35]]
thickness = 1.2

[forcing]
wind = [15.0, 0.0]
)";
  floesim::Simulation sim(floesim::build_scenario(floesim::parse_config(text, "inline", ".")));
  const double x0 = sim.floes().state[0].x;
  while (sim.time() < 600.0) sim.step(600.0);
  const floesim::FloeState& s = sim.floes().state[0];
  std::cout << "floes: " << sim.floes().size() << "\n"
            << "t: " << sim.time() << "\n"
            << "dx: " << s.x - x0 << "\n"
            << "vx: " << s.vx << "\n";
  if (argc > 1) {
    const floesim::Scenario loaded = floesim::build_scenario(floesim::load_config(argv[1]));
    std::cout << "loaded_floes: " << loaded.floes.size() << "\n";
  }
  return 0;
}
