#include "coupling/scenario.hpp"

#include <limits>
#include <sstream>

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
  check_floes_on_sea(s);
  return s;
}

void check_floes_on_sea(const Scenario& s) {
  const SeaParams& sea = s.config.sea;
  if (sea.model == SeaModel::none) return;
  // A walled sea (a bem basin; the tank's zones, which absorb at x = 0 and
  // x = Lx) holds a floe whole; a periodic sea holds its centroid, and a floe
  // wider than the box would lie over its own periodic image. dims = 1: the
  // sea is uniform along y, so only x is checked.
  const bool walled = sea.model == SeaModel::bem || sea.tank.enabled;
  const int axes = sea.dims == 2 ? 2 : 1;
  const char* names[2] = {"x", "y"};
  for (std::size_t i = 0; i < s.floes.size(); ++i) {
    if (s.floes.is_static[i]) continue;  // obstacles are not on the sea
    Vec2 lo = Vec2::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
    for (const Vec2& b : s.floes.vertices(i)) {
      const Vec2 p = s.floes.to_world(i, b);
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
    }
    const Vec2 c{s.floes.state[i].x, s.floes.state[i].y};
    for (int a = 0; a < axes; ++a) {
      const double L = sea.size[static_cast<std::size_t>(a)];
      std::ostringstream m;
      m << "floe " << i << " (pack floes first, then inline ones): ";
      if (walled && (lo[a] < 0.0 || hi[a] > L))
        m << "spans " << names[a] << " in [" << lo[a] << ", " << hi[a] << "] m, outside the sea's basin [0, " << L
          << "] m ([sea] size; walled: " << (sea.tank.enabled ? "[sea.tank] zones" : "model = \"bem\"") << ")";
      else if (!walled && !(c[a] >= 0.0 && c[a] <= L))
        m << "centroid " << names[a] << " = " << c[a] << " m is outside the sea's periodic box [0, " << L
          << "] m ([sea] size)";
      else if (!walled && hi[a] - lo[a] >= L)
        m << "is " << hi[a] - lo[a] << " m wide along " << names[a] << ", not less than the sea's periodic box of "
          << L << " m ([sea] size): it would overlap its own periodic image";
      else
        continue;
      throw InputError(where(s.config.file, 0, "", m.str()));
    }
  }
}

}  // namespace floesim
