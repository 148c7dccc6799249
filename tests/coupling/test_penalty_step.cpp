// The implicit step's equation on the pieces and its solver
// (coupling/penalty_step.hpp), on problems small enough to solve densely:
// a sea with a non-local (dense, symmetric positive definite) response and a
// few rigid bodies. References: the linear system solved by Eigen's LU where
// every piece stays in contact (the law is then linear), and the equation's
// residual and the discrete gradient's energy identity recomputed from the
// problem's data where pieces enter and leave contact.

#include <doctest/doctest.h>

#include <array>
#include <barrier>
#include <cmath>
#include <cstdint>
#include <random>
#include <thread>
#include <utility>
#include <vector>

#include <Eigen/Dense>

#include "core/exact_sum.hpp"
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

namespace {

// The case's pieces stored with its bodies in another order: new body j is
// the case's body perm[j], its pieces in their order; listed in `listed`
// (new indices). `old_of[k]` is the case's index of stored piece k.
struct Stored {
  std::vector<std::size_t> offsets{0};
  std::vector<std::uint32_t> bodies, old_of;
  std::vector<VerticalInertia> inertia;
  std::vector<Vec2> lever;
  std::vector<double> spring, damper, start, free_end;

  Stored(const Case& c, const std::vector<std::uint32_t>& perm, std::vector<std::uint32_t> listed)
      : bodies(std::move(listed)) {
    for (const std::uint32_t b : perm) {
      inertia.push_back(c.inertia[b]);
      for (std::size_t k = c.offsets[b]; k < c.offsets[b + 1]; ++k) {
        old_of.push_back(static_cast<std::uint32_t>(k));
        lever.push_back(c.lever[k]);
        spring.push_back(c.spring[k]);
        damper.push_back(c.damper[k]);
        start.push_back(c.start[k]);
        free_end.push_back(c.free_end[k]);
      }
      offsets.push_back(old_of.size());
    }
  }

  PenaltyStepProblem problem(const Case& c, double tolerance) const {
    PenaltyStepProblem p = c.problem(tolerance);
    p.offsets = offsets;
    p.bodies = bodies;
    p.inertia = inertia;
    p.lever = lever;
    p.spring = spring;
    p.damper = damper;
    p.start = start;
    p.free_end = free_end;
    return p;
  }

  // The case's sea, summed in the case's piece order whatever the storage:
  // each stored piece gets the bits the case's piece gets.
  SeaResponse sea(const Case& c) const {
    return [this, &c](std::span<const double> in, std::span<double> out) {
      Eigen::VectorXd u(Eigen::Index(in.size()));
      for (std::size_t k = 0; k < in.size(); ++k) u[Eigen::Index(old_of[k])] = in[k];
      const Eigen::VectorXd y = c.g_sea * u;
      for (std::size_t k = 0; k < out.size(); ++k) out[k] = y[Eigen::Index(old_of[k])];
    };
  }
};

}  // namespace

TEST_CASE("penalty step: the solution's bits do not depend on the order the bodies' pieces are stored or listed in") {
  // Pieces entering and leaving contact, dampers on half of them: several
  // Newton steps, each with its conjugate gradients.
  Case c(2.0e5, 0.03, 2);
  for (std::size_t k = 0; k < c.damper.size(); k += 2) c.damper[k] = 0.3 * c.spring[k];
  const double tolerance = 1e-10;
  PenaltyStepSolver reference;
  const PenaltyStepResult a = reference.solve(c.problem(tolerance), c.sea(), PenaltyStepOptions{});
  REQUIRE(a.status == PenaltyStepStatus::converged);
  REQUIRE(a.newton >= 2);
  // Stored 2, 0, 1 and listed backwards; stored 1, 2, 0 and listed 2, 0, 1.
  const std::vector<std::pair<std::vector<std::uint32_t>, std::vector<std::uint32_t>>> orders{
      {{2, 0, 1}, {2, 1, 0}}, {{1, 2, 0}, {2, 0, 1}}, {{0, 1, 2}, {1, 2, 0}}};
  for (const auto& [perm, listed] : orders) {
    const Stored s(c, perm, listed);
    PenaltyStepSolver solver;
    const PenaltyStepResult b = solver.solve(s.problem(c, tolerance), s.sea(c), PenaltyStepOptions{});
    CAPTURE(perm[0]);
    CAPTURE(listed[0]);
    CHECK(b.newton == a.newton);
    CHECK(b.cg == a.cg);
    CHECK(b.residual == a.residual);
    int differ = 0;
    for (std::size_t k = 0; k < s.old_of.size(); ++k) {
      differ += solver.end()[k] != reference.end()[s.old_of[k]];
      differ += solver.force()[k] != reference.force()[s.old_of[k]];
    }
    CHECK(differ == 0);
  }
}

