#include "fluid/waves.hpp"

#include <fftw3.h>

#include <cmath>
#include <complex>
#include <numbers>
#include <random>
#include <sstream>
#include <vector>

#include "core/error.hpp"

namespace floesim::fluid {

namespace {

constexpr double pi = std::numbers::pi;
using cplx = std::complex<double>;

std::string fmt(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

// At least this many cells per wavelength along each axis.
constexpr double cells_per_wavelength = 4.0;

// `requested` is the wavelength asked for (before rounding to the grid), for the message.
void check_resolved(double kx, double ky, const SurfaceGrid& grid, const char* key,
                    double requested) {
  const double lambda = 2.0 * pi / std::hypot(kx, ky);
  const double hx = grid.dx(), hy = grid.dims == 2 ? grid.dy() : 0.0;
  if (std::abs(kx) * hx * cells_per_wavelength > 2.0 * pi * (1.0 + 1e-12) ||
      std::abs(ky) * hy * cells_per_wavelength > 2.0 * pi * (1.0 + 1e-12)) {
    std::string what = fmt(requested) + " m";
    if (std::abs(lambda / requested - 1.0) > 1e-9) what += " (" + fmt(lambda) + " m on the grid)";
    throw InputError(std::string("[sea.waves] ") + key + ": wavelength " + what +
                     " is not resolved by the grid spacing " + fmt(std::max(hx, hy)) +
                     " m (need at least 4 cells per wavelength; raise [sea] cells)");
  }
}

}  // namespace

double Dispersion::omega(double k) const {
  return std::sqrt((g * k + sigma * k * k * k / rho) * std::tanh(k * depth));
}

double Dispersion::group_velocity(double k) const {
  const double f = g * k + sigma * k * k * k / rho;
  const double df = g + 3.0 * sigma * k * k / rho;
  const double t = std::tanh(k * depth);
  double dt = 0.0;
  if (std::isfinite(depth)) {
    const double c = std::cosh(k * depth);
    dt = depth / (c * c);
  }
  return (df * t + f * dt) / (2.0 * omega(k));
}

double Dispersion::wavenumber(double w) const {
  double lo = 0.0, hi = 1.0;
  while (omega(hi) < w) hi *= 2.0;
  for (int it = 0; it < 200 && hi - lo > 1e-15 * hi; ++it) {
    const double mid = 0.5 * (lo + hi);
    (omega(mid) < w ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

double Dispersion::mass_density(double k) const { return rho / (k * std::tanh(k * depth)); }

double PlaneWave::wavelength() const { return 2.0 * pi / std::hypot(kx, ky); }

double PlaneWave::elevation(double x, double y, double t) const {
  if (standing) return amplitude * std::cos(kx * x + ky * y + phase) * std::cos(omega * t);
  return amplitude * std::cos(kx * x + ky * y - omega * t + phase);
}

double PlaneWave::rate(double x, double y, double t) const {
  if (standing)
    return -amplitude * omega * std::cos(kx * x + ky * y + phase) * std::sin(omega * t);
  return amplitude * omega * std::sin(kx * x + ky * y - omega * t + phase);
}

PlaneWave plane_wave(const SeaParams& params, const SurfaceGrid& grid) {
  const WaveParams& w = params.waves;
  const Dispersion disp = Dispersion::of(params);
  if (!(w.amplitude >= 0.0) || !std::isfinite(w.amplitude))
    throw InputError("[sea.waves] amplitude: expected a finite value >= 0 m, got " +
                     fmt(w.amplitude));
  if (w.wavelength < 0.0 || w.period < 0.0)
    throw InputError("[sea.waves] wavelength: wavelength and period must be > 0 (0 = unset)");
  double k = 0.0;
  if (w.wavelength > 0.0) {
    k = 2.0 * pi / w.wavelength;
    if (w.period > 0.0) {
      const double t = 2.0 * pi / disp.omega(k);
      if (std::abs(t - w.period) > 1e-3 * w.period)
        throw InputError("[sea.waves] period: " + fmt(w.period) + " s disagrees with wavelength " +
                         fmt(w.wavelength) + " m (period " + fmt(t) +
                         " s by the dispersion relation); give one of them");
    }
  } else if (w.period > 0.0) {
    k = disp.wavenumber(2.0 * pi / w.period);
  } else {
    throw InputError("[sea.waves] wavelength: give a wavelength (m) or a period (s)");
  }

  const double theta = w.direction * pi / 180.0;
  double kx = k * std::cos(theta), ky = k * std::sin(theta);
  if (grid.dims == 1) {
    if (std::abs(std::sin(theta)) > 1e-9)
      throw InputError("[sea.waves] direction: dims = 1 carries waves along x only (0 or 180 "
                       "degrees), got " + fmt(w.direction));
    ky = 0.0;
  }
  PlaneWave pw;
  pw.amplitude = w.amplitude;
  pw.standing = w.kind == WaveKind::standing;
  if (grid.edge == GridEdge::periodic) {
    // Round to the nearest wave vector of the periodic box.
    const double dkx = 2.0 * pi / grid.lx, dky = 2.0 * pi / grid.ly;
    kx = std::round(kx / dkx) * dkx;
    ky = grid.dims == 2 ? std::round(ky / dky) * dky : 0.0;
    if (kx == 0.0 && ky == 0.0)
      throw InputError("[sea.waves] wavelength: " + fmt(2.0 * pi / k) +
                       " m does not fit in the periodic box (size " + fmt(grid.lx) + " m)");
  } else if (pw.standing) {
    // Sloshing mode of a basin with walls at 0 and lx: cos(n pi x / lx).
    const double n = std::max(1.0, std::round(k * grid.lx / pi));
    kx = n * pi / grid.lx;
    ky = 0.0;
  }
  check_resolved(kx, ky, grid, w.wavelength > 0.0 ? "wavelength" : "period", 2.0 * pi / k);
  pw.kx = kx;
  pw.ky = ky;
  pw.omega = disp.omega(std::hypot(kx, ky));
  return pw;
}

double jonswap(double omega, double omega_peak, double gamma, double g) {
  if (omega <= 0.0) return 0.0;
  const double s = omega <= omega_peak ? 0.07 : 0.09;
  const double r = std::exp(-(omega - omega_peak) * (omega - omega_peak) /
                            (2.0 * s * s * omega_peak * omega_peak));
  const double x = omega_peak / omega;
  return g * g * std::pow(omega, -5.0) * std::exp(-1.25 * x * x * x * x) * std::pow(gamma, r);
}

namespace {

// JONSWAP sea with cos^2s((theta - theta0) / 2) spreading, synthesised on the
// grid taken as periodic: each pair of Fourier modes (k, -k) carries a wave
// along k and one along -k, each of amplitude sqrt(E) with E the spectral
// density at that wave vector, and an independent uniform random phase.
void jonswap_surface(const SeaParams& params, const SurfaceGrid& grid, unsigned long seed,
                     std::span<double> eta, std::span<double> eta_t) {
  const WaveParams& w = params.waves;
  const Dispersion disp = Dispersion::of(params);
  if (!(w.hs > 0.0) || !std::isfinite(w.hs))
    throw InputError("[sea.waves] hs: expected a significant wave height > 0 m, got " +
                     fmt(w.hs));
  if (!(w.tp > 0.0) || !std::isfinite(w.tp))
    throw InputError("[sea.waves] tp: expected a peak period > 0 s, got " + fmt(w.tp));
  if (!(w.gamma >= 1.0))
    throw InputError("[sea.waves] gamma: expected a peak enhancement >= 1, got " +
                     fmt(w.gamma));
  if (!(w.spreading >= 0.0))
    throw InputError("[sea.waves] spreading: expected an exponent >= 0, got " +
                     fmt(w.spreading));
  const double wp = 2.0 * pi / w.tp;
  const double kp = disp.wavenumber(wp);
  const double theta0 = w.direction * pi / 180.0;
  if (grid.dims == 1 && std::abs(std::sin(theta0)) > 1e-9)
    throw InputError("[sea.waves] direction: dims = 1 carries waves along x only (0 or 180 "
                     "degrees), got " + fmt(w.direction));
  check_resolved(kp, 0.0, grid, "tp", 2.0 * pi / kp);
  if (2.0 * pi / kp > std::max(grid.lx, grid.dims == 2 ? grid.ly : 0.0))
    throw InputError("[sea.waves] tp: the peak wavelength " + fmt(2.0 * pi / kp) +
                     " m is longer than the box (" + fmt(grid.lx) + " m)");

  auto density = [&](double kx, double ky) {
    const double k = std::hypot(kx, ky);
    const double om = disp.omega(k);
    const double sk = jonswap(om, wp, w.gamma, params.g) * disp.group_velocity(k);
    const double theta = std::atan2(ky, kx);
    const double d = std::remainder(theta - theta0, 2.0 * pi);
    if (grid.dims == 1) return std::abs(d) < 1e-9 ? sk : 0.0;
    if (w.spreading == 0.0) return std::abs(d) < 1e-9 ? sk / k : 0.0;
    return sk / k * std::pow(std::cos(0.5 * d), 2.0 * w.spreading);
  };

  const int nx = grid.nx, ny = grid.dims == 2 ? grid.ny : 1;
  const int hx = nx / 2 + 1;
  const std::size_t nc = static_cast<std::size_t>(ny) * hx;
  std::vector<cplx> c(nc, 0.0), ct(nc, 0.0);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> phase(0.0, 2.0 * pi);
  for (int iy = 0; iy < ny; ++iy) {
    for (int ix = 0; ix < hx; ++ix) {
      const double u1 = phase(rng), u2 = phase(rng);  // drawn for every slot: stable streams
      if (2 * ix == nx || (ny > 1 && 2 * iy == ny)) continue;  // Nyquist: left empty
      if (ix == 0 && (iy == 0 || iy > ny / 2)) continue;       // mean; partner of a pair
      const int my = iy <= ny / 2 ? iy : iy - ny;
      const double kx = 2.0 * pi * ix / grid.lx, ky = 2.0 * pi * my / grid.ly;
      const double om = disp.omega(std::hypot(kx, ky));
      const cplx ap = std::sqrt(density(kx, ky)) * std::polar(1.0, u1);    // along k
      const cplx am = std::sqrt(density(-kx, -ky)) * std::polar(1.0, u2);  // along -k
      // Re(C e^{i k.x}) with C = A+ e^{-i w t} + conj(A-) e^{i w t}; c2r sums
      // the stored coefficient and its conjugate: store C / 2.
      const cplx cc = ap + std::conj(am);
      const cplx cr = cplx(0.0, -om) * ap + cplx(0.0, om) * std::conj(am);
      const std::size_t at = static_cast<std::size_t>(iy) * hx + ix;
      c[at] = 0.5 * cc;
      ct[at] = 0.5 * cr;
      if (ix == 0) {
        const std::size_t partner = static_cast<std::size_t>(ny - iy) * hx;
        c[partner] = 0.5 * std::conj(cc);
        ct[partner] = 0.5 * std::conj(cr);
      }
    }
  }
  auto* cin = reinterpret_cast<fftw_complex*>(c.data());
  auto* ctin = reinterpret_cast<fftw_complex*>(ct.data());
  fftw_plan plan = ny > 1 ? fftw_plan_dft_c2r_2d(ny, nx, cin, eta.data(), FFTW_ESTIMATE)
                          : fftw_plan_dft_c2r_1d(nx, cin, eta.data(), FFTW_ESTIMATE);
  fftw_execute_dft_c2r(plan, cin, eta.data());
  fftw_execute_dft_c2r(plan, ctin, eta_t.data());
  fftw_destroy_plan(plan);

  double var = 0.0;
  for (double e : eta) var += e * e;
  var /= static_cast<double>(eta.size());
  if (!(var > 0.0))
    throw InputError("[sea.waves] spreading: the JONSWAP spectrum puts no energy on the grid's "
                     "wave vectors (with spreading = 0 in dims = 2 the direction must lie on a "
                     "grid line)");
  const double scale = 0.25 * w.hs / std::sqrt(var);
  for (double& e : eta) e *= scale;
  for (double& e : eta_t) e *= scale;
}

}  // namespace

void initial_surface(const SeaParams& params, const SurfaceGrid& grid, unsigned long seed,
                     std::span<double> eta, std::span<double> eta_t) {
  FLOESIM_ASSERT(eta.size() == grid.size() && eta_t.size() == grid.size());
  std::fill(eta.begin(), eta.end(), 0.0);
  std::fill(eta_t.begin(), eta_t.end(), 0.0);
  switch (params.waves.kind) {
    case WaveKind::none:
      return;
    case WaveKind::regular:
    case WaveKind::standing: {
      const PlaneWave pw = plane_wave(params, grid);
      const int ny = grid.dims == 2 ? grid.ny : 1;
      for (int j = 0; j < ny; ++j)
        for (int i = 0; i < grid.nx; ++i) {
          const std::size_t at = static_cast<std::size_t>(j) * grid.nx + i;
          eta[at] = pw.elevation(grid.x(i), grid.y(j), 0.0);
          eta_t[at] = pw.rate(grid.x(i), grid.y(j), 0.0);
        }
      return;
    }
    case WaveKind::jonswap:
      jonswap_surface(params, grid, seed, eta, eta_t);
      return;
  }
}

}  // namespace floesim::fluid
