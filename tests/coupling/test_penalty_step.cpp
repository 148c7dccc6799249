// The implicit step's equation on the pieces and its solver
// (coupling/penalty_step.hpp), on problems small enough to solve densely:
// a sea with a non-local (dense, symmetric positive definite) response and a
// few rigid bodies. References: the linear system solved by Eigen's LU where
// every piece stays in contact (the law is then linear), and the equation's
// residual and the discrete gradient's energy identity recomputed from the
// problem's data where pieces enter and leave contact.

#include <doctest/doctest.h>

#include <cmath>
#include <random>
#include <vector>

#include <Eigen/Dense>

#include "coupling/penalty_law.hpp"
#include "coupling/penalty_step.hpp"

using namespace floesim;

namespace {

// Three bodies of 12, 20 and 9 pieces (heave only; pitch; pitch and roll)
// on a sea whose response couples every piece to every other one.
struct Case {
  double h = 0.05;
  std::vector<std::size_t> offsets{0, 12, 32, 41};
  std::vector<std::uint32_t> bodies{0, 1, 2};
  std::vector<VerticalInertia> inertia;
  std::vector<Vec2> lever;
  std::vector<double> spring, damper, start, free_end;
  Eigen::MatrixXd g_sea;  // m/N

  explicit Case(double stiffness, double depth_of_free_end, unsigned seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    const std::size_t n = offsets.back();
    for (std::uint8_t i = 0; i < 3; ++i) {
      VerticalInertia in;
      in.slopes = i;
      in.mass(0, 0) = 4.0e4 * (1 + i);
      in.inverse_mass(0, 0) = 1.0 / in.mass(0, 0);
      for (int d = 1; d <= i; ++d) {
        in.mass(d, d) = 3.0e5 * (1 + i);
        in.inverse_mass(d, d) = 1.0 / in.mass(d, d);
      }
      inertia.push_back(in);
    }
    for (std::size_t k = 0; k < n; ++k) {
      lever.emplace_back(5.0 * u(rng), 5.0 * u(rng));
      spring.push_back(stiffness * (0.5 + 0.5 * std::abs(u(rng))));
      damper.push_back(0.0);
      start.push_back(0.05 + 0.02 * u(rng));
      free_end.push_back(depth_of_free_end + 0.03 * u(rng));
    }
    // A smooth, decaying kernel (like the sea's |k| response: positive
    // definite, largest on the diagonal), scaled as h^2 / 2 per unit mass.
    Eigen::MatrixXd A(n, n);
    for (std::size_t a = 0; a < n; ++a)
      for (std::size_t b = 0; b < n; ++b) {
        const double r = (lever[a] - lever[b]).norm() + 1.5 * std::abs(double(a / 12) - double(b / 12));
        A(a, b) = std::exp(-r / 3.0);
      }
    g_sea = 0.5 * h * h / 2.0e3 * A;
  }

  PenaltyStepProblem problem(double tolerance) const {
    PenaltyStepProblem p;
    p.step = h;
    p.offsets = offsets;
    p.bodies = bodies;
    p.inertia = inertia;
    p.lever = lever;
    p.spring = spring;
    p.damper = damper;
    p.start = start;
    p.free_end = free_end;
    p.self_response = g_sea(0, 0);
    p.tolerance = tolerance;
    return p;
  }

  SeaResponse sea() const {
    return [this](std::span<const double> in, std::span<double> out) {
      const Eigen::VectorXd y = g_sea * Eigen::Map<const Eigen::VectorXd>(in.data(), Eigen::Index(in.size()));
      for (std::size_t k = 0; k < out.size(); ++k) out[k] = y[Eigen::Index(k)];
    };
  }

  // G = G_sea + per body h^2 / 2 Phi M^-1 Phi^T, densely.
  Eigen::MatrixXd g() const {
    Eigen::MatrixXd G = g_sea;
    for (std::size_t i = 0; i < 3; ++i)
      for (std::size_t a = offsets[i]; a < offsets[i + 1]; ++a)
        for (std::size_t b = offsets[i]; b < offsets[i + 1]; ++b) {
          const Eigen::Vector3d pa(1.0, lever[a].x(), lever[a].y()), pb(1.0, lever[b].x(), lever[b].y());
          G(Eigen::Index(a), Eigen::Index(b)) += 0.5 * h * h * pa.dot(inertia[i].inverse_mass * pb);
        }
    return G;
  }

  // max_k |d1 - d_free + G f(d0, d1)|, recomputed from the data.
  double residual(std::span<const double> d1) const {
    const std::size_t n = d1.size();
    Eigen::VectorXd f(n), d(n), r(n);
    for (std::size_t k = 0; k < n; ++k) {
      f[Eigen::Index(k)] = step_force(spring[k], damper[k], start[k], d1[k]).f;
      d[Eigen::Index(k)] = d1[k] - free_end[k];
    }
    r = d + g() * f;
    return r.cwiseAbs().maxCoeff();
  }
};

}  // namespace

