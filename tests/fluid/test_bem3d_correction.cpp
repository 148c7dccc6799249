// The static correction of a truncated 3D BEM sea (`[sea] bem_static_correction`,
// fluid/static_correction.hpp): the dropped modes answer the pressure held over
// a step quasi-statically, eta = X q + R F, R = K^-1 P - X Omega^-2 X^T. The
// reference is the full-mode dense sea (bem_modes = 0) and the static surface
// K^-1 P F itself, computed here from K = rho g A I + sigma L. Issue 19.
#include <doctest/doctest.h>

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

#include "fluid/bem3d.hpp"
#include "tests/fluid/sea_cases.hpp"

using namespace floesim;
using namespace floesim::fluid;

TEST_SUITE_BEGIN("fluid");

namespace {

constexpr double pi = std::numbers::pi;

// A sloping basin 1 m x 0.57 m, 16 x 9 cells (no two modes share a frequency).
SeaParams sloping(int modes, bool correct) {
  SeaParams p = cases::lab_tank_bem(16, 1.0, 0.2);
  p.dims = 2;
  p.size = {1.0, 0.57};
  p.cells = {16, 9};
  p.bottom = {{0.0, -0.15}, {0.4, -0.15}, {1.0, -0.05}};
  p.bem_modes = modes;
  p.bem_static_correction = correct;
  return p;
}

// The full static surface K^-1 P F of the nodal load F = -A p, K = rho g A I
// + sigma L (five-point finite volumes, d eta / dn = 0 at the walls), solved
// densely: the reference the correction must reach.
std::vector<double> full_static(const SeaParams& p, const SurfaceGrid& g, const std::vector<double>& pressure) {
  const int nx = g.nx, ny = g.ny, n = nx * ny;
  const double dx = g.dx(), dy = g.dy(), area = dx * dy;
  Eigen::MatrixXd k = Eigen::MatrixXd::Zero(n, n);
  auto face = [&](int a, int b, double s) {
    k(a, a) += s;
    k(b, b) += s;
    k(a, b) -= s;
    k(b, a) -= s;
  };
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      const int c = j * nx + i;
      k(c, c) += p.rho * p.g * area;
      if (i + 1 < nx) face(c, c + 1, p.sigma * dy / dx);
      if (j + 1 < ny) face(c, c + nx, p.sigma * dx / dy);
    }
  Eigen::VectorXd f(n);
  for (int c = 0; c < n; ++c) f(c) = -area * pressure[static_cast<std::size_t>(c)];
  f.array() -= f.mean();
  const Eigen::VectorXd eta = k.ldlt().solve(f);
  return {eta.data(), eta.data() + n};
}

// A floe-like pressure: a sharp patch of 500 Pa on 4 x 3 cells over a smooth 50 Pa swell.
std::vector<double> patch_pressure(const SurfaceGrid& g) {
  std::vector<double> p(g.size());
  for (int j = 0; j < g.ny; ++j)
    for (int i = 0; i < g.nx; ++i)
      p[static_cast<std::size_t>(j * g.nx + i)] =
          50.0 * std::cos(pi * g.x(i)) + (i >= 5 && i < 9 && j >= 3 && j < 6 ? 500.0 : 0.0);
  return p;
}

double largest_difference(std::span<const double> a, const std::vector<double>& b) {
  double d = 0.0;
  for (std::size_t i = 0; i < b.size(); ++i) d = std::max(d, std::abs(a[i] - b[i]));
  return d;
}

}  // namespace

TEST_CASE("3D BEM static correction: a pressure held still gives the full-mode static surface K^-1 P F to round-off") {
  // Each sea starts from the full static surface and holds the pressure over
  // midpoint steps. The dense sea (all 143 modes) stays there: it is its
  // static equilibrium. The 30 lowest modes alone hold X Omega^-2 X^T F, the
  // kept modes' share; with the correction R F they hold K^-1 P F whatever n.
  Bem3dSea dense(sloping(0, false)), low(sloping(30, false)), corrected(sloping(30, true));
  const SurfaceGrid& g = dense.grid();
  const std::vector<double> p = patch_pressure(g);
  const std::vector<double> eta = full_static(sloping(0, false), g, p);
  const std::vector<double> zero(g.size(), 0.0);
  const double scale = *std::max_element(eta.begin(), eta.end(), [](double a, double b) { return std::abs(a) < std::abs(b); });
  double errors[3] = {0.0, 0.0, 0.0}, potential[3] = {0.0, 0.0, 0.0};
  Bem3dSea* seas[3] = {&dense, &low, &corrected};
  for (int s = 0; s < 3; ++s) {
    seas[s]->set_surface(eta, zero);
    for (int step = 0; step < 5; ++step) seas[s]->midpoint_step(p, 0.01);
    errors[s] = largest_difference(seas[s]->elevation(), eta) / std::abs(scale);
    potential[s] = seas[s]->energy().potential;
  }
  MESSAGE("static surface (largest " << std::abs(scale) << " m), largest difference / largest: all modes " << errors[0]
                                     << ", 30 modes " << errors[1] << ", 30 modes corrected " << errors[2]);
  MESSAGE("potential energy: all modes " << potential[0] << " J, 30 modes " << potential[1] << " J, corrected "
                                         << potential[2] << " J");
  CHECK(errors[0] < 1e-10);
  CHECK(errors[2] < 1e-10);
  CHECK(errors[1] > 0.1);  // the dimple of the patch is in the dropped modes
  // The static energy 1/2 F^T K^-1 P F: the kept modes' plus 1/2 F^T R F.
  CHECK(potential[2] == doctest::Approx(potential[0]).epsilon(1e-10));
  CHECK(potential[1] < 0.9 * potential[0]);
}

