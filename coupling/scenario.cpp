#include "coupling/scenario.hpp"

#include "core/error.hpp"
#include "fluid/sea.hpp"

namespace floesim {

Scenario build_scenario(const Config& config) {
  Scenario s{config, {}, make_forcing(config.forcing), std::nullopt, {}};
  std::vector<FloeInput> inputs;
  if (!config.floes.pack.empty()) {
    Pack pack = read_pack(config.floes.pack, config.floes.defaults);
    s.window = pack.window;
    inputs = std::move(pack.floes);
  }
  inputs.insert(inputs.end(), config.floes.floes.begin(), config.floes.floes.end());
  std::size_t reoriented = 0;
  for (const FloeInput& in : inputs) {
    const FloeShape shape = make_floe_shape(in);
    if (shape.reoriented) ++reoriented;
    s.floes.add(shape, in);
  }
  if (reoriented)
    s.notes.push_back(std::to_string(reoriented) + " floe outline(s) given clockwise were reoriented "
                      "counter-clockwise");
  try {
    fluid::validate(config.sea);  // names the [sea] key; add the file
  } catch (const InputError& e) {
    throw InputError(config.file + ": " + e.what());
  }
  return s;
}

}  // namespace floesim
