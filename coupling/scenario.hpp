#pragma once
// A Scenario is a run's problem as data: the floes at t = 0, the parameters,
// the forcing. Built from a Config (files read, floes checked) and shared by
// the `floesim run` command, the tests, the benchmarks and the examples.

#include <array>
#include <optional>
#include <string>
#include <vector>

#include "core/config.hpp"
#include "core/floes.hpp"
#include "core/forcing.hpp"

namespace floesim {

struct Scenario {
  Config config;                 // the parameters in force (resolved)
  Floes floes;                   // at t = 0
  ForcingSeries forcing;
  std::optional<std::array<double, 4>> window;  // from a pack file, if any
  std::vector<std::string> notes;  // said once to the user (e.g. reoriented floes)
};

// Loads the pack file (if any) then the inline floes, checks every floe and the
// forcing series. Throws InputError for any bad input.
Scenario build_scenario(const Config& config);

// InputError unless every floe that moves is on the sea: whole inside a walled
// sea (bem, or the tank's zones), its centroid inside a periodic sea's box and
// narrower than that box (along x only when dims = 1). build_scenario calls it.
void check_floes_on_sea(const Scenario& scenario);

}  // namespace floesim