namespace {

// Two "processes" (threads, in lockstep at each collective call) solve the
// case, each listing its own bodies (`held`): each gives the sea its own
// bodies' pieces' forces (the others' entries of its vectors are never
// read), and the reduction hook adds the two processes' ExactSum words as
// integers, as parallel::Communicator::sum does. Returns the number of
// stored entries (d1 and f on each process's own pieces) whose bits differ
// from the serial solve's, and checks the counts.
int split_differences(const Case& c, double tolerance, const PenaltyStepOptions& base,
                      const std::array<std::vector<std::uint32_t>, 2>& held) {
  PenaltyStepSolver serial;
  const PenaltyStepResult a = serial.solve(c.problem(tolerance), c.sea(), base);
  REQUIRE(a.status == PenaltyStepStatus::converged);
  const std::size_t n = c.start.size();
  std::barrier sync(2);
  std::vector<double> forces(n);                   // the sea's input, from both
  std::array<std::vector<std::int64_t>, 2> words;  // each one's ExactSum words
  std::array<double, 2> largest{};                 // each one's max
  std::array<PenaltyStepSolver, 2> solver;
  std::array<PenaltyStepResult, 2> result;
  std::array<long, 2> calls{};
  auto process = [&](int rank) {
    const std::size_t me = std::size_t(rank), other = 1 - me;
    PenaltyStepProblem p = c.problem(tolerance);
    p.bodies = held[me];
    PenaltyStepOptions options = base;
    options.reduction.sum = [&](std::span<ExactSum> sums) {
      words[me].clear();
      for (ExactSum& s : sums)
        for (std::int64_t w : s.limbs()) words[me].push_back(w);
      sync.arrive_and_wait();
      for (std::size_t j = 0; j < sums.size(); ++j) {
        std::array<std::int64_t, ExactSum::kWords> total{};
        for (std::size_t w = 0; w < total.size(); ++w)
          total[w] = words[me][j * total.size() + w] + words[other][j * total.size() + w];
        sums[j] = ExactSum::from_limbs(total);
      }
      ++calls[me];
      sync.arrive_and_wait();
    };
    options.reduction.max = [&](double value) {
      largest[me] = value;
      sync.arrive_and_wait();
      const double m = std::max(largest[0], largest[1]);
      sync.arrive_and_wait();
      return m;
    };
    const SeaResponse sea = [&](std::span<const double> in, std::span<double> out) {
      for (std::uint32_t i : held[me])
        for (std::size_t k = c.offsets[i]; k < c.offsets[i + 1]; ++k) forces[k] = in[k];
      sync.arrive_and_wait();
      const Eigen::VectorXd y = c.g_sea * Eigen::Map<const Eigen::VectorXd>(forces.data(), Eigen::Index(n));
      sync.arrive_and_wait();
      for (std::size_t k = 0; k < n; ++k) out[k] = y[Eigen::Index(k)];
    };
    result[me] = solver[me].solve(p, sea, options);
    // A process that made fewer calls (a broken rule) leaves the other to
    // finish alone rather than wait for ever: the counts below then differ.
    sync.arrive_and_drop();
  };
  std::thread second(process, 1);
  process(0);
  second.join();

  int differ = 0;
  for (std::size_t rank = 0; rank < 2; ++rank) {
    CAPTURE(rank);
    const PenaltyStepResult& b = result[rank];
    CHECK(b.newton == a.newton);
    CHECK(b.cg == a.cg);
    CHECK(b.residual == a.residual);
    CHECK(calls[rank] > 2 * b.cg);  // two sums a CG iteration, and the Newton steps'
    for (std::uint32_t i : held[rank])
      for (std::size_t k = c.offsets[i]; k < c.offsets[i + 1]; ++k) {
        differ += solver[rank].end()[k] != serial.end()[k];
        differ += solver[rank].force()[k] != serial.force()[k];
      }
  }
  return differ;
}

}  // namespace

TEST_CASE("penalty step: bodies split between two processes, their sums merged by the reduction hook, give the serial bits") {
  // Pieces entering and leaving contact, dampers on half of them; the Newton
  // steps solved inexactly and tightly; the bodies split two ways.
  for (const unsigned seed : {2u, 3u, 4u, 5u}) {
    Case c(2.0e5, 0.03, seed);
    for (std::size_t k = 0; k < c.damper.size(); k += 2) c.damper[k] = 0.3 * c.spring[k];
    PenaltyStepOptions inexact, tight;
    tight.forcing = tight.cg_tolerance;
    for (const PenaltyStepOptions& options : {inexact, tight})
      for (const auto& held : {std::array<std::vector<std::uint32_t>, 2>{{{0, 2}, {1}}},
                               std::array<std::vector<std::uint32_t>, 2>{{{1}, {2, 0}}}}) {
        CAPTURE(seed);
        CAPTURE(options.forcing);
        CAPTURE(held[0].size());
        CHECK(split_differences(c, 1e-10, options, held) == 0);
      }
  }
  // A process whose one body is out of the water all along (d0, d1 < 0: no
  // force, S = 0 on its pieces, r = 0 there): its conjugate gradients stop
  // when the other's do only if r . r is summed over both.
  Case c(2.0e5, 0.03, 2);
  for (std::size_t k = c.offsets[1]; k < c.offsets[2]; ++k) {
    c.start[k] = -0.5;
    c.free_end[k] = -0.5;
  }
  CHECK(split_differences(c, 1e-10, PenaltyStepOptions{}, {{{1}, {0, 2}}}) == 0);
}
