// Spectral sea: free oscillations against the dispersion relation, energy,
// point queries. MODEL.md §3; issue 5 "Validation tests".
#include <doctest/doctest.h>

#include <cmath>
#include <limits>
#include <numbers>
#include <vector>

#include "fluid/sea.hpp"
#include "fluid/spectral.hpp"
#include "fluid/waves.hpp"
#include "tests/fluid/sea_cases.hpp"

using namespace floesim;
using namespace floesim::fluid;

TEST_SUITE_BEGIN("fluid");
constexpr double pi = std::numbers::pi;

namespace {

// Period of the elevation at cell 0, measured from the simulated surface: step
// until the elevation changes sign, then Newton on the crossing time using the
// simulated rate eta' (the flow is exact for any step, so each Newton update is
// itself a step of the sea). Averaged over `periods` periods.
double measured_period(Sea& sea, double guess, int periods) {
  auto eta = [&] { return sea.elevation()[0]; };
  auto rate = [&] { return sea.field(Field::velocity_z)[0]; };
  const double dt = guess / 40.0;
  std::vector<double> crossings;
  double prev = eta();
  while (crossings.size() < static_cast<std::size_t>(2 * periods + 1)) {
    sea.flow(dt);
    const double cur = eta();
    if ((prev < 0.0) != (cur < 0.0)) {
      for (int it = 0; it < 8; ++it) sea.flow(-eta() / rate());
      crossings.push_back(sea.time());
    }
    prev = cur;
  }
  return (crossings.back() - crossings.front()) / periods;
}

}  // namespace

TEST_CASE("standing waves in the 1 m box of 0.1 m depth oscillate at the dispersion periods") {
  // omega^2 = (g k + sigma k^3 / rho) tanh(k H), k = 2 pi n / L; the issue quotes
  // T = 1.0723, 0.6134, 0.40185, 0.28035, 0.19297, 0.12408 s (0.14148 s without capillarity).
  const int modes[] = {1, 2, 4, 8, 16, 32};
  const double quoted[] = {1.0723, 0.6134, 0.40185, 0.28035, 0.19297, 0.12408};
  for (int m = 0; m < 6; ++m) {
    const int n = modes[m];
    SeaParams p = cases::lab_box_1d(256);
    p.waves.kind = WaveKind::standing;
    p.waves.amplitude = 1e-3;
    p.waves.wavelength = 1.0 / n;
    const Dispersion d = Dispersion::of(p);
    const double expected = 2.0 * pi / d.omega(2.0 * pi * n);
    CAPTURE(n);
    // The dispersion relation reproduces the numbers to their last digit.
    CHECK(std::abs(expected - quoted[m]) < 0.51 * std::pow(10.0, std::floor(std::log10(quoted[m])) - 4));
    auto sea = make_sea(p, 1);
    const double measured = measured_period(*sea, expected, 5);
    MESSAGE("n = " << n << ": T = " << measured << " s, relative error " << measured / expected - 1.0);
    CHECK(std::abs(measured / expected - 1.0) < 1e-6);
  }
  // Gravity only at n = 32.
  SeaParams p = cases::lab_box_1d(256);
  p.sigma = 0.0;
  const double tg = 2.0 * pi / Dispersion::of(p).omega(2.0 * pi * 32);
  CHECK(std::abs(tg - 0.14148) < 0.51e-5);
}

TEST_CASE("a standing wave in a 2-D box oscillates at the dispersion period") {
  SeaParams p = cases::lab_box_1d(64);
  p.dims = 2;
  p.size = {1.0, 0.5};
  p.cells = {64, 32};
  p.waves.kind = WaveKind::standing;
  p.waves.amplitude = 1e-3;
  p.waves.wavelength = 0.25;
  p.waves.direction = 90.0;  // along y: k = 2 pi 2 / 0.5
  auto sea = make_sea(p, 1);
  const double expected = 2.0 * pi / Dispersion::of(p).omega(2.0 * pi / 0.25);
  CHECK(std::abs(measured_period(*sea, expected, 3) / expected - 1.0) < 1e-6);
}

TEST_CASE("the energy of a free sea is conserved to round-off over 1e5 steps") {
  SeaParams p;
  p.model = SeaModel::spectral;
  p.dims = 2;
  p.size = {100.0, 100.0};
  p.cells = {32, 32};
  p.depth = 20.0;
  p.waves.kind = WaveKind::jonswap;
  p.waves.hs = 1.0;
  p.waves.tp = 8.0;
  p.waves.spreading = 4.0;
  auto sea = make_sea(p, 7);
  const double e0 = sea->energy().total();
  REQUIRE(e0 > 0.0);
  double worst = 0.0;
  for (int s = 0; s < 100000; ++s) {
    sea->flow(0.37);
    if (s % 1000 == 999) worst = std::max(worst, std::abs(sea->energy().total() / e0 - 1.0));
  }
  MESSAGE("largest relative energy change over 1e5 steps: " << worst);
  // Each step is an exact rotation per mode: only round-off accumulates, at
  // most about one unit roundoff per step (1e5 x 2.2e-16).
  CHECK(worst < 1e5 * std::numeric_limits<double>::epsilon());
}

