// Drift under ocean drag, air drag and Coriolis, validated against closed-form
// solutions of the equations in MODEL.md §2 (coupling/drift.hpp).
#include <doctest/doctest.h>

#include <cmath>
#include <iomanip>
#include <numbers>
#include <sstream>

#include <Eigen/Dense>

#include "core/geometry.hpp"
#include "coupling/simulation.hpp"

using namespace floesim;

TEST_SUITE_BEGIN("coupling");

namespace {

constexpr double kRhoW = 1025.0, kRhoI = 917.0, kCw = 5e-3, kRhoA = 1.341, kCa = 1.7e-3;

// One square floe of side `side`, thickness h, centred at the origin.
Simulation square_floe(const std::string& forcing, double dt, double side = 20.0, double h = 1.0,
                       const std::string& floe_extra = "") {
  std::ostringstream t;
  const double a = side / 2;
  t << "[run]\ndt_max = " << dt << "\n[sea]\nrho = " << kRhoW << "\n"
    << "[[floes.floe]]\nvertices = [[" << -a << ", " << -a << "], [" << a << ", " << -a << "], [" << a << ", "
    << a << "], [" << -a << ", " << a << "]]\nthickness = " << h << "\ndensity = " << kRhoI << "\n"
    << floe_extra << "\n[forcing]\nocean_drag = " << kCw << "\nair_drag = " << kCa << "\nair_density = " << kRhoA
    << "\n" << forcing << "\n";
  return Simulation(build_scenario(parse_config(t.str(), "test.toml", ".")));
}

void advance(Simulation& s, double t) {
  while (s.time() < t) s.step(t);
}

}  // namespace

TEST_CASE("footprint quadrature integrates area and second moments exactly") {
  Simulation s = square_floe("", 1.0, 20.0);
  const Floes& f = s.floes();
  const FootprintQuadrature q = build_footprint_quadrature(f, 1);
  double area = 0, jxx = 0;
  for (std::size_t j = q.first[0]; j < q.first[0] + q.count[0]; ++j) {
    area += q.weight[j];
    jxx += q.weight[j] * q.point[j].x() * q.point[j].x();
  }
  CHECK(area == doctest::Approx(400.0).epsilon(1e-13));
  CHECK(jxx == doctest::Approx(20.0 * 20.0 * 20.0 * 20.0 / 12.0).epsilon(1e-13));
}

TEST_CASE("a floe in a constant current relaxes to it by the analytic law") {
  // M dv/dt = rho_w C_w A |U - v| (U - v)  =>  with u = U - v and k = rho_w C_w / (rho_i h):
  //   du/dt = -k u^2,  u(t) = U / (1 + k U t),  v(t) = U - U / (1 + k U t).
  const double U = 0.3, h = 1.0, k = kRhoW * kCw / (kRhoI * h), T = 1500.0;
  const double exact = U - U / (1 + k * U * T);
  double previous_error = 0.0;
  for (double dt : {8.0, 4.0, 2.0, 1.0}) {
    Simulation s = square_floe("current = [0.3, 0.0]", dt);
    advance(s, T);
    const double v = s.floes().state[0].vx;
    const double error = std::abs(v - exact);
    MESSAGE("dt = " << dt << ": v = " << v << ", exact " << exact << ", error " << error);
    CHECK(error < 2e-3 * dt * U);  // first order in dt (linearised backward Euler)
    CHECK(std::abs(s.floes().state[0].vy) < 1e-15);
    CHECK(std::abs(s.floes().state[0].yaw_rate) < 1e-15);  // uniform flow on a symmetric floe: no torque
    if (previous_error > 0) {
      const double order = std::log2(previous_error / error);
      CHECK(order == doctest::Approx(1.0).epsilon(0.15));
    }
    previous_error = error;
  }
}

