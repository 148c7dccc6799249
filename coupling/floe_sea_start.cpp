// The floe–sea contact's static start (FloeSeaContact::start): each floe
// placed at rest on the sea (its heave and, where allowed, pitch and roll
// found so that the contact's pressure carries its weight), and the sea's
// pressure held at that equilibrium (hold_static_pressure). Split from
// floe_sea.cpp, which holds the per-step contact.
#include "coupling/floe_sea.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include <Eigen/Dense>

#include "core/error.hpp"
#include "fluid/sea.hpp"

namespace floesim {

namespace {

// Solves A x = b for (heave, pitch, roll) with only the slopes that `tilt`
// allows (0: none, 1: pitch, 2: both); the others are 0.
Eigen::Vector3d solve_tilted(const Eigen::Matrix3d& A, const Eigen::Vector3d& b, std::uint8_t tilt) {
  if (tilt == 2) return A.ldlt().solve(b);
  if (tilt == 1) {
    const Eigen::Vector2d x = A.topLeftCorner<2, 2>().ldlt().solve(b.head<2>());
    return {x[0], x[1], 0.0};
  }
  return {b[0] / A(0, 0), 0.0, 0.0};
}

}  // namespace

void FloeSeaContact::hold_static_pressure(fluid::Sea& sea, std::span<const double> waves,
                                          std::span<const double> eta) {
  // A sea with a static part (a truncated BEM sea with its static correction,
  // fluid/sea.hpp) keeps only its kept modes at set_surface; the rest of the
  // floes' dimples is its static answer to their pressure, which it must
  // hold from the start. The start's local response eta = W + L - p / (rho g)
  // gives that pressure, up to a constant (which does nothing).
  if (!sea.has_static_part()) return;
  std::vector<double> p(eta.size());
  for (std::size_t c = 0; c < eta.size(); ++c) p[c] = rho_ * g_ * (waves[c] - eta[c]);
  sea.hold_pressure(p);
}

void FloeSeaContact::start(Floes& floes, fluid::Sea& sea, bool given) {
  const fluid::SurfaceGrid& grid = sea.grid();
  const std::size_t n = floes.size();
  pressure_.assign(grid.size(), 0.0);  // evaluate() clears only the footprints' cells
  cells_.assign(grid.size(), {});
  pressure_kicked_ = false;
  pose_at_states(floes);
  footprints_.rebuild_at(floes, constants_.dynamic, evaluated_.poses, threads_);
  if (given) {
    free_level_ = 0.0;
    for (std::size_t i = 0; i < n; ++i) constants_.bottom0[i] = -floes.draft(i, rho_) * (1.0 + 1.0 / K_);
    return;
  }
  // The static problem (see the header): on the calm sea first, which fixes
  // each floe's reference bottom (heave 0), then on the sea's waves. It
  // couples every floe sharing a cell, in one Gauss–Seidel sweep over the
  // floes in floe order whose cell sums are updated floe by floe: it reads
  // every floe's pieces, on every rank. By owner a rank holds its own
  // floes' only: every floe's are gathered for this once, into a copy freed
  // at the end of the start (the contact by owner never reads another
  // floe's pieces after it: docs/parallel.md, "The footprints' area pieces
  // by holder (foot28)").
  Footprints gathered;
  const Footprints& fp = footprints_.every_floe(gathered);
  std::vector<double> F(grid.size(), 0.0), S(grid.size(), 0.0), eta(grid.size());
  std::vector<double> z(n, 0.0);
  std::vector<Vec2> a(n, Vec2::Zero());
  auto zb = [&](std::size_t i, std::size_t k) { return z[i] + a[i].dot(fp.centroid[k]); };
  // psi of each piece (the sub-cell weight of its cell's coverage) and its
  // weight phi psi in the cell's balance.
  std::vector<double> coverage(grid.size(), 0.0), psi(fp.cell.size());
  for (std::size_t k = 0; k < fp.cell.size(); ++k) coverage[fp.cell[k]] += fp.area[k] / cell_area_;
  for (std::size_t k = 0; k < fp.cell.size(); ++k) psi[k] = subcell_weight(coverage[fp.cell[k]]);
  auto weight = [&](std::size_t k) { return fp.area[k] / cell_area_ * psi[k]; };
  for (std::size_t i = 0; i < n; ++i) {
    if (!constants_.dynamic[i]) continue;
    z[i] = -floes.draft(i, rho_) * (1.0 + 1.0 / K_);
    for (std::size_t k = fp.offsets[i]; k < fp.offsets[i + 1]; ++k) F[fp.cell[k]] += weight(k);
  }
  // Gauss–Seidel over the floes from the present z, a, with the free level W
  // (+ L); fills eta (zero mean) and returns the L that makes it so.
  auto solve = [&](std::span<const double> W) {
    std::fill(S.begin(), S.end(), 0.0);
    for (std::size_t i = 0; i < n; ++i)
      if (constants_.dynamic[i])
        for (std::size_t k = fp.offsets[i]; k < fp.offsets[i + 1]; ++k) S[fp.cell[k]] += weight(k) * zb(i, k);
    double change = INFINITY;
    int sweeps = 0;
    for (; sweeps < 200 && change > 1e-13; ++sweeps) {
      change = 0.0;
      for (std::size_t i = 0; i < n; ++i) {
        if (!constants_.dynamic[i] || fp.offsets[i] == fp.offsets[i + 1]) continue;
        Eigen::Matrix3d A = Eigen::Matrix3d::Zero();
        Eigen::Vector3d b(-floes.mass[i] * g_ / kappa_, 0.0, 0.0);
        for (std::size_t k = fp.offsets[i]; k < fp.offsets[i + 1]; ++k) {
          const std::uint32_t c = fp.cell[k];
          const double f = psi[k], w = weight(k);
          const double Fo = F[c] - w, So = S[c] - w * zb(i, k);
          const double alpha = (W[c] + K_ * So) / (1.0 + K_ * F[c]), beta = (1.0 + K_ * Fo) / (1.0 + K_ * F[c]);
          const Eigen::Vector3d phi(1.0, fp.centroid[k].x(), fp.centroid[k].y());
          A += f * fp.area[k] * beta * phi * phi.transpose();
          b += f * fp.area[k] * alpha * phi;
        }
        // Slopes the discrete footprint cannot resist stay 0 (a floe within a
        // few cells; roll in a long-crested sea).
        const Eigen::Vector3d x = solve_tilted(A, b, constants_.tilt[i]);
        for (std::size_t k = fp.offsets[i]; k < fp.offsets[i + 1]; ++k) S[fp.cell[k]] -= weight(k) * zb(i, k);
        change = std::max(change, std::abs(x[0] - z[i]) / floes.draft(i, rho_));
        z[i] = x[0];
        a[i] = {x[1], x[2]};
        for (std::size_t k = fp.offsets[i]; k < fp.offsets[i + 1]; ++k) S[fp.cell[k]] += weight(k) * zb(i, k);
      }
    }
    if (change > 1e-9) {
      std::ostringstream m;
      m << "the floes' static equilibrium on the sea did not converge in " << sweeps
        << " sweeps (last relative change " << change << ")";
      throw RunError(m.str());
    }
    double mean = 0.0;
    for (std::size_t c = 0; c < grid.size(); ++c) {
      eta[c] = (W[c] + K_ * S[c]) / (1.0 + K_ * F[c]);
      mean += eta[c];
    }
    mean /= static_cast<double>(grid.size());
    for (double& e : eta) e -= mean;
    return mean;
  };
  const double calm_level = solve(std::vector<double>(grid.size(), 0.0));
  free_level_ = -calm_level;  // the free water's level once eta has zero mean
  for (std::size_t i = 0; i < n; ++i)
    if (constants_.dynamic[i]) constants_.bottom0[i] = z[i] - calm_level;
  // The waves in the sea: the floes start from the least-squares plane of the
  // waves under them (and take the plane of the waves' rates as theirs),
  // then settle on the waves.
  // Whole fields (every floe's pieces are read; in slabs gathered for this
  // call, their storage given back when the fields are next computed with a
  // halo). Copied: set_surface below changes the state they were of.
  const std::span<const double> wave = sea.field(fluid::Field::elevation).all();
  const std::vector<double> wave_eta(wave.begin(), wave.end());
  sea.release_field(fluid::Field::elevation);
  const std::span<const double> wave_w = sea.field(fluid::Field::velocity_z).all();
  const std::vector<double> eta_t(wave_w.begin(), wave_w.end());
  sea.release_field(fluid::Field::velocity_z);
  for (std::size_t i = 0; i < n; ++i) {
    if (!constants_.dynamic[i]) continue;
    FloeState& st = floes.state[i];
    Eigen::Matrix3d A = Eigen::Matrix3d::Zero();
    Eigen::Vector3d be = Eigen::Vector3d::Zero(), bw = Eigen::Vector3d::Zero();
    for (std::size_t k = fp.offsets[i]; k < fp.offsets[i + 1]; ++k) {
      const Eigen::Vector3d phi(1.0, fp.centroid[k].x(), fp.centroid[k].y());
      A += fp.area[k] * phi * phi.transpose();
      be += fp.area[k] * wave_eta[fp.cell[k]] * phi;
      bw += fp.area[k] * eta_t[fp.cell[k]] * phi;
    }
    if (!(A(0, 0) > 0.0)) continue;
    const Eigen::Vector3d xe = solve_tilted(A, be, constants_.tilt[i]), xw = solve_tilted(A, bw, constants_.tilt[i]);
    z[i] += xe[0];
    a[i] += Vec2{xe[1], xe[2]};
    st.heave_rate = xw[0];
    st.pitch_rate = xw[1];
    st.roll_rate = xw[2];
  }
  const double wave_level = solve(wave_eta);
  sea.set_surface(eta, eta_t);
  hold_static_pressure(sea, wave_eta, eta);
  for (std::size_t i = 0; i < n; ++i) {
    if (!constants_.dynamic[i]) continue;
    FloeState& st = floes.state[i];
    st.heave = z[i] - wave_level - constants_.bottom0[i];
    st.pitch = a[i].x();
    st.roll = a[i].y();
  }
  const double capillary =
      sigma_ * (std::pow(M_PI / grid.dx(), 2) + (grid.dims == 2 ? std::pow(M_PI / grid.dy(), 2) : 0.0)) / (rho_ * g_);
  if (capillary > 1e-3) {
    std::ostringstream m;
    m << "the static start neglects capillarity, whose relative size on this grid is up to " << capillary;
    notes_.push_back(m.str());
  }
}

}  // namespace floesim