TEST_CASE("a progressive wave has kinetic = potential energy = (rho g + sigma k^2) a^2 A / 4") {
  SeaParams p = cases::lab_box_1d(128);
  p.dims = 2;
  p.size = {1.0, 0.5};
  p.cells = {128, 64};
  p.waves.kind = WaveKind::regular;
  p.waves.amplitude = 2e-3;
  p.waves.wavelength = 0.125;
  p.waves.direction = 0.0;
  auto sea = make_sea(p, 1);
  const double k = 2.0 * pi / 0.125, a = 2e-3, area = 0.5;
  const double each = 0.25 * (p.rho * p.g + p.sigma * k * k) * a * a * area;
  for (int s = 0; s < 3; ++s) {
    const SeaEnergy e = sea->energy();
    CHECK(e.kinetic == doctest::Approx(each).epsilon(1e-12));
    CHECK(e.potential == doctest::Approx(each).epsilon(1e-12));
    sea->flow(0.0123);
  }
  // Parseval: the modal potential energy equals 1/2 ∫ sigma |grad eta|^2 + rho g eta^2
  // computed from the grid fields.
  const auto eta = sea->elevation();
  std::vector<double> sx(sea->field(Field::slope_x).all().begin(), sea->field(Field::slope_x).all().end());
  const auto sy = sea->field(Field::slope_y).all();
  double pot = 0.0;
  for (std::size_t i = 0; i < eta.size(); ++i)
    pot += 0.5 * (p.sigma * (sx[i] * sx[i] + sy[i] * sy[i]) + p.rho * p.g * eta[i] * eta[i]);
  pot *= sea->grid().cell_area();
  CHECK(pot == doctest::Approx(sea->energy().potential).epsilon(1e-12));
}

TEST_CASE("point queries give the elevation and slope and orbital velocity of linear theory") {
  // eta = a cos(k.x - w t); grad phi at z = 0: horizontal a w coth(k H) cos(.) k/|k|,
  // vertical a w sin(.).
  SeaParams p;
  p.model = SeaModel::spectral;
  p.dims = 2;
  p.size = {40.0, 40.0};
  p.cells = {128, 128};
  p.depth = 5.0;
  p.waves.kind = WaveKind::regular;
  p.waves.amplitude = 0.1;
  p.waves.wavelength = 40.0 / std::sqrt(13.0);  // wave vector 2 pi (3, 2) / 40
  p.waves.direction = std::atan2(2.0, 3.0) * 180.0 / pi;
  auto sea = make_sea(p, 1);
  sea->flow(1.7);
  const double kx = 2 * pi * 3 / 40.0, ky = 2 * pi * 2 / 40.0, k = std::hypot(kx, ky);
  const double w = Dispersion::of(p).omega(k), a = 0.1, t = sea->time();
  const double coth = 1.0 / std::tanh(k * p.depth);
  double worst = 0.0;
  for (int m = 0; m < 25; ++m) {
    const double x = 1.618 * m + 0.3, y = 40.0 - 1.37 * m;  // arbitrary, off the grid
    const double th = kx * x + ky * y - w * t;
    const SurfaceSample s = sea->sample(x, y);
    worst = std::max({worst, std::abs(s.eta - a * std::cos(th)) / a,
                      std::abs(s.slope_x + a * kx * std::sin(th)) / (a * k),
                      std::abs(s.slope_y + a * ky * std::sin(th)) / (a * k),
                      std::abs(s.u - a * w * coth * std::cos(th) * kx / k) / (a * w * coth),
                      std::abs(s.v - a * w * coth * std::cos(th) * ky / k) / (a * w * coth),
                      std::abs(s.w - a * w * std::sin(th)) / (a * w)});
  }
  MESSAGE("point queries: worst relative error " << worst);
  // Cubic interpolation between cell centres: error ~ (k h)^4 / 40 with k h = 0.18.
  CHECK(worst < 1e-4);
}

TEST_CASE("a uniform pressure does nothing: the surface keeps zero mean") {
  SeaParams p = cases::lab_box_1d(64);
  p.waves.kind = WaveKind::regular;
  p.waves.amplitude = 1e-3;
  p.waves.wavelength = 0.25;
  auto sea = make_sea(p, 1);
  auto free_sea = make_sea(p, 1);
  for (int s = 0; s < 10; ++s) {
    sea->step(0.01, [](Sea&, double, std::span<double> pr) {
      for (double& v : pr) v = 500.0;
    });
    free_sea->flow(0.01);
  }
  const auto e = sea->elevation(), f = free_sea->elevation();
  double mean = 0.0, diff = 0.0;
  for (std::size_t i = 0; i < e.size(); ++i) {
    mean += e[i] / static_cast<double>(e.size());
    diff = std::max(diff, std::abs(e[i] - f[i]));
  }
  CHECK(std::abs(mean) < 1e-15);
  CHECK(diff < 1e-15);
}

