#pragma once
// Relaxation zones for tank-like runs in a periodic box (dims = 1 or 2, zones
// along x) or a 3D BEM basin (the zones against its end walls): a generation zone [0, Lg] that relaxes the surface toward a target
// plane wave, and an absorbing zone [lx - La, lx] that relaxes it toward calm.
//
// Inside a zone, both eta and eta' relax toward their targets at the rate
// r w(x) (1/s), integrated exactly over a step:
//     f <- f_target + (f - f_target) exp(-r w(x) dt).
// w is the relaxation function of Jacobsen, Fuhrman & Fredsøe (2012),
//     w(chi) = (exp(chi^3.5) - 1) / (exp(1) - 1),
// with chi = 0 at the zone's inner edge (facing the working section) and 1 at
// its outer end, so the relaxation fades in smoothly. Where the two zones meet
// across the periodic seam both relax toward zero: the target wave is tapered
// (sin^2) to zero over the outer quarter of the generation zone. The target
// is ramped in time over ramp_periods (sin^2), so a run starts from calm water.

#include <span>
#include <vector>

#include "fluid/grid.hpp"
#include "fluid/waves.hpp"

namespace floesim::fluid {

struct TankParams {
  bool enabled = false;
  double generation_length = 0.0;  // m; 0 = 3 target wavelengths
  double absorption_length = 0.0;  // m; 0 = 2 target wavelengths
  double rate = 0.0;               // 1/s, r at w = 1; 0 = 4 omega of the target
  double ramp_periods = 3.0;       // target amplitude ramp, in wave periods
};

double relaxation_weight(double chi);

class TankZones {
public:
  // Lengths and rate are resolved from the defaults against the target wave;
  // throws InputError when the zones do not fit in the box.
  TankZones(const SurfaceGrid& grid, const TankParams& params, const PlaneWave& target);

  // Relaxes eta and eta_t (grid layout) over [t, t + dt].
  void relax(double t, double dt, std::span<double> eta, std::span<double> eta_t) const;

  const PlaneWave& target() const { return target_; }
  double generation_length() const { return lg_; }
  double absorption_length() const { return la_; }
  double rate() const { return rate_; }

private:
  double ramp(double t) const;

  SurfaceGrid grid_;
  PlaneWave target_;
  double lg_ = 0.0, la_ = 0.0, rate_ = 0.0, ramp_time_ = 0.0;
  std::vector<double> weight_;  // w(x) per column i (0 outside the zones)
  std::vector<double> taper_;   // target taper per column (0 in the absorbing zone)
};

}  // namespace floesim::fluid
