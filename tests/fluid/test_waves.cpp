// Waves: dispersion helpers, JONSWAP seas, and input validation (exit-2 errors
// naming the key).
#include <doctest/doctest.h>

#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "fluid/sea.hpp"
#include "fluid/waves.hpp"
#include "tests/fluid/sea_cases.hpp"

using namespace floesim;
using namespace floesim::fluid;

TEST_SUITE_BEGIN("fluid");
constexpr double pi = std::numbers::pi;

namespace {

std::string input_error(const SeaParams& p) {
  try {
    make_sea(p, 1);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

bool has(const std::string& s, const std::string& part) { return s.find(part) != std::string::npos; }

}  // namespace

TEST_CASE("dispersion: wavenumber inverts omega and deep-water and group-velocity limits hold") {
  Dispersion d{9.81, 0.073, 1025.0, 3.0};
  for (double k : {0.01, 0.5, 3.0, 200.0}) CHECK(d.wavenumber(d.omega(k)) == doctest::Approx(k).epsilon(1e-12));
  Dispersion deep{9.81, 0.0, 1025.0, std::numeric_limits<double>::infinity()};
  CHECK(deep.omega(2.0) == doctest::Approx(std::sqrt(9.81 * 2.0)).epsilon(1e-15));
  CHECK(deep.group_velocity(2.0) == doctest::Approx(0.5 * std::sqrt(9.81 / 2.0)).epsilon(1e-12));
  const double h = 1e-6;
  CHECK(d.group_velocity(1.3) == doctest::Approx((d.omega(1.3 + h) - d.omega(1.3 - h)) / (2 * h)).epsilon(1e-7));
}

TEST_CASE("a JONSWAP sea has the requested Hs and is reproducible from its seed and peaks near Tp") {
  SeaParams p;
  p.model = SeaModel::spectral;
  p.dims = 1;
  p.size = {2000.0, 10.0};
  p.cells = {4096, 1};
  p.depth = 50.0;
  p.waves.kind = WaveKind::jonswap;
  p.waves.hs = 2.0;
  p.waves.tp = 9.0;
  auto a = make_sea(p, 11), b = make_sea(p, 11), c = make_sea(p, 12);
  const auto ea = a->elevation(), eb = b->elevation(), ec = c->elevation();
  double var = 0.0, same = 0.0, other = 0.0;
  for (std::size_t i = 0; i < ea.size(); ++i) {
    var += ea[i] * ea[i] / static_cast<double>(ea.size());
    same = std::max(same, std::abs(ea[i] - eb[i]));
    other = std::max(other, std::abs(ea[i] - ec[i]));
  }
  CHECK(4.0 * std::sqrt(var) == doctest::Approx(2.0).epsilon(1e-12));
  CHECK(same == 0.0);
  CHECK(other > 0.1);
  // Energy-weighted mean frequency of a JONSWAP spectrum (gamma 3.3) lies
  // slightly above the peak: omega_mean / omega_p ~ 1.2 (m1/m0 moment).
  const auto& bank = a->modes();
  double m0 = 0.0, m1 = 0.0;
  for (std::size_t j = 0; j < bank.modes(); ++j) {
    const double e = bank.mass()[j] * (bank.v()[2 * j] * bank.v()[2 * j] + bank.v()[2 * j + 1] * bank.v()[2 * j + 1]);
    m0 += e;
    m1 += e * bank.omega()[j];
  }
  const double ratio = (m1 / m0) / (2.0 * pi / 9.0);
  CHECK(ratio > 1.05);
  CHECK(ratio < 1.4);
}

TEST_CASE("a long-crested 2-D JONSWAP sea along x does not vary along y") {
  SeaParams p;
  p.model = SeaModel::spectral;
  p.dims = 2;
  p.size = {400.0, 200.0};
  p.cells = {128, 16};
  p.waves.kind = WaveKind::jonswap;
  p.waves.hs = 1.0;
  p.waves.tp = 7.0;
  p.waves.spreading = 0.0;
  auto sea = make_sea(p, 3);
  const auto e = sea->elevation();
  double dev = 0.0;
  for (int j = 1; j < 16; ++j)
    for (int i = 0; i < 128; ++i) dev = std::max(dev, std::abs(e[j * 128 + i] - e[i]));
  CHECK(dev < 1e-12);
}

TEST_CASE("a spread JONSWAP sea travels in its mean direction") {
  // For a progressive wave along k, eta = a cos(theta) and the orbital velocity
  // is a w coth(kH) cos(theta) k/|k|: <eta (u, v)> points along the propagation.
  // cos^2s((theta - theta0)/2) spreading is symmetric about theta0.
  SeaParams p;
  p.model = SeaModel::spectral;
  p.dims = 2;
  p.size = {400.0, 400.0};
  p.cells = {128, 128};
  p.depth = 30.0;
  p.waves.kind = WaveKind::jonswap;
  p.waves.hs = 1.5;
  p.waves.tp = 6.0;
  p.waves.direction = 30.0;
  p.waves.spreading = 10.0;
  auto sea = make_sea(p, 21);
  const auto eta = sea->elevation();
  std::vector<double> u(sea->field(Field::velocity_x).all().begin(), sea->field(Field::velocity_x).all().end());
  const auto v = sea->field(Field::velocity_y).all();
  double mx = 0.0, my = 0.0;
  for (std::size_t i = 0; i < eta.size(); ++i) {
    mx += eta[i] * u[i];
    my += eta[i] * v[i];
  }
  const double mean = std::atan2(my, mx) * 180.0 / pi;
  MESSAGE("mean direction " << mean << " degrees (requested 30)");
  CHECK(mean == doctest::Approx(30.0).epsilon(0.05));
}

TEST_CASE("bad [sea] input is an InputError that names the key") {
  SeaParams ok = cases::lab_box_1d(64);
  CHECK(input_error(ok).empty());

  SeaParams p = ok;
  p.cells = {0, 1};
  CHECK(has(input_error(p), "[sea] cells"));
  p = ok;
  p.size = {-1.0, 1.0};
  CHECK(has(input_error(p), "[sea] size"));
  p = ok;
  p.depth = 0.0;
  CHECK(has(input_error(p), "[sea] depth"));
  p = ok;
  p.dims = 3;
  CHECK(has(input_error(p), "[sea] dims"));

  // A wave the grid cannot resolve: the message gives the wavelength and the spacing.
  p = ok;
  p.waves.kind = WaveKind::regular;
  p.waves.amplitude = 1e-3;
  p.waves.wavelength = 0.03;  // 1.92 cells of 1/64 m
  const std::string m = input_error(p);
  CHECK(has(m, "[sea.waves] wavelength"));
  CHECK(has(m, "0.03 m"));
  CHECK(has(m, "0.015625 m"));
  p.waves.wavelength = 0.0;
  CHECK(has(input_error(p), "[sea.waves] wavelength"));
  p.waves.wavelength = 0.25;
  p.waves.direction = 30.0;  // dims = 1 carries waves along x only
  CHECK(has(input_error(p), "[sea.waves] direction"));

  p = ok;
  p.waves.kind = WaveKind::jonswap;
  p.waves.hs = 0.0;
  p.waves.tp = 0.5;
  CHECK(has(input_error(p), "[sea.waves] hs"));

  // BEM basins (the bottom polyline's own rules are checked at load: tests/core/test_config.cpp).
  SeaParams b = cases::lab_tank_bem(32);
  CHECK(input_error(b).empty());
  b.bottom = {{0.0, -0.1}, {1.2, -0.1}};
  CHECK(input_error(b).empty());
  // A 3D basin (dims = 2, fluid/bem3d.hpp) needs cells across it.
  b = cases::lab_tank_bem(32);
  b.dims = 2;
  CHECK(has(input_error(b), "[sea] cells"));
  b.cells = {32, 4};
  CHECK(input_error(b).empty());
}

TEST_SUITE_END();
