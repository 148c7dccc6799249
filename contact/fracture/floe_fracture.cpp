#include "contact/fracture/floe_fracture.hpp"

#include <chrono>
#include <limits>

namespace floesim::fracture {

MeshOptions mesh_options(const FractureParams& p) {
  MeshOptions o;
  o.size = p.mesh_size;
  o.across = p.elements_across;
  o.mesher = p.mesher == FractureMesher::cgal ? Mesher::cgal : Mesher::automatic;
  return o;
}

ResponseOptions response_options(const FractureParams& p, double thickness) {
  ResponseOptions o;
  o.duration = p.duration;
  o.load_radius = p.load_radius > 0.0 ? p.load_radius : thickness;
  return o;
}

CriterionOptions criterion_options(const FractureParams& p) {
  CriterionOptions o;
  o.criterion = p.criterion == FractureCriterion::stress ? Criterion::stress : Criterion::griffith;
  o.strength = p.strength;
  o.toughness = p.toughness;
  return o;
}

namespace {
Mesh timed_mesh(std::span<const Vec2> polygon, const MeshOptions& options, double& seconds) {
  const auto begin = std::chrono::steady_clock::now();
  Mesh mesh = mesh_polygon(polygon, options);
  seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - begin).count();
  return mesh;
}
}  // namespace

FloeFracture::FloeFracture(std::span<const Vec2> polygon, double thickness, double density,
                           const FractureParams& params)
    : polygon_(polygon.begin(), polygon.end()),
      model_(timed_mesh(polygon, mesh_options(params), mesh_seconds_),
             Material{params.young, params.poisson, density, thickness}),
      responder_(model_, response_options(params, thickness)),
      criterion_(criterion_options(params)) {}

FloeFracture::Result FloeFracture::judged(std::span<const PointLoad> loads, const Observer& observe, double level) {
  Result r;
  r.response = responder_.respond(loads, observe, level);
  r.initiation = judge(responder_, r.response, polygon_, criterion_);
  return r;
}

FloeFracture::Result FloeFracture::analyse(std::span<const PointLoad> loads, const Observer& observe) {
  return judged(loads, observe, -std::numeric_limits<double>::infinity());
}

FloeFracture::Result FloeFracture::decide(std::span<const PointLoad> loads) {
  // Griffith's criterion judges the energy peak of the whole response: no level stops it.
  const bool stress = criterion_.criterion == Criterion::stress;
  return judged(loads, {}, stress ? criterion_.strength : -std::numeric_limits<double>::infinity());
}

}  // namespace floesim::fracture
