#pragma once
// The seas whose modes come from dense surface operators: the BEM slice
// (fluid/bem.hpp) and the 3D BEM basin (fluid/bem3d.hpp). Each builds, once
// per basin, its surface's stiffness a_sf, added mass m_sf and Neumann-to-
// Dirichlet map Phi; what follows is common and lives here:
//  - the reduction to modes (reduce_to_modes): a_sf x = omega^2 m_sf x on
//    zero-mean surfaces, all modes or the lowest few, and the dense maps
//    between modes and surface nodes (fluid/dense_modes.hpp);
//  - the process-wide cache of set-ups (cached_setup);
//  - the Sea's modal side (DenseModalSea): kick and repeat kick, set_surface,
//    projection and synthesis, the surface elevation and potential from
//    which each backend differentiates its fields;
//  - with the lowest modes only and `[sea] bem_static_correction`, the
//    dropped modes' static response to the pressure held over a step
//    (fluid/static_correction.hpp): the sea's static part below.
// The BEM seas' headers include it; other layers use them through Sea.

#include <Eigen/Dense>
#include <Eigen/SparseCore>

#include <map>
#include <memory>
#include <mutex>
#include <span>
#include <vector>
#include <string>

#include "fluid/dense_modes.hpp"
#include "fluid/sea.hpp"
#include "fluid/static_correction.hpp"

namespace floesim::fluid {

// One basin's set-up: its modes and maps, its panels and what it cost.
struct DenseSetup : DenseModes {
  int panels = 0;  // boundary panels in all
  // Wall time of the set-up and its parts (the parts the backend measures).
  struct Cost {
    double seconds = 0.0;   // in all
    double assemble = 0.0;  // the panel integrals
    double solve = 0.0;     // LU of the collocation system, Phi
    double modes = 0.0;     // the eigenproblem (dense or Lanczos) and the modal maps
    double correction = 0.0;  // lowest modes: the factorisation of a_sf for the static correction
    double bytes = 0.0;     // the dense matrices alive at the peak (the LU's)
  } cost;
  // Lowest modes only: the dropped modes' static response (null with all modes).
  std::shared_ptr<const StaticCorrection> correction;
};

// Fills out's modes from the surface operators (all symmetric, on the
// surface nodes): a_sf (positive definite on zero-mean surfaces), m_sf
// (symmetrised added mass), Phi (the Neumann-to-Dirichlet map, for the
// surface potential) and the nodes' areas `weight` (a pressure p_i does the
// work weight p_i eta_i). count = 0: all the modes, by the dense generalised
// eigenproblem (zero-mean surfaces by one Householder reflection that maps
// the constants onto the first axis); count = n > 0: the n lowest, by Lanczos
// (fluid/lowest_modes.hpp). Then load = -weight x^T, project = x^T m_sf,
// potential = Phi x. With count > 0 the static correction of the dropped
// modes is set up too (a sparse factorisation of a_sf; whether a sea uses it
// is its own choice, `[sea] bem_static_correction`).
void reduce_to_modes(const Eigen::SparseMatrix<double>& a_sf, const Eigen::MatrixXd& m_sf, const Eigen::MatrixXd& phi,
                     double weight, int count, DenseSetup& out);

class DenseModalSea : public Sea {
public:
  void kick(std::span<const double> pressure, double h) override;
  void repeat_kick(double h) override;
  void set_surface(std::span<const double> eta, std::span<const double> eta_t) override;

  std::span<const double> frequencies() const { return setup_->omega; }  // omega of each mode, ascending, rad/s
  int panels() const { return setup_->panels; }                          // boundary panels in all
  // What the set-up that built it cost (whether this sea built it or reused it).
  const DenseSetup::Cost& setup_cost() const { return setup_->cost; }
  double setup_seconds() const { return setup_->cost.seconds; }
  bool from_cache() const { return hit_; }  // the set-up was reused
  // The dropped modes' static response is part of the surface
  // (`[sea] bem_static_correction` with the lowest modes).
  bool has_static_part() const override { return correct_; }

  struct Cached {
    std::shared_ptr<const DenseSetup> setup;
    bool hit = false;  // reused from the cache
  };

protected:
  // The modal bank gets one real mode per column of setup.x (mass 1, gain 1).
  // correct: use the set-up's static correction (it must have one).
  DenseModalSea(const SurfaceGrid& grid, Cached setup, bool correct = false);

  void project(std::span<const double> pressure, std::span<double> s) override;
  void synthesize(std::span<const double> q, std::span<double> eta) override;
  // The static part (fluid/static_correction.hpp): eta_r = R F of the
  // pressure held, F = -A p; energy 1/2 F^T R F. Without the correction
  // these are the Sea's no-ops.
  void hold(std::span<const double> pressure, std::span<const double> s) override;
  void add_static_response(std::span<const double> pressure, std::span<const double> s,
                           std::span<double> eta) override;
  double static_potential() const override { return held_ ? held_potential_ : 0.0; }
  std::span<const double> held_pressure() const override {
    return held_ ? std::span<const double>(held_pressure_) : std::span<const double>();
  }
  // The surface elevation x q (plus the static part when one is held), or
  // the surface potential Phi x v (of the rates), in a surface-sized buffer
  // valid until the next call.
  const Eigen::VectorXd& surface_elevation();
  const Eigen::VectorXd& surface_potential();

private:
  std::shared_ptr<const DenseSetup> setup_;
  bool hit_ = false;
  bool kicked_ = false;  // work_modes_ holds the projection of the last kick's pressure
  Eigen::VectorXd work_modes_, work_surface_;
  // R F into out, F = -A p (scratch: the correction's).
  void static_response(std::span<const double> pressure, std::span<const double> s, Eigen::VectorXd& out);
  bool correct_ = false;
  bool held_ = false;                  // a pressure is held: held_eta_ is its static part
  Eigen::VectorXd held_eta_;           // R F of the held pressure (m)
  std::vector<double> held_pressure_;  // the held pressure itself (Pa), for checkpoints
  double held_potential_ = 0.0;        // 1/2 F^T R F (J)
  Eigen::VectorXd load_, centred_, modal_, response_;  // scratch of the static part
};

// A process-wide cache of set-ups by key (everything that enters them): the
// set-up is built on a miss (under the lock: two seas of one basin build it
// once), and when `keep` are held the cache is emptied first (the seas alive
// keep theirs). The result says whether it was reused.
// Each Tag (the backend) has its own cache.
template <class Tag, class Build>
DenseModalSea::Cached cached_setup(const std::string& key, std::size_t keep, Build&& build) {
  using Setup = std::shared_ptr<const DenseSetup>;
  static std::mutex mutex;
  static std::map<std::string, Setup> cache;
  std::lock_guard lock(mutex);
  if (auto it = cache.find(key); it != cache.end()) return {it->second, true};
  Setup setup = build();
  if (cache.size() >= keep) cache.clear();
  cache.emplace(key, setup);
  return {setup, false};
}

}  // namespace floesim::fluid
