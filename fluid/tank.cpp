#include "fluid/tank.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>

#include "core/error.hpp"

namespace floesim::fluid {

double relaxation_weight(double chi) {
  chi = std::clamp(chi, 0.0, 1.0);
  return (std::exp(std::pow(chi, 3.5)) - 1.0) / (std::numbers::e - 1.0);
}

TankZones::TankZones(const SurfaceGrid& grid, const TankParams& params, const PlaneWave& target)
    : grid_(grid), target_(target) {
  const double lambda = target.wavelength();
  const double period = 2.0 * std::numbers::pi / target.omega;
  lg_ = params.generation_length > 0.0 ? params.generation_length : 3.0 * lambda;
  la_ = params.absorption_length > 0.0 ? params.absorption_length : 2.0 * lambda;
  rate_ = params.rate > 0.0 ? params.rate : 4.0 * target.omega;
  ramp_time_ = std::max(0.0, params.ramp_periods) * period;
  if (lg_ + la_ >= grid.lx) {
    std::ostringstream s;
    s << "[sea] size: the tank's generation (" << lg_ << " m) and absorbing (" << la_
      << " m) zones do not fit in the box of " << grid.lx << " m";
    throw InputError(s.str());
  }
  weight_.assign(grid.nx, 0.0);
  taper_.assign(grid.nx, 0.0);
  const double seam = 0.25 * lg_;
  for (int i = 0; i < grid.nx; ++i) {
    const double x = grid.x(i);
    if (x <= lg_) {
      weight_[i] = relaxation_weight((lg_ - x) / lg_);
      const double s = std::sin(0.5 * std::numbers::pi * std::min(1.0, x / seam));
      taper_[i] = s * s;
    } else if (x >= grid.lx - la_) {
      weight_[i] = relaxation_weight((x - (grid.lx - la_)) / la_);
    }
  }
}

double TankZones::ramp(double t) const {
  if (t >= ramp_time_) return 1.0;
  if (t <= 0.0) return 0.0;
  const double s = std::sin(0.5 * std::numbers::pi * t / ramp_time_);
  return s * s;
}

void TankZones::relax(double t, double dt, std::span<double> eta,
                      std::span<double> eta_t) const {
  // The target is frozen at the middle of the interval: the relaxation is
  // exact for a fixed target and second order for a moving one.
  const double tm = t + 0.5 * dt;
  const double amp = ramp(tm);
  const int ny = grid_.dims == 2 ? grid_.ny : 1;
  for (int i = 0; i < grid_.nx; ++i) {
    if (weight_[i] == 0.0) continue;
    const double f = std::exp(-rate_ * weight_[i] * dt);
    const double g = amp * taper_[i];
    for (int j = 0; j < ny; ++j) {
      const std::size_t at = static_cast<std::size_t>(j) * grid_.nx + i;
      const double x = grid_.x(i), y = grid_.y(j);
      const double e0 = g == 0.0 ? 0.0 : g * target_.elevation(x, y, tm);
      const double r0 = g == 0.0 ? 0.0 : g * target_.rate(x, y, tm);
      eta[at] = e0 + (eta[at] - e0) * f;
      eta_t[at] = r0 + (eta_t[at] - r0) * f;
    }
  }
}

}  // namespace floesim::fluid
