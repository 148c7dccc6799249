#include "coupling/penalty_law.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace floesim {

// The obstacle problem in units of the draft d, the time sqrt(d / g) and the
// mass per unit area rho_w d: the mass sits at height x above the obstacle,
// its spring pulls it toward x = 1/2 with unit frequency, and it is released
// from x = 3/2, so it reaches the obstacle with speed v0 = sqrt(3) / 2. While
// x < 0 (delta = -x > 0) the law adds p = s K delta + (1 - s) K delta':
//     x'' + c x' + w2 x = 1/2,   c = (1 - s) K,   w2 = 1 + s K,
// linear with constant coefficients, so the contact phase is solved in closed
// form. The mass leaves when x returns to 0; e = |x'| there / v0.
double obstacle_restitution(double s, double K) {
  const double v0 = std::sqrt(0.75);
  const double c = (1.0 - s) * K, w2 = 1.0 + s * K;
  const double xp = 0.5 / w2;
  const double beta = 0.5 * c;
  const double disc = beta * beta - w2;
  // x(t) and x'(t) of the contact phase, x(0) = 0, x'(0) = -v0.
  auto motion = [&](double t, double& x, double& v) {
    if (disc < -1e-12 * w2) {  // underdamped
      const double wd = std::sqrt(-disc);
      const double c1 = -xp, c2 = (-v0 + beta * c1) / wd;
      const double ex = std::exp(-beta * t), co = std::cos(wd * t), si = std::sin(wd * t);
      x = xp + ex * (c1 * co + c2 * si);
      v = ex * ((-beta * c1 + wd * c2) * co + (-beta * c2 - wd * c1) * si);
    } else if (disc > 1e-12 * w2) {  // overdamped: r_fast < r_slow < 0
      const double sq = std::sqrt(disc);
      const double r_fast = -beta - sq, r_slow = -w2 / (beta + sq);
      // A + B = -xp, r_slow A + r_fast B = -v0.
      const double b = (-v0 + r_slow * xp) / (r_fast - r_slow);
      const double a = -xp - b;
      x = xp + a * std::exp(r_slow * t) + b * std::exp(r_fast * t);
      v = a * r_slow * std::exp(r_slow * t) + b * r_fast * std::exp(r_fast * t);
    } else {  // critical
      const double c1 = -xp, c2 = -v0 + beta * c1;
      const double ex = std::exp(-beta * t);
      x = xp + (c1 + c2 * t) * ex;
      v = (c2 - beta * (c1 + c2 * t)) * ex;
    }
  };
  // First return to x = 0: scan on a geometric grid in t (the contact may
  // last from 1/K to K time units), then bisect.
  const double t_fast = 1.0 / (std::sqrt(w2) + c);
  double t_prev = 0.0;
  for (double t = 1e-3 * t_fast; t < 1e9; t *= 1.002) {
    double x, v;
    motion(t, x, v);
    if (x >= 0.0) {
      double lo = t_prev, hi = t;
      for (int k = 0; k < 200 && hi - lo > 1e-15 * hi; ++k) {
        const double mid = 0.5 * (lo + hi);
        motion(mid, x, v);
        (x >= 0.0 ? hi : lo) = mid;
      }
      motion(hi, x, v);
      return std::abs(v) / v0;
    }
    t_prev = t;
  }
  return 0.0;  // never leaves within 10^9 time units: absorbed
}

StepForce step_force(double c, double cd, double d0, double d1) {
  StepForce r;
  if (d0 > 0.0 && d1 > 0.0) {
    r = {0.5 * c * (d0 + d1), 0.5 * c};
  } else if (d0 > 0.0) {  // leaves the water within the step: d1 <= 0 < d0
    r.f = 0.5 * c * d0 * d0 / (d0 - d1);
    r.df = r.f / (d0 - d1);
  } else if (d1 > 0.0) {  // enters it: d0 <= 0 < d1
    const double e = d1 - d0;
    r = {0.5 * c * d1 * d1 / e, 0.5 * c * d1 * (d1 - 2.0 * d0) / (e * e)};
  }
  if (cd > 0.0) {
    r.f += cd * (std::max(d1, 0.0) - std::max(d0, 0.0));
    if (d1 > 0.0) r.df += cd;
  }
  return r;
}

double stepped_obstacle_restitution(double s, double K, double h) {
  const double v0 = std::sqrt(0.75);
  const double ks = s * K, c = (1.0 - s) * K;
  // The penalty's force held over the step from x0 to x1 (penetration
  // delta = -x) and its x1-derivative.
  auto penalty = [&](double x0, double x1, double& df) {
    const StepForce f = step_force(ks, c / h, -x0, -x1);
    df = -f.df;
    return f.f;
  };
  double x = 0.0, v = -v0;  // at the surface, going down
  bool touched = false;
  for (long n = 0; n < 10'000'000 && static_cast<double>(n) * h < 1e5; ++n) {
    // x1 - x - h v - h^2 / 2 F(x1) = 0, F = 1/2 - (x + x1) / 2 + penalty:
    // increasing in x1, solved by Newton from x + h v.
    const double x0 = x;
    double x1 = x + h * v, df = 0.0;
    for (int it = 0; it < 100; ++it) {
      const double F = 0.5 - 0.5 * (x0 + x1) + penalty(x0, x1, df);
      const double step = (x1 - x0 - h * v - 0.5 * h * h * F) / (1.0 - 0.5 * h * h * (df - 0.5));
      x1 -= step;
      if (std::abs(step) <= 1e-15 * (1.0 + std::abs(x1))) break;
    }
    v += h * (0.5 - 0.5 * (x0 + x1) + penalty(x0, x1, df));
    x = x1;
    if (x < 0.0) touched = true;
    if (touched && x >= 0.0) {
      // Out of contact: free oscillation about 1/2 with unit frequency.
      const double energy = 0.5 * v * v + 0.5 * (x - 0.5) * (x - 0.5);
      return std::sqrt(std::max(2.0 * energy - 0.25, 0.0)) / v0;
    }
  }
  return 0.0;  // still in contact after 10^5 time units: absorbed
}

