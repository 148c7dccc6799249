#pragma once
// Linear waves on the sea surface: the capillary-gravity dispersion relation,
// plane (regular and standing) waves, JONSWAP irregular seas, and the initial
// surface of a [sea.waves] section.

#include <span>

#include "core/params.hpp"
#include "fluid/grid.hpp"

namespace floesim::fluid {

// omega(k)^2 = (g k + sigma k^3 / rho) tanh(k H); H = inf is deep water.
struct Dispersion {
  double g = 9.81, sigma = 0.073, rho = 1025.0, depth = 0.0;

  static Dispersion of(const SeaParams& p) { return {p.g, p.sigma, p.rho, p.depth}; }
  double omega(double k) const;
  double group_velocity(double k) const;  // d omega / dk
  // The k > 0 with omega(k) = w (omega is increasing in k); Newton on a bracket.
  double wavenumber(double w) const;
  // Added-mass density of mode k per unit area: rho coth(k H) / k, so that
  // m_sf = mass_density * |eta_k|^2 and omega^2 = (rho g + sigma k^2) / mass_density.
  double mass_density(double k) const;
};

// eta(x, y, t) = amplitude cos(kx x + ky y - omega t + phase)   (progressive), or
// eta(x, y, t) = amplitude cos(kx x + ky y + phase) cos(omega t) (standing).
struct PlaneWave {
  double amplitude = 0.0;
  double kx = 0.0, ky = 0.0;  // rad/m
  double omega = 0.0;         // rad/s
  double phase = 0.0;
  bool standing = false;

  double wavelength() const;
  double elevation(double x, double y, double t) const;
  double rate(double x, double y, double t) const;  // d eta / dt
};

// The plane wave of a regular or standing [sea.waves] section on this grid.
// In a periodic box the wave vector is rounded to the nearest one the box
// carries (2 pi (m / lx, n / ly)); in a walled basin a standing wave is rounded
// to the nearest sloshing mode k = n pi / lx. Throws InputError when the grid
// cannot resolve it (fewer than 4 cells per wavelength) or the box cannot hold it.
PlaneWave plane_wave(const SeaParams& params, const SurfaceGrid& grid);

// Fills eta and eta_t (m, m/s; grid layout) with the initial surface of
// params.waves at t = 0. JONSWAP seas are drawn with random phases from `seed`
// and scaled so that 4 sqrt(variance of eta) = hs exactly.
void initial_surface(const SeaParams& params, const SurfaceGrid& grid, unsigned long seed,
                     std::span<double> eta, std::span<double> eta_t);

// JONSWAP frequency spectrum S(omega) (m^2 s), with alpha = 1: the caller
// normalises. sigma_J = 0.07 below the peak, 0.09 above.
double jonswap(double omega, double omega_peak, double gamma, double g);

}  // namespace floesim::fluid
