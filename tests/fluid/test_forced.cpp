// Forced response: the Strang-split step kick(dt/2) flow(dt) kick(dt/2)
// converges at second order in dt. Issue 5, "Forced response".
#include <doctest/doctest.h>

#include <cmath>
#include <numbers>
#include <vector>

#include "fluid/sea.hpp"
#include "fluid/waves.hpp"
#include "tests/fluid/sea_cases.hpp"

using namespace floesim;
using namespace floesim::fluid;

TEST_SUITE_BEGIN("fluid");
constexpr double pi = std::numbers::pi;

namespace {

// Max-norm of the elevation after integrating to t_end with steps dt.
std::vector<double> run(const SeaParams& p, const Sea::PressureFn& pressure, double dt,
                        double t_end) {
  auto sea = make_sea(p, 1);
  const int steps = static_cast<int>(std::lround(t_end / dt));
  for (int s = 0; s < steps; ++s) sea->step(dt, pressure);
  const auto e = sea->elevation();
  return {e.begin(), e.end()};
}

double max_diff(const std::vector<double>& a, const std::vector<double>& b) {
  double m = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i) m = std::max(m, std::abs(a[i] - b[i]));
  return m;
}

}  // namespace

TEST_CASE("a pressure mode P cos(kx) sin(Wt) drives the Duhamel response at second order in dt") {
  // mu A'' + mu w^2 A = -P sin(W t), mu = rho coth(kH)/k, A(0) = A'(0) = 0:
  // A(t) = -(P / mu) (sin(W t) - (W / w) sin(w t)) / (w^2 - W^2).
  SeaParams p = cases::lab_box_1d(64);
  const double k = 2.0 * pi * 3.0, big_p = 50.0, big_w = 5.0, t_end = 2.0;
  const Dispersion d = Dispersion::of(p);
  const double w = d.omega(k), mu = d.mass_density(k);
  auto pressure = [&](Sea& sea, double t, std::span<double> out) {
    for (int i = 0; i < sea.grid().nx; ++i)
      out[i] = big_p * std::cos(k * sea.grid().x(i)) * std::sin(big_w * t);
  };
  const double amp = -(big_p / mu) * (std::sin(big_w * t_end) - big_w / w * std::sin(w * t_end)) /
                     (w * w - big_w * big_w);
  std::vector<double> err;
  for (double dt : {0.04, 0.02, 0.01, 0.005}) {
    const auto e = run(p, pressure, dt, t_end);
    double m = 0.0;
    for (int i = 0; i < 64; ++i) m = std::max(m, std::abs(e[i] - amp * std::cos(k * (i + 0.5) / 64)));
    err.push_back(m);
  }
  for (std::size_t i = 1; i < err.size(); ++i) {
    const double order = std::log2(err[i - 1] / err[i]);
    MESSAGE("Duhamel mode: error " << err[i] << ", order " << order);
    CHECK(order == doctest::Approx(2.0).epsilon(0.05));
  }
}

TEST_CASE("a pulsating pressure patch: the Strang step converges at second order in dt") {
  // No closed form here: the order is measured from successive refinements,
  // log2(|e(dt) - e(dt/2)| / |e(dt/2) - e(dt/4)|) -> 2.
  SeaParams p;
  p.model = SeaModel::spectral;
  p.dims = 2;
  p.size = {10.0, 10.0};
  p.cells = {64, 64};
  p.depth = 1.0;
  auto pressure = [](Sea& sea, double t, std::span<double> out) {
    const auto& g = sea.grid();
    for (int j = 0; j < g.ny; ++j)
      for (int i = 0; i < g.nx; ++i) {
        const double r2 = (g.x(i) - 5.0) * (g.x(i) - 5.0) + (g.y(j) - 5.0) * (g.y(j) - 5.0);
        out[static_cast<std::size_t>(j) * g.nx + i] = 200.0 * std::exp(-r2 / 0.5) * std::sin(4.0 * t);
      }
  };
  std::vector<std::vector<double>> runs;
  for (double dt : {0.04, 0.02, 0.01, 0.005}) runs.push_back(run(p, pressure, dt, 1.6));
  for (std::size_t i = 2; i < runs.size(); ++i) {
    const double order = std::log2(max_diff(runs[i - 2], runs[i - 1]) / max_diff(runs[i - 1], runs[i]));
    MESSAGE("pressure patch: measured order " << order);
    CHECK(order == doctest::Approx(2.0).epsilon(0.05));
  }
}

