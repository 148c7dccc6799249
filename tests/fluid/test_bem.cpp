// BEM vertical-slice basin: sloshing frequencies against the analytic
// relation, convergence against panel count, a sloping bottom, and agreement
// with the spectral backend. Issue 5, "Validation tests".
#include <doctest/doctest.h>

#include <cmath>
#include <numbers>
#include <vector>

#include "fluid/bem.hpp"
#include "fluid/spectral.hpp"
#include "fluid/waves.hpp"
#include "tests/fluid/sea_cases.hpp"

using namespace floesim;
using namespace floesim::fluid;

TEST_SUITE_BEGIN("fluid");
constexpr double pi = std::numbers::pi;

namespace {

// Largest relative error of the first `count` frequencies against
// omega_n^2 = (g k_n + sigma k_n^3 / rho) tanh(k_n H), k_n = n pi / L.
double worst_error(const SeaParams& p, const BemSea& sea, int count) {
  const Dispersion d = Dispersion::of(p);
  double worst = 0.0;
  for (int n = 1; n <= count; ++n)
    worst = std::max(worst, std::abs(sea.frequencies()[n - 1] / d.omega(n * pi / p.size[0]) - 1.0));
  return worst;
}

}  // namespace

TEST_CASE("BEM rectangular tank: the first 10 sloshing frequencies within 0.5% and second order in panels") {
  std::vector<double> err;
  for (int ns : {50, 100, 200}) {
    const SeaParams p = cases::lab_tank_bem(ns);
    BemSea sea(p);
    err.push_back(worst_error(p, sea, 10));
    MESSAGE("surface panels " << ns << ", panels " << sea.panels() << ": worst error of modes 1-10 "
                              << err.back() << ", setup " << sea.setup_seconds() << " s");
  }
  // 100 surface panels (224 panels in all) meet the 0.5% bound.
  CHECK(err[1] < 0.005);
  for (std::size_t i = 1; i < err.size(); ++i) {
    const double order = std::log2(err[i - 1] / err[i]);
    CAPTURE(i);
    CHECK(order > 1.7);  // measured 1.73 then 1.82: approaching 2
    CHECK(order < 2.3);
  }
}

TEST_CASE("BEM flat tank agrees with the spectral sea: sloshing mode n is Fourier mode n of a 2L box") {
  SeaParams b = cases::lab_tank_bem(200, 2.0, 0.3);
  BemSea bem(b);
  SeaParams s = b;
  s.model = SeaModel::spectral;
  s.size = {4.0, 1.0};
  s.cells = {256, 1};
  SpectralSea spectral(s);
  for (int n = 1; n <= 10; ++n) {
    CAPTURE(n);
    CHECK(bem.frequencies()[n - 1] == doctest::Approx(spectral.omega(n)).epsilon(0.002));
  }
}

TEST_CASE("BEM sloping bottom: frequencies converge and lie between the shallow and deep flat tanks") {
  // Kelvin's minimum-energy theorem: deepening the basin can only lower the added
  // mass m_sf, so by min-max each omega_n lies between those of the flat basins
  // at the smallest and largest depth.
  auto sloped = [](int ns) {
    SeaParams p = cases::lab_tank_bem(ns);
    p.bottom = {{0.0, -0.15}, {0.4, -0.15}, {1.0, -0.05}};
    return p;
  };
  std::vector<std::vector<double>> f;
  for (int ns : {40, 80, 160}) {
    BemSea sea(sloped(ns));
    f.emplace_back(sea.frequencies().begin(), sea.frequencies().begin() + 10);
  }
  double d1 = 0.0, d2 = 0.0;
  for (int n = 0; n < 10; ++n) {
    d1 = std::max(d1, std::abs(f[1][n] / f[0][n] - 1.0));
    d2 = std::max(d2, std::abs(f[2][n] / f[1][n] - 1.0));
  }
  MESSAGE("sloping bottom: change 40->80 panels " << d1 << ", 80->160 panels " << d2);
  // Measured ratio 0.33 (order 1.6: the sloping bottom meets the wall at a
  // non-right angle, a corner singularity).
  CHECK(d2 < 0.4 * d1);
  CHECK(d2 < 3e-3);
  BemSea shallow(cases::lab_tank_bem(160, 1.0, 0.05)), deep(cases::lab_tank_bem(160, 1.0, 0.15));
  for (int n = 0; n < 10; ++n) {
    CAPTURE(n);
    CHECK(f[2][n] > shallow.frequencies()[n]);
    CHECK(f[2][n] < deep.frequencies()[n]);
  }
}

TEST_CASE("BEM sea: a sloshing mode oscillates at its frequency and conserves energy under uniform pressure") {
  SeaParams p = cases::lab_tank_bem(64);
  p.waves.kind = WaveKind::standing;
  p.waves.amplitude = 1e-3;
  p.waves.wavelength = 2.0 / 3.0;  // mode n = 3: cos(3 pi x / L)
  auto sea = make_sea(p, 1);
  auto& bem = dynamic_cast<BemSea&>(*sea);
  CHECK(bem.from_cache() == false);
  const double w = bem.frequencies()[2], e0 = sea->energy().total();
  // a_sf of a cos(k x) over the basin (width 1 m): 1/4 (rho g + sigma k^2) a^2 L;
  // at rest (standing wave at t = 0) that is all the energy.
  const double k = 3.0 * pi;
  CHECK(e0 == doctest::Approx(0.25 * (p.rho * p.g + p.sigma * k * k) * 1e-6 * 1.0).epsilon(2e-3));
  CHECK(sea->energy().kinetic == doctest::Approx(0.0));
  const std::vector<double> eta0(sea->elevation().begin(), sea->elevation().end());
  for (int s = 0; s < 100; ++s)
    sea->step(2.0 * pi / w / 100.0, [](Sea&, double, std::span<double> pr) {
      for (double& v : pr) v = 1000.0;
    });
  double diff = 0.0;
  const auto eta = sea->elevation();
  for (std::size_t i = 0; i < eta.size(); ++i) diff = std::max(diff, std::abs(eta[i] - eta0[i]));
  // The discrete cosine is mode 3 up to discretisation: after one period of mode 3
  // the surface is back to within a small fraction of the amplitude.
  CHECK(diff < 0.05 * 1e-3);
  CHECK(sea->energy().total() == doctest::Approx(e0).epsilon(1e-12));
  auto again = make_sea(p, 1);
  CHECK(dynamic_cast<BemSea&>(*again).from_cache());
}

TEST_SUITE_END();