TEST_CASE("deferred kicks are invisible: queries between the operations of a step change nothing") {
  // The spectral sea fuses kicks into the next flow; every query must see the
  // settled state, and a queried run must match an unqueried one.
  SeaParams p;
  p.model = SeaModel::spectral;
  p.dims = 2;
  p.size = {50.0, 50.0};
  p.cells = {32, 32};
  p.depth = 10.0;
  p.waves.kind = WaveKind::jonswap;
  p.waves.hs = 0.5;
  p.waves.tp = 4.0;
  p.waves.spreading = 2.0;
  auto quiet = make_sea(p, 5), busy = make_sea(p, 5);
  std::vector<double> pr(quiet->grid().size());
  for (std::size_t i = 0; i < pr.size(); ++i) pr[i] = 300.0 * std::exp(-0.01 * static_cast<double>(i % 97));
  double e_before = 0.0, e_after = 0.0;
  for (int s = 0; s < 20; ++s) {
    quiet->kick(pr, 0.05);
    quiet->flow(0.1);
    quiet->kick(pr, 0.05);
    e_before = busy->energy().total();
    busy->kick(pr, 0.05);
    e_after = busy->energy().total();  // sees the kick at once
    (void)busy->sample(3.0, 4.0);
    busy->flow(0.1);
    (void)busy->field(Field::velocity_x);
    busy->kick(pr, 0.05);
    (void)busy->sample(7.0, 1.0);
  }
  CHECK(e_after != e_before);
  double diff = 0.0, scale = 0.0;
  for (Field f : {Field::elevation, Field::velocity_x, Field::velocity_z}) {
    const auto a = quiet->field(f).all(), b = busy->field(f).all();
    for (std::size_t i = 0; i < a.size(); ++i) {
      diff = std::max(diff, std::abs(a[i] - b[i]));
      scale = std::max(scale, std::abs(a[i]));
    }
  }
  CHECK(diff <= 1e-13 * scale);
  CHECK(quiet->energy().total() == doctest::Approx(busy->energy().total()).epsilon(1e-13));
}

TEST_CASE("the y-velocity made alongside the x-velocity equals the y-velocity made alone") {
  // The x-velocity's pass over the modes also stages the y-velocity's spectrum;
  // it must be exactly the field a lone query makes, and dropped when the
  // state changes (kick, flow, modes()).
  SeaParams p;
  p.model = SeaModel::spectral;
  p.dims = 2;
  p.size = {60.0, 40.0};
  p.cells = {32, 24};
  p.depth = 8.0;
  p.waves.kind = WaveKind::jonswap;
  p.waves.hs = 0.6;
  p.waves.tp = 4.0;
  p.waves.spreading = 3.0;
  p.waves.direction = 30.0;
  auto both = make_sea(p, 3), alone = make_sea(p, 3);
  std::vector<double> pr(both->grid().size());
  for (std::size_t i = 0; i < pr.size(); ++i) pr[i] = 200.0 * std::cos(0.07 * static_cast<double>(i));
  auto same_vy = [&] {
    (void)both->field(Field::velocity_x);
    const auto a = both->field(Field::velocity_y).all(), b = alone->field(Field::velocity_y).all();
    double diff = 0.0, scale = 0.0;
    for (std::size_t i = 0; i < a.size(); ++i) {
      diff = std::max(diff, std::abs(a[i] - b[i]));
      scale = std::max(scale, std::abs(b[i]));
    }
    CHECK(scale > 0.0);
    CHECK(diff == 0.0);
  };
  same_vy();
  for (auto* s : {both.get(), alone.get()}) s->kick(pr, 0.05);  // deferred kick, folded into the rates
  same_vy();
  for (auto* s : {both.get(), alone.get()}) s->flow(0.1);
  same_vy();
  for (auto* s : {both.get(), alone.get()}) s->kick(pr, 0.02);
  (void)both->field(Field::velocity_x);  // stages vy, then the state changes under it
  for (auto* s : {both.get(), alone.get()}) {
    auto v = s->modes().v();
    for (std::size_t i = 0; i < v.size(); ++i) v[i] *= 0.5;
  }
  const auto a = both->field(Field::velocity_y).all(), b = alone->field(Field::velocity_y).all();
  double diff = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i) diff = std::max(diff, std::abs(a[i] - b[i]));
  CHECK(diff == 0.0);
}

TEST_SUITE_END();
