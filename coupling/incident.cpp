#include "coupling/incident.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "fluid/waves.hpp"

namespace floesim {

IncidentSea::IncidentSea(std::unique_ptr<fluid::Sea> sea, double tau) : sea_(std::move(sea)), tau_(tau) {
  t0_ = t1_ = sea_->time();
  take(u1_, v1_);
  u0_ = u1_;
  v0_ = v1_;
}

double IncidentSea::interval_for(const SeaParams& params) {
  const WaveParams& w = params.waves;
  double period = 0.0;
  switch (w.kind) {
    case WaveKind::none: return 0.0;
    case WaveKind::jonswap: period = w.tp; break;
    case WaveKind::regular:
    case WaveKind::standing:
      period = w.period;
      if (!(period > 0.0) && w.wavelength > 0.0) {
        const fluid::Dispersion d = fluid::Dispersion::of(params);
        period = 2.0 * std::numbers::pi / d.omega(2.0 * std::numbers::pi / w.wavelength);
      }
      break;
  }
  return period > 0.0 ? period / 40.0 : 0.0;
}

void IncidentSea::take(std::vector<double>& u, std::vector<double>& v) {
  const std::span<const double> fu = sea_->field(fluid::Field::velocity_x);
  u.assign(fu.begin(), fu.end());
  const std::span<const double> fv = sea_->field(fluid::Field::velocity_y);
  v.assign(fv.begin(), fv.end());
}

void IncidentSea::advance_to(double t) {
  if (!(tau_ > 0.0)) {
    if (t > t1_) sea_->flow(t - t1_);
    t0_ = t1_ = std::max(t, t1_);
    take(u1_, v1_);
    return;
  }
  if (t1_ == t0_) {  // the first call: open the first interval
    sea_->flow(tau_);
    t1_ = t0_ + tau_;
    take(u1_, v1_);
  }
  while (t > t1_) {
    std::swap(u0_, u1_);
    std::swap(v0_, v1_);
    t0_ = t1_;
    sea_->flow(tau_);
    t1_ = t0_ + tau_;
    take(u1_, v1_);
  }
}

double IncidentSea::weight(double t) const {
  return t1_ > t0_ ? std::clamp((t - t0_) / (t1_ - t0_), 0.0, 1.0) : 1.0;
}

}  // namespace floesim
