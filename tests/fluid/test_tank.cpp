// Tank runs in a periodic box: a generation zone makes a regular wave that
// crosses the working section and dies in the absorbing zone. Issue 5, "Waves".
#include <doctest/doctest.h>

#include <cmath>
#include <complex>
#include <numbers>
#include <vector>

#include "core/error.hpp"
#include "fluid/sea.hpp"
#include "fluid/spectral.hpp"
#include "fluid/tank.hpp"
#include "tests/fluid/sea_cases.hpp"

using namespace floesim;
using namespace floesim::fluid;

TEST_SUITE_BEGIN("fluid");
using cplx = std::complex<double>;
constexpr double pi = std::numbers::pi;

TEST_CASE("relaxation weight rises from 0 at the inner edge to 1 at the outer end") {
  CHECK(relaxation_weight(0.0) == 0.0);
  CHECK(relaxation_weight(1.0) == doctest::Approx(1.0).epsilon(1e-15));
  for (double c = 0.05; c <= 1.0; c += 0.05) CHECK(relaxation_weight(c) > relaxation_weight(c - 0.05));
}

TEST_CASE("a tank wave reaches the middle at the target amplitude and the absorbing zone hardly reflects") {
  SeaParams p = cases::lab_box_1d(512);
  p.size = {16.0, 1.0};
  p.depth = 0.5;
  p.waves.kind = WaveKind::regular;
  p.waves.amplitude = 0.01;
  p.waves.wavelength = 1.0;
  SeaOptions opt;
  opt.tank.enabled = true;  // defaults: generation 3 wavelengths, absorption 2, rate 4 omega
  auto sea = make_sea(p, 1, opt);
  const auto* tank = dynamic_cast<SpectralSea&>(*sea).tank();
  REQUIRE(tank != nullptr);
  const double w = tank->target().omega, k = tank->target().kx;
  const double period = 2.0 * pi / w, dt = period / 32.0;
  // Spin-up: the front crosses the tank at the group velocity (~0.6 m/s), and the
  // reflection of the absorbing zone returns to the middle: ~3 crossings.
  const int spin = 32 * 60, sample = 32 * 10;
  for (int s = 0; s < spin; ++s) sea->flow(dt);

  // Complex amplitude at each cell, demodulated over 10 periods:
  // A(x) = (2 / N) sum eta(x, t) e^{i w t} = alpha e^{i k x} + beta e^{-i k x}.
  const auto& g = sea->grid();
  std::vector<cplx> amp(g.nx, 0.0);
  for (int s = 0; s < sample; ++s) {
    sea->flow(dt);
    const auto e = sea->elevation();
    const cplx rot = std::polar(2.0 / sample, w * sea->time());
    for (int i = 0; i < g.nx; ++i) amp[i] += e[i] * rot;
  }
  // Least squares for (alpha, beta) over the working section, one wavelength
  // clear of each zone.
  cplx n11 = 0, n12 = 0, n22 = 0, r1 = 0, r2 = 0;
  for (int i = 0; i < g.nx; ++i) {
    const double x = g.x(i);
    if (x < tank->generation_length() + 1.0 || x > g.lx - tank->absorption_length() - 1.0) continue;
    const cplx ep = std::polar(1.0, k * x), em = std::conj(ep);
    n11 += 1.0;
    n12 += std::conj(ep) * em;
    n22 += 1.0;
    r1 += std::conj(ep) * amp[i];
    r2 += std::conj(em) * amp[i];
  }
  const cplx det = n11 * n22 - n12 * std::conj(n12);
  const cplx alpha = (r1 * n22 - n12 * r2) / det, beta = (n11 * r2 - std::conj(n12) * r1) / det;
  const double target = p.waves.amplitude;
  MESSAGE("incident " << std::abs(alpha) << " m, reflected " << std::abs(beta) << " m, middle "
                      << std::abs(amp[g.nx / 2]) << " m (target " << target << " m)");
  CHECK(std::abs(std::abs(alpha) / target - 1.0) < 0.02);
  CHECK(std::abs(std::abs(amp[g.nx / 2]) / target - 1.0) < 0.02);
  CHECK(std::abs(beta) / std::abs(alpha) < 0.05);
}

TEST_CASE("tank zones that do not fit are an InputError") {
  SeaParams p = cases::lab_box_1d(64);
  p.waves.kind = WaveKind::regular;
  p.waves.amplitude = 0.001;
  p.waves.wavelength = 0.5;
  SeaOptions opt;
  opt.tank.enabled = true;  // 1.5 m + 1 m zones in a 1 m box
  CHECK_THROWS_AS(make_sea(p, 1, opt), InputError);
}

TEST_SUITE_END();