TEST_CASE("3D BEM static correction: nothing held, nothing changed (the free sea keeps its energy, bit for bit)") {
  // With no pressure the correction is R 0 = 0: the corrected sea flows and
  // steps exactly as the truncated one, and keeps its energy.
  Bem3dSea low(sloping(30, false)), corrected(sloping(30, true));
  const SurfaceGrid& g = low.grid();
  std::vector<double> eta(g.size()), rate(g.size()), zero(g.size(), 0.0);
  for (std::size_t i = 0; i < eta.size(); ++i) {
    eta[i] = 1e-3 * std::sin(0.37 * static_cast<double>(i * i % 101));
    rate[i] = 1e-3 * std::cos(0.21 * static_cast<double>(i));
  }
  low.set_surface(eta, rate);
  corrected.set_surface(eta, rate);
  const double e0 = corrected.energy().total();
  for (int step = 0; step < 100; ++step) {
    low.flow(0.01);
    corrected.flow(0.01);
    low.midpoint_step(zero, 0.01);
    corrected.midpoint_step(zero, 0.01);
  }
  const double e1 = corrected.energy().total();
  MESSAGE("energy " << e0 << " J, after 200 steps " << e1 << " J (relative change " << e1 / e0 - 1.0 << ")");
  CHECK(e1 == doctest::Approx(e0).epsilon(1e-12));
  CHECK(e1 == low.energy().total());
  CHECK(largest_difference(corrected.elevation(), std::vector<double>(low.elevation().begin(), low.elevation().end())) == 0.0);
}

TEST_CASE("3D BEM static correction: the midpoint response includes R F and stays symmetric") {
  // The implicit floe–sea step needs the response of a pressure held over a
  // step to be symmetric (coupling/penalty_step.hpp): R is. With the
  // correction the response of a static-like pressure over a long step is the
  // kept modes' midpoint response plus R F.
  Bem3dSea low(sloping(30, false)), corrected(sloping(30, true));
  const SurfaceGrid& g = low.grid();
  const std::vector<double> p = patch_pressure(g);
  std::vector<double> q(g.size());
  for (std::size_t i = 0; i < q.size(); ++i) q[i] = 100.0 * std::sin(0.37 * static_cast<double>(i * i % 101));
  std::vector<double> rp(g.size()), rq(g.size()), kept(g.size());
  const double h = 0.02;
  corrected.midpoint_response(p, h, rp);
  corrected.midpoint_response(q, h, rq);
  double qrp = 0.0, prq = 0.0, size = 0.0;
  for (std::size_t i = 0; i < q.size(); ++i) {
    qrp += q[i] * rp[i];
    prq += p[i] * rq[i];
    size += std::abs(q[i] * rp[i]);
  }
  MESSAGE("q . r(p) = " << qrp << ", p . r(q) = " << prq);
  CHECK(std::abs(qrp - prq) < 1e-12 * size);
  // r(p) - kept modes' response = R F, which a held p adds to the elevation.
  low.midpoint_response(p, h, kept);
  corrected.hold_pressure(p);
  const std::span<const double> held = corrected.elevation();  // the sea is calm: R F alone
  double worst = 0.0, scale = 0.0;
  for (std::size_t i = 0; i < q.size(); ++i) {
    worst = std::max(worst, std::abs(rp[i] - kept[i] - held[i]));
    scale = std::max(scale, std::abs(held[i]));
  }
  MESSAGE("R F: largest " << scale << " m, response difference " << worst << " m");
  CHECK(scale > 0.0);
  CHECK(worst < 1e-12 * scale);
}

TEST_SUITE_END();