TEST_CASE("wind + current equilibrium velocity matches the closed form") {
  SUBCASE("no Coriolis: v = U_w + sqrt(rho_a C_a / (rho_w C_w)) U_a") {
    Simulation s = square_floe("current = [0.1, -0.05]\nwind = [8.0, 6.0]", 10.0);
    advance(s, 2.0e5);
    const double r = std::sqrt(kRhoA * kCa / (kRhoW * kCw));
    CHECK(s.floes().state[0].vx == doctest::Approx(0.1 + r * 8.0).epsilon(1e-9));
    CHECK(s.floes().state[0].vy == doctest::Approx(-0.05 + r * 6.0).epsilon(1e-9));
  }
  SUBCASE("with Coriolis") {
    // Per unit area, with m = rho_i h, c = rho_w C_w, a = f m, u = U_w - v, tau_a = rho_a C_a |U_a| U_a:
    //   tau_a + c |u| u - f m k x v = 0  <=>  (c|u| I + a K) u = R,  R = -tau_a + a K U_w
    // (K the rotation by +90 degrees). Taking norms: c^2 s^4 + a^2 s^2 = |R|^2 with s = |u|, so
    //   s^2 = (-a^2 + sqrt(a^4 + 4 c^2 |R|^2)) / (2 c^2),  u = (c s I + a K)^{-1} R.
    const double f = 1.4e-4, h = 1.0, m = kRhoI * h, c = kRhoW * kCw, a = f * m;
    const Vec2 Uw{0.1, -0.05}, Ua{8.0, 6.0};
    const Vec2 tau = kRhoA * kCa * Ua.norm() * Ua;
    const Vec2 KU{-Uw.y(), Uw.x()};
    const Vec2 R = -tau + a * KU;
    const double s2 = (-a * a + std::sqrt(a * a * a * a + 4 * c * c * R.squaredNorm())) / (2 * c * c);
    Eigen::Matrix2d A;
    A << c * std::sqrt(s2), -a, a, c * std::sqrt(s2);
    const Vec2 u = A.lu().solve(R);
    const Vec2 v = Uw - u;
    Simulation sim = square_floe("current = [0.1, -0.05]\nwind = [8.0, 6.0]\ncoriolis = 1.4e-4", 10.0);
    advance(sim, 3.0e5);
    CHECK(sim.floes().state[0].vx == doctest::Approx(v.x()).epsilon(1e-8));
    CHECK(sim.floes().state[0].vy == doctest::Approx(v.y()).epsilon(1e-8));
    // Coriolis turns the drift to the right of the no-Coriolis one (northern hemisphere).
    CHECK(cross(Uw + std::sqrt(kRhoA * kCa / c) * Ua, v) < 0.0);
  }
}

TEST_CASE("an inertial oscillation under Coriolis has period 2 pi / f") {
  // No drag: dV/dt = -f k x V, a circle traversed clockwise (f > 0) with period 2 pi / f.
  const double f = 1.4e-4, T = 2 * std::numbers::pi / f, dt = T / 2000;
  std::ostringstream t;
  t << "[run]\ndt_max = " << dt << "\n[[floes.floe]]\nvertices = [[0,0],[10,0],[10,10],[0,10]]\n"
    << "velocity = [0.1, 0.0]\n[forcing]\nocean_drag = 0.0\nair_drag = 0.0\ncoriolis = " << f << "\n";
  Simulation sim(build_scenario(parse_config(t.str(), "test.toml", ".")));
  // Times at which vy changes sign from + to - (once per period), interpolated linearly.
  std::vector<double> crossings;
  double prev_vy = sim.floes().state[0].vy, prev_t = 0.0;
  while (sim.time() < 3.2 * T) {
    sim.step(3.2 * T);
    const double vy = sim.floes().state[0].vy;
    if (prev_vy > 0.0 && vy <= 0.0) crossings.push_back(prev_t + (sim.time() - prev_t) * prev_vy / (prev_vy - vy));
    prev_vy = vy;
    prev_t = sim.time();
    const double speed = std::hypot(sim.floes().state[0].vx, vy);
    REQUIRE(speed == doctest::Approx(0.1).epsilon(1e-12));  // the trapezoidal rule keeps |V|
  }
  REQUIRE(crossings.size() >= 3);
  const double period = (crossings.back() - crossings.front()) / static_cast<double>(crossings.size() - 1);
  MESSAGE("measured period " << std::setprecision(12) << period << " s, 2 pi / f = " << T << " s");
  CHECK(period == doctest::Approx(T).epsilon(1e-5));
}

