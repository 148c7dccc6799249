#pragma once
// Percussion analysis of one floe (MODEL.md §6): its mesh, elastic model and
// factorisations, built once and reused for every load case; a load case
// (static forces and impulses at points) gives the response and the
// initiation verdict of the configured criterion.
//
//   FloeFracture f(polygon, thickness, density, params);   // meshes, assembles
//   FloeFracture::Result r = f.analyse(loads);            // solves, judges
//
// Everything is in the polygon's frame (a floe's body frame in a run).

#include <span>
#include <vector>

#include "contact/fracture/criteria.hpp"
#include "core/params.hpp"

namespace floesim::fracture {

class FloeFracture {
public:
  FloeFracture(std::span<const Vec2> polygon, double thickness, double density, const FractureParams& params);
  FloeFracture(const FloeFracture&) = delete;  // the responder refers to the model
  FloeFracture& operator=(const FloeFracture&) = delete;

  const std::vector<Vec2>& polygon() const { return polygon_; }
  double mesh_seconds() const { return mesh_seconds_; }  // wall time meshing the polygon
  const ElasticModel& model() const { return model_; }
  Responder& responder() { return responder_; }
  const CriterionOptions& criterion() const { return criterion_; }

  struct Result {
    Response response;
    Initiation initiation;
  };
  Result analyse(std::span<const PointLoad> loads, const Observer& observe = {});
  // The same verdict (initiates or not, and where and how when it does) at
  // less cost: by the stress criterion the response stops as soon as it can
  // no longer reach the strength (Responder::respond's level), and the
  // stress, time and load factor reported for a case that does not initiate
  // are then those of the steps run (Response::cut_short). By griffith, analyse().
  Result decide(std::span<const PointLoad> loads);

private:
  // The response up to `level` (respond's), judged.
  Result judged(std::span<const PointLoad> loads, const Observer& observe, double level);

  std::vector<Vec2> polygon_;
  double mesh_seconds_ = 0.0;
  ElasticModel model_;
  Responder responder_;
  CriterionOptions criterion_;
};

// The options of the pieces from the [fracture] parameters.
MeshOptions mesh_options(const FractureParams& params);
// The load radius is [fracture] load_radius, or the floe's thickness when that is 0
// (a contact between floes spans about their thickness).
ResponseOptions response_options(const FractureParams& params, double thickness);
CriterionOptions criterion_options(const FractureParams& params);

}  // namespace floesim::fracture