TEST_CASE("penalty step: every piece in contact (a linear law) gives the dense linear solve's answer") {
  // Every piece stays wet (d0, d1 > 0): f = c (d0 + d1) / 2, so
  // (I + G C / 2) d1 = d_free - G C d0 / 2.
  const Case c(2.0e5, 0.3, 1);
  const std::size_t n = c.start.size();
  const Eigen::MatrixXd G = c.g();
  Eigen::VectorXd C(n), d0(n), dfree(n);
  for (std::size_t k = 0; k < n; ++k) {
    C[Eigen::Index(k)] = c.spring[k];
    d0[Eigen::Index(k)] = c.start[k];
    dfree[Eigen::Index(k)] = c.free_end[k];
  }
  const Eigen::MatrixXd A = Eigen::MatrixXd::Identity(n, n) + 0.5 * G * C.asDiagonal();
  const Eigen::VectorXd ref = A.lu().solve(dfree - 0.5 * G * C.cwiseProduct(d0));
  REQUIRE(ref.minCoeff() > 0.0);  // the case is what it says
  for (const double forcing : {1e-12, 1e-2})
    for (const bool predictor : {false, true}) {
      PenaltyStepSolver solver;
      PenaltyStepOptions options;
      options.forcing = forcing;
      options.predictor = predictor;
      const PenaltyStepResult r = solver.solve(c.problem(1e-12), c.sea(), options);
      CAPTURE(forcing);
      CAPTURE(predictor);
      CHECK(r.status == PenaltyStepStatus::converged);
      double err = 0.0;
      for (std::size_t k = 0; k < n; ++k) err = std::max(err, std::abs(solver.end()[k] - ref[Eigen::Index(k)]));
      CHECK(err < 1e-11);
      MESSAGE("forcing " << forcing << ", predictor " << predictor << ": " << r.newton << " Newton, " << r.cg
                         << " CG, error " << err << " m");
    }
}

TEST_CASE("penalty step: pieces entering and leaving contact; the residual and the discrete gradient's energy identity") {
  // Free ends near the surface: some pieces leave the water, some stay; the
  // damper is on for half of them.
  Case c(2.0e5, 0.03, 2);
  for (std::size_t k = 0; k < c.damper.size(); k += 2) c.damper[k] = 0.3 * c.spring[k];
  const double tolerance = 1e-10;
  PenaltyStepSolver exact, inexact;
  PenaltyStepOptions tight;
  tight.forcing = tight.cg_tolerance;
  const PenaltyStepResult a = exact.solve(c.problem(tolerance), c.sea(), tight);
  const PenaltyStepResult b = inexact.solve(c.problem(tolerance), c.sea(), PenaltyStepOptions{});
  REQUIRE(a.status == PenaltyStepStatus::converged);
  REQUIRE(b.status == PenaltyStepStatus::converged);
  int wet = 0, dry = 0;
  for (double d : exact.end()) (d > 0.0 ? wet : dry) += 1;
  CHECK(wet > 0);
  CHECK(dry > 0);
  // The residual, recomputed densely, meets the tolerance (up to the
  // rounding of G's products).
  CHECK(c.residual(exact.end()) < 2 * tolerance);
  CHECK(c.residual(inexact.end()) < 2 * tolerance);
  // The spring's force is the discrete gradient: f (d1 - d0) = c/2 ([d1]^+^2 - [d0]^+^2)
  // exactly; the damper only absorbs.
  for (std::size_t k = 0; k < c.start.size(); ++k) {
    const double d0 = c.start[k], d1 = exact.end()[k];
    const double spring = step_force(c.spring[k], 0.0, d0, d1).f * (d1 - d0);
    const double potential = 0.5 * c.spring[k] * (std::pow(std::max(d1, 0.0), 2) - std::pow(std::max(d0, 0.0), 2));
    CHECK(spring == doctest::Approx(potential).epsilon(1e-12).scale(1.0));
    CHECK((exact.force()[k] - step_force(c.spring[k], 0.0, d0, d1).f) * (d1 - d0) >= 0.0);
  }
  // The inexact iteration solves the same equation with fewer conjugate-gradient iterations.
  MESSAGE("exact: " << a.newton << " Newton, " << a.cg << " CG; inexact: " << b.newton << " Newton, " << b.cg << " CG");
  CHECK(b.cg < a.cg);
  double diff = 0.0;
  for (std::size_t k = 0; k < c.start.size(); ++k) diff = std::max(diff, std::abs(exact.end()[k] - inexact.end()[k]));
  CHECK(diff < 1e-8);
}

TEST_CASE("penalty step: a Newton limit is reported as a status, with the residual reached") {
  const Case c(2.0e6, 0.01, 3);
  PenaltyStepSolver solver;
  PenaltyStepOptions options;
  options.max_newton = 1;
  const PenaltyStepResult r = solver.solve(c.problem(1e-14), c.sea(), options);
  CHECK(r.status == PenaltyStepStatus::newton_limit);
  CHECK(r.newton == 1);
  CHECK(r.residual > 1e-14);
  CHECK(r.residual == doctest::Approx(c.residual(solver.end())).epsilon(1e-6));
}