TEST_CASE("a spinning floe in still water slows down at the rate the drag integral predicts") {
  // Pure rotation: v_P = omega k x r, so tau = -rho_w C_w |omega| omega |r| (k x r) and the torque is
  //   T = -rho_w C_w omega |omega| ∫ |r|^3 dA.  With I_z = rho_i h ∫ |r|^2 dA:
  //   d omega / dt = -c omega |omega|, c = rho_w C_w ∫|r|^3 / I_z  =>  omega(t) = omega0 / (1 + c omega0 t).
  // ∫|r|^3 over the square comes from its closed form (core/geometry polar_moment3, tested there).
  const double side = 20.0, h = 1.0, w0 = 0.02, T = 600.0;
  const double b = side / 2, s2 = std::sqrt(2.0);
  const double r3 = std::pow(b, 5) * 8.0 / 5.0 * (s2 / 2 + 3.0 * (s2 + std::log(1 + s2)) / 8.0);
  const double Iz = kRhoI * h * side * side * side * side / 6.0;
  // The run integrates ∫|r|^3 with the footprint quadrature (degree 4 on the fan triangles):
  // check it against the closed form, then the decay law with the quadrature's own integral.
  Simulation probe = square_floe("", 1.0, side, h);
  const FootprintQuadrature q = build_footprint_quadrature(probe.floes());
  double r3q = 0.0;
  for (std::size_t j = q.first[0]; j < q.first[0] + q.count[0]; ++j) r3q += q.weight[j] * std::pow(q.point[j].norm(), 3);
  MESSAGE("quadrature of |r|^3: " << r3q << ", closed form " << r3 << ", relative error " << r3q / r3 - 1);
  CHECK(r3q == doctest::Approx(r3).epsilon(2e-3));
  const double c = kRhoW * kCw * r3q / Iz;
  const double exact = w0 / (1 + c * w0 * T);
  double prev = 0;
  for (double dt : {4.0, 2.0, 1.0}) {
    Simulation s = square_floe("", dt, side, h, "angular_velocity = 0.02");
    advance(s, T);
    const double err = std::abs(s.floes().state[0].yaw_rate - exact);
    MESSAGE("dt = " << dt << ": omega = " << s.floes().state[0].yaw_rate << ", exact " << exact);
    CHECK(err < 0.01 * (w0 - exact));  // within 1% of the lost angular velocity
    CHECK(std::hypot(s.floes().state[0].vx, s.floes().state[0].vy) < 1e-15);
    if (prev > 0) CHECK(std::log2(prev / err) == doctest::Approx(1.0).epsilon(0.2));
    prev = err;
  }
}

TEST_CASE("static floes never move") {
  Simulation s = square_floe("current = [0.5, 0.2]\nwind = [10, 0]", 1.0, 20.0, 1.0, "static = true");
  advance(s, 100.0);
  CHECK(s.floes().state[0].x == 0.0);
  CHECK(s.floes().state[0].vx == 0.0);
}

TEST_CASE("stiff drag: a thin floe with a step far above its drag time stays stable and monotone") {
  // h = 1 cm in a 1 m/s current: drag time rho_i h / (rho_w C_w U) = 1.8 s; dt = 60 s is 33 times
  // longer. Linearised backward Euler must neither oscillate nor overshoot the current.
  Simulation s = square_floe("current = [1.0, 0.0]", 60.0, 20.0, 0.01, "angular_velocity = 0.5");
  double prev = 0.0, prev_w = 0.5;
  for (int k = 0; k < 50; ++k) {
    s.step(1e9);
    const FloeState& st = s.floes().state[0];
    CHECK(st.vx >= prev);             // monotone approach
    CHECK(st.vx <= 1.0 + 1e-12);      // never past the current
    CHECK(std::abs(st.yaw_rate) <= prev_w);  // spin decays without changing sign
    CHECK(st.yaw_rate >= 0.0);
    prev = st.vx;
    prev_w = std::abs(st.yaw_rate);
  }
  CHECK(prev == doctest::Approx(1.0).epsilon(1e-3));
}

TEST_SUITE_END();

TEST_CASE("a soft mooring: the undamped and damped oscillator of its period and ratio") {
  // coupling/mooring.hpp: with no drag, a floe started at its anchor with
  // speed v0 follows x'' = -omega^2 x - 2 zeta omega x', whose solution is
  //   x(t) = v0 / omega_d exp(-zeta omega t) sin(omega_d t),  omega_d = omega sqrt(1 - zeta^2).
  const double period = 20.0, v0 = 0.1, omega = 2.0 * std::numbers::pi / period;
  for (double zeta : {0.0, 0.3}) {
    INFO("damping ratio " << zeta);
    std::ostringstream extra;
    extra << "velocity = [" << v0 << ", 0.0]\nmooring_period = " << period << "\nmooring_damping = " << zeta << "\n";
    std::ostringstream toml;
    toml << "[run]\ndt_max = 0.01\n[[floes.floe]]\nvertices = [[-10, -10], [10, -10], [10, 10], [-10, 10]]\n"
      << extra.str() << "[forcing]\nocean_drag = 0.0\nair_drag = 0.0\n";
    Simulation s(build_scenario(parse_config(toml.str(), "test.toml", ".")));
    const double wd = omega * std::sqrt(1.0 - zeta * zeta);
    double worst = 0.0;
    for (double t : {0.25 * period, 0.5 * period, 0.8 * period, 1.5 * period}) {
      advance(s, t);
      const double exact = v0 / wd * std::exp(-zeta * omega * t) * std::sin(wd * t);
      worst = std::max(worst, std::abs(s.floes().state[0].x - exact));
      CHECK(std::abs(s.floes().state[0].y) < 1e-12);
    }
    MESSAGE("largest error " << worst << " m of an amplitude " << v0 / omega << " m");
    CHECK(worst < 0.01 * v0 / omega);
  }
}
