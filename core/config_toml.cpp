// The configuration written back as TOML (resolved_toml: every key, defaults
// included, as the run file stores it) and two such texts compared key by key
// (physics_differences, for restarts). The choices' names are those the
// reader accepts (core/detail/config_names.hpp).
#include <toml++/toml.h>

#include <charconv>
#include <map>
#include <set>
#include <sstream>

#include "core/config.hpp"
#include "core/detail/config_names.hpp"
#include "core/error.hpp"

namespace floesim {

namespace {
using namespace detail;
toml::array pair_array(const std::array<double, 2>& a) { return toml::array{a[0], a[1]}; }
}  // namespace

std::string resolved_toml(const Config& c) {
  toml::table run{{"t_end", c.run.t_end}, {"dt_max", c.run.dt_max},
                  {"output_interval", c.run.output_interval},
                  {"seed", static_cast<int64_t>(c.run.seed)}, {"checkpoint_interval", c.run.checkpoint_interval},
                  {"record_collisions", c.run.record_collisions}};
  const WaveParams& w = c.sea.waves;
  toml::table waves{{"kind", name_of(w.kind, kWaveKinds)},
                    {"amplitude", w.amplitude}, {"direction", w.direction}, {"hs", w.hs}, {"tp", w.tp}, {"gamma", w.gamma},
                    {"spreading", w.spreading}};
  if (w.wavelength > 0.0) waves.insert("wavelength", w.wavelength);
  if (w.period > 0.0) waves.insert("period", w.period);
  toml::array bottom;
  for (auto& b : c.sea.bottom) bottom.push_back(pair_array(b));
  toml::table sea{{"model", name_of(c.sea.model, kSeaModels)},
                  {"dims", c.sea.dims}, {"size", pair_array(c.sea.size)},
                  {"cells", toml::array{c.sea.cells[0], c.sea.cells[1]}}, {"depth", c.sea.depth},
                  {"rho", c.sea.rho}, {"g", c.sea.g}, {"sigma", c.sea.sigma}, {"waves", waves}};
  if (!bottom.empty()) sea.insert("bottom", bottom);
  if (!c.sea.bottom_file.empty()) sea.insert("bottom_file", c.sea.bottom_file);
  if (c.sea.bem_modes != 0) sea.insert("bem_modes", c.sea.bem_modes);
  if (c.sea.bem_static_correction) sea.insert("bem_static_correction", true);
  if (c.sea.tank.enabled)
    sea.insert("tank", toml::table{{"enabled", true}, {"generation_length", c.sea.tank.generation_length},
                                   {"absorption_length", c.sea.tank.absorption_length}, {"rate", c.sea.tank.rate},
                                   {"ramp_periods", c.sea.tank.ramp_periods}});

  toml::array floe_list;
  for (const FloeInput& f : c.floes.floes) {
    toml::array verts;
    for (auto& v : f.vertices) verts.push_back(toml::array{v.x(), v.y()});
    toml::table t{{"vertices", verts}, {"velocity", toml::array{f.velocity.x(), f.velocity.y()}},
                  {"angular_velocity", f.angular_velocity}, {"thickness", f.thickness},
                  {"density", f.density}, {"static", f.is_static}};
    if (f.ocean_drag >= 0.0) t.insert("ocean_drag", f.ocean_drag);
    if (f.heave != 0.0) t.insert("heave", f.heave);
    if (f.heave_rate != 0.0) t.insert("heave_rate", f.heave_rate);
    if (f.mooring_period > 0.0) {
      t.insert("mooring_period", f.mooring_period);
      t.insert("mooring_damping", f.mooring_damping);
    }
    floe_list.push_back(t);
  }
  toml::table floes{{"thickness", c.floes.defaults.thickness}, {"density", c.floes.defaults.density}};
  if (!c.floes.pack.empty()) floes.insert("pack", c.floes.pack);
  if (!floe_list.empty()) floes.insert("floe", floe_list);

  toml::table contact{{"collision_distance", c.contact.collision_distance},
                      {"restitution", c.contact.restitution}, {"friction", c.contact.friction},
                      {"rest_speed", c.contact.rest_speed},
                      {"domain", name_of(c.contact.periodic, kDomains)}};
  if (!c.contact.dump_failed_lcps.empty()) contact.insert("dump_failed_lcps", c.contact.dump_failed_lcps);
  if (c.contact.box[1] > c.contact.box[0])
    contact.insert("box", toml::array{c.contact.box[0], c.contact.box[1], c.contact.box[2], c.contact.box[3]});
  toml::table coupling{{"law", name_of(c.coupling.law, kPenaltyLaws)},
                       {"stiffness", c.coupling.stiffness},
                       {"start", name_of(c.coupling.start_given, kStarts)},
                       {"footprint", name_of(c.coupling.footprint, kFootprints)},
                       {"footprint_reach", c.coupling.footprint_reach},
                       {"integrator", name_of(c.coupling.integrator, kIntegrators)},
                       {"horizontal_loads", name_of(c.coupling.horizontal_loads, kHorizontalLoads)},
                       {"newton_tolerance", c.coupling.newton_tolerance},
                       {"cg_tolerance", c.coupling.cg_tolerance},
                       {"cg_forcing", c.coupling.cg_forcing}};
  if (c.coupling.law == PenaltyLaw::blend) {
    if (c.coupling.restitution >= 0.0) coupling.insert("restitution", c.coupling.restitution);
    else coupling.insert("blend", c.coupling.blend);
  }
  toml::table forcing{{"current", pair_array(c.forcing.current)}, {"wind", pair_array(c.forcing.wind)},
                      {"series_interpolation", name_of(c.forcing.series_interpolation, kSeriesInterpolations)},
                      {"coriolis", c.forcing.coriolis}, {"ocean_drag", c.forcing.ocean_drag},
                      {"air_drag", c.forcing.air_drag}, {"air_density", c.forcing.air_density}};
  if (!c.forcing.series.empty()) forcing.insert("series", c.forcing.series);
  const FractureParams& fr = c.fracture;
  toml::array loads;
  for (auto& l : fr.loads) {
    toml::table t{{"point", pair_array(l.point)}};
    t.insert(l.is_impulse ? "impulse" : "force", pair_array(l.is_impulse ? l.impulse : l.force));
    loads.push_back(t);
  }
  toml::table fracture{{"enabled", fr.enabled},
                       {"criterion", name_of(fr.criterion, kFractureCriteria)},
                       {"strength", fr.strength}, {"toughness", fr.toughness}, {"young", fr.young},
                       {"poisson", fr.poisson}, {"split", fr.split}, {"mesh_size", fr.mesh_size},
                       {"duration", fr.duration}, {"load_radius", fr.load_radius},
                       {"min_fragment_area", fr.min_fragment_area}, {"elements_across", fr.elements_across},
                       {"mesher", name_of(fr.mesher, kFractureMeshers)}};
  if (!loads.empty()) fracture.insert("load", loads);

  toml::table root{{"run", run}, {"sea", sea}, {"floes", floes}, {"contact", contact},
                   {"coupling", coupling}, {"forcing", forcing}, {"fracture", fracture}};
  std::ostringstream os;
  os << root;
  return os.str();
}

namespace {
// A TOML value as text, numbers in their shortest exact form (0.4, not
// 0.40000000000000002), arrays and inline tables whole.
std::string value_text(const toml::node& node) {
  if (const auto* d = node.as_floating_point()) {
    char buf[64];
    const auto r = std::to_chars(buf, buf + sizeof buf, d->get());
    return std::string(buf, r.ptr);
  }
  if (const auto* i = node.as_integer()) return std::to_string(i->get());
  if (const auto* b = node.as_boolean()) return b->get() ? "true" : "false";
  if (const auto* s = node.as_string()) return "\"" + s->get() + "\"";
  std::string out;
  if (const auto* a = node.as_array()) {
    out = "[";
    for (std::size_t k = 0; k < a->size(); ++k) out += (k ? ", " : "") + value_text(*a->get(k));
    return out + "]";
  }
  if (const auto* t = node.as_table()) {
    out = "{";
    for (const auto& [k, v] : *t) out += (out.size() > 1 ? ", " : "") + std::string(k.str()) + " = " + value_text(v);
    return out + "}";
  }
  std::ostringstream o;
  node.visit([&](const auto& n) { o << n; });
  return o.str();
}

// Each leaf of a TOML table as "[section] key" -> its value as text.
void flatten(const toml::table& t, const std::string& section, std::map<std::string, std::string>& out) {
  for (const auto& [k, node] : t) {
    const std::string key(k.str());
    const std::string path = section.empty() ? key : section + "." + key;
    if (const toml::table* sub = node.as_table()) {
      flatten(*sub, path, out);
      continue;
    }
    // An array of tables (the inline floes) key by key, "[floes.floe 3] velocity".
    if (const toml::array* a = node.as_array(); a && !a->empty() && a->is_array_of_tables()) {
      for (std::size_t i = 0; i < a->size(); ++i) flatten(*a->get(i)->as_table(), path + " " + std::to_string(i), out);
      out["[" + path + "] count"] = std::to_string(a->size());
      continue;
    }
    out[(section.empty() ? key : "[" + section + "] " + key)] = value_text(node);
  }
}
}  // namespace

std::vector<std::string> physics_differences(std::string_view run_toml, std::string_view now_toml,
                                             const std::string& run_name) {
  std::map<std::string, std::string> a, b;
  try {
    flatten(toml::parse(run_toml), "", a);
  } catch (const toml::parse_error& e) {
    throw InputError(run_name + ": the stored configuration is not TOML (" + std::string(e.description()) + ")");
  }
  flatten(toml::parse(now_toml), "", b);
  static const std::set<std::string> kFree = {"[run] t_end", "[run] checkpoint_interval"};
  std::vector<std::string> out;
  for (const auto& [key, value] : a) {
    if (kFree.count(key)) continue;
    const auto it = b.find(key);
    if (it == b.end()) out.push_back(key + ": " + value + " -> (not set)");
    else if (it->second != value) out.push_back(key + ": " + value + " -> " + it->second);
  }
  for (const auto& [key, value] : b)
    if (!kFree.count(key) && !a.count(key)) out.push_back(key + ": (not set) -> " + value);
  return out;
}

}  // namespace floesim