TEST_CASE("a positive pressure pushes the surface down under it, in both backends") {
  // -∫ p v on the right of m_sf(eta'', v) + a_sf(eta, v): from rest, eta'' has the
  // sign of -p where p is applied (MODEL.md §3; the water feels -p, §4).
  auto check = [](SeaParams p) {
    auto sea = make_sea(p, 1);
    const auto& g = sea->grid();
    auto patch = [](Sea& s, double, std::span<double> out) {
      const auto& gr = s.grid();
      for (int i = 0; i < gr.nx; ++i) {
        const double d = (gr.x(i) - 0.5 * gr.lx) / (0.05 * gr.lx);
        out[i] = 100.0 * std::exp(-d * d);
      }
    };
    for (int s = 0; s < 5; ++s) sea->step(0.002, patch);
    const SurfaceSample mid = sea->sample(0.5 * g.lx), far = sea->sample(0.05 * g.lx);
    CHECK(mid.eta < 0.0);
    CHECK(mid.w < 0.0);
    CHECK(std::abs(far.eta) < 0.05 * std::abs(mid.eta));
  };
  check(cases::lab_box_1d(128));
  check(cases::lab_tank_bem(128));
}

TEST_CASE("a repeated kick acts as a kick by the same pressure, deferred or applied, in both backends") {
  // repeat_kick(h) must equal kick(p, h) with the p of the last kick, to the
  // bit: while that kick is still deferred (spectral), after it was applied by
  // a flow or a query, and behind a second deferred kick.
  auto check = [](SeaParams p) {
    auto a = make_sea(p, 1), b = make_sea(p, 1);
    const auto& g = a->grid();
    std::vector<double> p1(g.size()), p2(g.size());
    for (int i = 0; i < g.nx; ++i) {
      const double d = (g.x(i) - 0.4 * g.lx) / (0.05 * g.lx);
      p1[i] = 100.0 * std::exp(-d * d);
      p2[i] = 40.0 * std::sin(9.0 * g.x(i) / g.lx);
    }
    for (int s = 0; s < 4; ++s) {
      a->kick(p1, 0.001);
      a->repeat_kick(0.002);  // still deferred
      b->kick(p1, 0.001);
      b->kick(p1, 0.002);
      a->flow(0.003);
      b->flow(0.003);
      a->repeat_kick(0.001);  // applied by the flow
      b->kick(p1, 0.001);
      (void)a->energy();      // applied by a query
      a->repeat_kick(0.0015);
      b->kick(p1, 0.0015);
      a->kick(p2, 0.001);
      a->repeat_kick(0.001);  // behind a deferred kick by p1
      b->kick(p2, 0.001);
      b->kick(p2, 0.001);
      a->flow(0.004);
      b->flow(0.004);
      a->repeat_kick(0.0005);  // p2, from the second slot, applied by the flow
      b->kick(p2, 0.0005);
    }
    for (Field f : {Field::elevation, Field::velocity_x, Field::velocity_z}) {
      const auto ea = a->field(f).all(), eb = b->field(f).all();
      double diff = 0.0, scale = 0.0;
      for (std::size_t i = 0; i < ea.size(); ++i) {
        diff = std::max(diff, std::abs(ea[i] - eb[i]));
        scale = std::max(scale, std::abs(eb[i]));
      }
      CHECK(scale > 0.0);
      CHECK(diff == 0.0);  // the same arithmetic, whatever settled in between
    }
  };
  check(cases::lab_box_1d(128));
  check(cases::lab_tank_bem(128));
}

TEST_SUITE_END();
