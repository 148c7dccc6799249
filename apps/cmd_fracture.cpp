// floesim fracture CONFIG.toml [--probe X Y]...
// Percussion analysis of one floe (MODEL.md §6, docs/fracture.md): the floe
// of the configuration, the [[fracture.load]] forces and impulses, the
// [fracture] model and criterion. Prints key: value lines:
//   max_principal_stress (Pa, the largest tensile principal stress over the
//   floe and the response), at (x y, world, where it is), direction (degrees
//   from +x of the crack it would open, perpendicular to that stress),
//   initiates (true/false), and for an initiation crack_from, crack_to
//   (x y, world: the crack of the criterion); then details: criterion, nodes,
//   triangles, mesh_size, load_factor (strength / max_principal_stress: the
//   factor on the loads at which the stress criterion would initiate), time
//   (s into the response of that stress), steps, dt, through, the griffith
//   energies, one probe line per --probe (sxx syy sxy at that point, Pa, at
//   the instant of max_principal_stress), time_ms.
// Exit 0 when the analysis ran (whether or not it initiates), 2 for bad input.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <iostream>
#include <limits>
#include <memory>
#include <sstream>

#include "apps/commands.hpp"
#include "contact/fracture/floe_fracture.hpp"
#include "core/config.hpp"
#include "core/error.hpp"
#include "coupling/scenario.hpp"

namespace floesim::apps {

namespace {

struct FractureArgs {
  std::string config;
  std::vector<double> probes;  // x y pairs
};

// Distance from p to the polygon (0 inside).
double distance_to(std::span<const Vec2> v, const Vec2& p) {
  if (point_in_polygon(v, p)) return 0.0;
  double best = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < v.size(); ++i) {
    const Vec2 a = v[i], e = v[(i + 1) % v.size()] - a;
    const double s = std::clamp((p - a).dot(e) / e.squaredNorm(), 0.0, 1.0);
    best = std::min(best, (a + s * e - p).norm());
  }
  return best;
}

std::string pair(const Vec2& p) {
  std::ostringstream o;
  o.precision(8);
  o << p.x() << " " << p.y();
  return o.str();
}

int run_fracture(const FractureArgs& args) {
  const Config config = load_config(args.config);
  const Scenario scenario = build_scenario(config);
  const Floes& floes = scenario.floes;
  if (floes.size() != 1)
    throw InputError(args.config + ": floesim fracture studies one floe ([[floes.floe]] or a pack of one), got " +
                     std::to_string(floes.size()));
  const FractureParams& params = config.fracture;
  if (params.loads.empty())
    throw InputError(args.config + ": [[fracture.load]]: at least one load (point and force or impulse) is needed");
  if (args.probes.size() % 2) throw InputError("--probe: expected X Y");

  const auto start = std::chrono::steady_clock::now();
  const FloeState& s = floes.state[0];
  const Vec2 g{s.x, s.y};
  fracture::FloeFracture floe(floes.vertices(0), floes.thickness[0], floes.density[0], params);
  const double radius = floe.responder().options().load_radius;
  const std::vector<Vec2> outline = floes.world_vertices(0);
  std::vector<fracture::PointLoad> loads;
  for (std::size_t k = 0; k < params.loads.size(); ++k) {
    const FractureLoad& l = params.loads[k];
    const Vec2 point{l.point[0], l.point[1]};
    if (distance_to(outline, point) > radius)
      throw InputError(args.config + ": [[fracture.load]] " + std::to_string(k + 1) + ": point (" + pair(point) +
                       ") is not on the floe (farther than the load radius " + std::to_string(radius) + " m)");
    const Vec2 value = l.is_impulse ? Vec2{l.impulse[0], l.impulse[1]} : Vec2{l.force[0], l.force[1]};
    loads.push_back({rotate(point - g, -s.yaw), rotate(value, -s.yaw), l.is_impulse});
  }
  const fracture::FloeFracture::Result r = floe.analyse(loads);
  const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();

  const fracture::Snapshot& peak = r.response.peak_stress;
  const fracture::Initiation& init = r.initiation;
  const fracture::Mesh& mesh = floe.model().mesh();
  auto world = [&](const Vec2& p) -> Vec2 { return g + rotate(p, s.yaw); };
  // The crack a stress peak would open runs perpendicular to it.
  double direction = std::fmod(peak.angle + 0.5 * M_PI + s.yaw, M_PI);
  if (direction < 0.0) direction += M_PI;
  std::ostream& o = std::cout;
  o.precision(8);
  o << "max_principal_stress: " << peak.max_principal << "\n"
    << "at: " << pair(world(mesh.nodes[peak.node])) << "\n"
    << "direction: " << direction * 180.0 / M_PI << "\n"
    << "initiates: " << (init.initiates ? "true" : "false") << "\n";
  if (init.initiates)
    o << "crack_from: " << pair(world(init.crack_from)) << "\n"
      << "crack_to: " << pair(world(init.crack_to)) << "\n";
  o << "criterion: " << (params.criterion == FractureCriterion::stress ? "stress" : "griffith") << "\n"
    << "nodes: " << mesh.node_count() << "\n"
    << "triangles: " << mesh.triangles.size() << "\n"
    << "mesh_size: " << mesh.size << "\n"
    << "load_factor: " << (peak.max_principal > 0.0 ? params.strength / peak.max_principal : INFINITY) << "\n"
    << "time: " << peak.time << "\n"
    << "steps: " << r.response.steps << "\n"
    << "dt: " << r.response.dt << "\n"
    << "through: " << (init.through ? "true" : "false") << "\n";
  if (params.criterion == FractureCriterion::griffith)
    o << "energy_released: " << init.energy_released << "\n"
      << "energy_needed: " << init.energy_needed << "\n"
      << "growth_released: " << init.growth_released << "\n"
      << "growth_needed: " << init.growth_needed << "\n";
  const std::vector<Eigen::Vector3d> stress = floe.model().nodal_stress(peak.u);
  for (std::size_t k = 0; k + 1 < args.probes.size(); k += 2) {
    const Vec2 p{args.probes[k], args.probes[k + 1]};
    Eigen::Vector3d v;
    if (!floe.model().interpolate(stress, rotate(p - g, -s.yaw), v))
      throw InputError("--probe " + pair(p) + ": the point is not on the floe");
    // Back to the world frame: sigma_w = R sigma R^T.
    const double c = std::cos(s.yaw), sn = std::sin(s.yaw);
    Eigen::Matrix2d m, rot;
    m << v[0], v[2], v[2], v[1];
    rot << c, -sn, sn, c;
    const Eigen::Matrix2d w = rot * m * rot.transpose();
    o << "probe: " << pair(p) << " " << w(0, 0) << " " << w(1, 1) << " " << w(0, 1) << "\n";
  }
  o << "time_ms: " << ms << "\n";
  return 0;
}

}  // namespace

void add_fracture_command(CLI::App& app, Registry& registry) {
  auto args = std::make_shared<FractureArgs>();
  CLI::App* sub = app.add_subcommand(
      "fracture", "Percussion analysis of one floe under [[fracture.load]] forces and impulses");
  sub->add_option("CONFIG", args->config, "Configuration file (.toml) with one floe and [[fracture.load]]")->required();
  sub->add_option("--probe", args->probes, "Also print the stress at X Y (world), repeatable")
      ->expected(2)
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
  registry[sub] = [args] { return run_fracture(*args); };
}

}  // namespace floesim::apps