BlendCalibration calibrate_blend(double K, int points, double step) {
  // Tabulated along the damping ratio zeta = (1 - s) sqrt(K / s) / 2, where e
  // varies (for large K all of it happens within 1 - s ~ 1 / sqrt(K)):
  // s = q^2 with q^2 + b q - 1 = 0, b = 2 zeta / sqrt(K); zeta from 0 (s = 1)
  // log-spaced over 10^-3 .. 10^3, then s = 0.
  BlendCalibration cal;
  cal.stiffness = K;
  cal.step = step;
  std::vector<double> zetas{0.0};
  for (int k = 0; k < points - 2; ++k) zetas.push_back(std::pow(10.0, -3.0 + 6.0 * k / (points - 3)));
  for (double zeta : zetas) {
    const double b = 2.0 * zeta / std::sqrt(K);
    const double q = 2.0 / (b + std::sqrt(b * b + 4.0));  // the root of q^2 + b q - 1, cancellation-free
    cal.share.push_back(q * q);
  }
  cal.share.push_back(0.0);
  std::reverse(cal.share.begin(), cal.share.end());  // increasing s
  for (double s : cal.share)
    cal.restitution.push_back(step > 0.0 ? stepped_obstacle_restitution(s, K, step) : obstacle_restitution(s, K));
  // Stepped at a coarse step, e(s) is steep where the contact shortens to a
  // step: refine the table (s halved between neighbours) where e jumps by
  // more than 0.01, so that interpolation meets a requested e within 0.02.
  if (step > 0.0) {
    for (std::size_t k = 0; k + 1 < cal.share.size() && cal.share.size() < 4000;) {
      const double ds = cal.share[k + 1] - cal.share[k];
      if (std::abs(cal.restitution[k + 1] - cal.restitution[k]) > 0.01 && ds > 1e-9 * cal.share[k + 1]) {
        const double s = cal.share[k] + 0.5 * ds;
        cal.share.insert(cal.share.begin() + static_cast<std::ptrdiff_t>(k + 1), s);
        cal.restitution.insert(cal.restitution.begin() + static_cast<std::ptrdiff_t>(k + 1),
                               stepped_obstacle_restitution(s, K, step));
      } else {
        ++k;
      }
    }
  }
  // Stepped, e(s) is monotone only from s = 1 down to where it first
  // reaches its lowest: below that the contact lasts less than a step and e
  // is the step's artefact. The table keeps that branch.
  if (step > 0.0) {
    std::size_t first = cal.restitution.size() - 1;
    while (first > 0 && cal.restitution[first - 1] <= cal.restitution[first] + 1e-12) --first;
    cal.share.erase(cal.share.begin(), cal.share.begin() + static_cast<std::ptrdiff_t>(first));
    cal.restitution.erase(cal.restitution.begin(), cal.restitution.begin() + static_cast<std::ptrdiff_t>(first));
  }
  // Round-off may leave the table flat at its ends; keep it non-decreasing.
  for (std::size_t k = 1; k < cal.restitution.size(); ++k)
    cal.restitution[k] = std::max(cal.restitution[k], cal.restitution[k - 1]);
  return cal;
}

double BlendCalibration::share_for(double e) const {
  const auto& x = restitution;
  const auto& y = share;
  if (x.empty()) throw std::logic_error("BlendCalibration::share_for on an empty table");
  if (e <= x.front()) return y.front();
  if (e >= x.back()) return y.back();
  std::size_t k = static_cast<std::size_t>(std::upper_bound(x.begin(), x.end(), e) - x.begin()) - 1;
  while (k + 1 < x.size() && x[k + 1] == x[k]) ++k;
  // Monotone cubic (Fritsch–Carlson) through the table points.
  auto slope = [&](std::size_t i) {
    const std::size_t n = x.size();
    auto secant = [&](std::size_t a) { return (y[a + 1] - y[a]) / (x[a + 1] - x[a]); };
    if (i == 0) return secant(0);
    if (i == n - 1) return secant(n - 2);
    const double l = secant(i - 1), r = secant(i);
    if (l * r <= 0.0 || !std::isfinite(l) || !std::isfinite(r)) return 0.0;
    return 2.0 / (1.0 / l + 1.0 / r);  // harmonic mean keeps monotonicity
  };
  const double h = x[k + 1] - x[k];
  const double t = (e - x[k]) / h;
  const double h00 = (1 + 2 * t) * (1 - t) * (1 - t), h10 = t * (1 - t) * (1 - t);
  const double h01 = t * t * (3 - 2 * t), h11 = t * t * (t - 1);
  return h00 * y[k] + h10 * h * slope(k) + h01 * y[k + 1] + h11 * h * slope(k + 1);
}

}  // namespace floesim
