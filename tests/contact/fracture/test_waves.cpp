// Percussion dynamics: a pulse travels along a slender strip at the bar
// speed sqrt(E / rho) (1D wave equation rho u_tt = E u_xx; e.g. Graff, Wave
// Motion in Elastic Solids, §2.1), and the impulse given is the one asked.
#include <doctest/doctest.h>

#include <cmath>

#include "cases.hpp"
#include "contact/fracture/response.hpp"

using namespace floesim;
using namespace floesim::fracture;
using namespace floesim::fracture::testing;

TEST_SUITE_BEGIN("contact");

TEST_CASE("fracture waves: a percussion pulse runs along a strip at sqrt(E / rho)") {
  const double lx = 300.0, ly = 3.0;
  Material mat{6.0e9, 0.3, 917.0, 1.0};
  MeshOptions mo;
  mo.size = 1.0;
  const ElasticModel model(mesh_polygon(rectangle(lx, ly), mo), mat);
  const double c0 = model.bar_speed();
  ResponseOptions ro;
  ro.duration = 15.0 / c0;  // a pulse 15 m long, five times the strip's width
  ro.load_radius = 1.5;
  Responder responder(model, ro);
  const PointLoad hit{{-lx / 2, 0.0}, {2.0e4, 0.0}, true};
  // Stations 150 m apart, far enough from both ends for the direct pulse to
  // pass before the reflection from the far end comes back.
  const double xs[2] = {-75.0, 75.0};
  // The stress pulse is the force pulse over the section, sigma = F(t - x / c0) / (W h):
  // its crest pi J / (2 tau W h). Damping (5% at the mesh's shortest wave, 0.3% at the
  // pulse's frequency) and dispersion lower it on the way (by 17% over 150 m here).
  const double crest = M_PI / 2.0 * hit.value.x() / (ly * mat.thickness * ro.duration);
  double peak[2] = {0.0, 0.0}, when[2] = {0.0, 0.0};
  double last[2][2] = {{0.0, 0.0}, {0.0, 0.0}};  // the two previous samples of -sxx
  bool rising[2] = {true, true};
  const Eigen::VectorXd& m = model.lumped_mass();
  double momentum_check = 0.0;
  responder.respond(std::span<const PointLoad>(&hit, 1), [&](double t, const Eigen::VectorXd& u) {
    const auto s = model.nodal_stress(u);
    for (int k = 0; k < 2; ++k) {
      if (t > (lx + (lx / 2 - xs[k])) / c0 * 0.95) continue;  // before the reflection
      Eigen::Vector3d v;
      REQUIRE(model.interpolate(s, Vec2{xs[k], 0.0}, v));
      const double y0 = last[k][0], y1 = last[k][1], y2 = -v[0];
      // The crest: the parabola through three samples around the largest.
      if (rising[k] && y1 > y2 && y1 > y0 && y1 > 0.3 * crest) {
        const double dt = responder.time_step();
        const double shift = 0.5 * (y0 - y2) / (y0 - 2.0 * y1 + y2);
        peak[k] = y1;
        when[k] = t - dt + shift * dt;
        rising[k] = false;
      }
      last[k][0] = y1;
      last[k][1] = y2;
    }
    double p = 0.0, scale = 0.0;
    for (Eigen::Index i = 0; i < u.size(); i += 2) {
      p += m[i] * u[i];
      scale += m[i] * std::abs(u[i]);
    }
    if (scale > 0.0) momentum_check = std::max(momentum_check, std::abs(p) / scale);
  });
  const double speed = (xs[1] - xs[0]) / (when[1] - when[0]);
  MESSAGE("front speed " << speed << " m/s, sqrt(E/rho) = " << c0 << " m/s, peaks " << peak[0] << " " << peak[1]);
  CHECK(speed == doctest::Approx(c0).epsilon(0.02));
  CHECK(peak[0] == doctest::Approx(crest).epsilon(0.1));
  CHECK(peak[1] < peak[0]);
  CHECK(peak[1] > 0.8 * peak[0]);
  // The rigid part stays removed (inertia relief is exact in linear dynamics).
  CHECK(momentum_check < 1e-8);
}

TEST_SUITE_END();
