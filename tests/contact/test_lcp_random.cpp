// Lemke on seeded random LCPs of known classes (symmetric positive definite,
// positive semidefinite with a solution, non-symmetric P-matrices) up to n = 300,
// and on degenerate constructions. Solutions are verified by lcp_checks.hpp,
// which recomputes M z + q itself.
#include <doctest/doctest.h>

#include <random>
#include <utility>

#include "contact/lcp/lemke.hpp"
#include "core/error.hpp"
#include "tests/contact/lcp_checks.hpp"

namespace floesim::lcp {
namespace {

TEST_SUITE_BEGIN("contact");

using testing::check_complementary;

DenseMatrix gaussian(std::mt19937_64& rng, Index rows, Index cols) {
  std::normal_distribution<double> normal(0.0, 1.0);
  DenseMatrix A(rows, cols);
  for (Index j = 0; j < cols; ++j)
    for (Index i = 0; i < rows; ++i) A(i, j) = normal(rng);
  return A;
}

Vector gaussian(std::mt19937_64& rng, Index n) { return gaussian(rng, n, 1).col(0); }

// q = w* - M z* with z*, w* >= 0 complementary (half the indices active): the
// LCP has the solution z*, so Lemke must find one when M is PSD.
Vector feasible_q(std::mt19937_64& rng, const DenseMatrix& M) {
  const Index n = M.rows();
  std::uniform_real_distribution<double> uniform(0.1, 2.0);
  Vector z = Vector::Zero(n), w = Vector::Zero(n);
  for (Index i = 0; i < n; ++i) (i % 2 ? z(i) : w(i)) = uniform(rng);
  return w - M * z;
}

// Dense LU, then each sparse LU (lemke.hpp's SparseLu) forced on every basis.
void check_solved(const Lcp& lcp, double tol = 1e-9) {
  for (const auto& [f, lu] : {std::pair{Factorization::dense, SparseLu::umfpack},
                              std::pair{Factorization::sparse, SparseLu::umfpack},
                              std::pair{Factorization::sparse, SparseLu::klu}}) {
    CAPTURE(static_cast<int>(f));
    CAPTURE(static_cast<int>(lu));
    LemkeOptions options;
    options.factorization = f;
    options.sparse_lu = lu;
    const Result r = solve_lemke(lcp, options);
    REQUIRE(r.status == Status::solved);
    CHECK(r.residual <= tol);
    check_complementary(lcp, r.z, tol);
  }
}

TEST_CASE("lcp random: symmetric positive definite M - any q") {
  std::mt19937_64 rng(20240601);
  for (const Index n : {1, 2, 7, 40, 120, 300}) {
    CAPTURE(n);
    const DenseMatrix A = gaussian(rng, n, n);
    Lcp lcp{DenseMatrix(A * A.transpose() / static_cast<double>(n) +
                        0.05 * DenseMatrix::Identity(n, n)),
            gaussian(rng, n)};
    check_solved(lcp);
  }
}

TEST_CASE("lcp random: positive semidefinite M (rank n/2) with a solution") {
  std::mt19937_64 rng(7);
  for (const Index n : {4, 30, 100, 300}) {
    CAPTURE(n);
    const DenseMatrix B = gaussian(rng, n, n / 2);
    const DenseMatrix M = B * B.transpose();
    Lcp lcp{M, feasible_q(rng, M)};
    check_solved(lcp);
  }
}

TEST_CASE("lcp random: non-symmetric P-matrices") {
  std::mt19937_64 rng(99);
  for (const Index n : {3, 25, 150, 300}) {
    CAPTURE(n);
    // Positive definite (not symmetric): symmetric PD part plus a skew part.
    const DenseMatrix A = gaussian(rng, n, n);
    const DenseMatrix K = gaussian(rng, n, n);
    const DenseMatrix pd = A * A.transpose() / static_cast<double>(n) +
                           0.1 * DenseMatrix::Identity(n, n) + (K - K.transpose());
    check_solved(Lcp{pd, gaussian(rng, n)});
    // Strictly row diagonally dominant with positive diagonal.
    DenseMatrix dd = gaussian(rng, n, n);
    for (Index i = 0; i < n; ++i) dd(i, i) = 1.0 + dd.row(i).cwiseAbs().sum();
    check_solved(Lcp{dd, gaussian(rng, n)});
  }
}

TEST_CASE("lcp random: a P-matrix LCP has one solution - whatever the covering vector") {
  std::mt19937_64 rng(3);
  const Index n = 60;
  const DenseMatrix A = gaussian(rng, n, n);
  const Lcp lcp{DenseMatrix(A * A.transpose() / 60.0 + DenseMatrix::Identity(n, n)),
                gaussian(rng, n)};
  LemkeOptions other;
  other.covering = Vector::LinSpaced(n, 0.5, 3.0);
  const Result a = solve_lemke(lcp);
  const Result b = solve_lemke(lcp, other);
  REQUIRE(a.status == Status::solved);
  REQUIRE(b.status == Status::solved);
  CHECK((a.z - b.z).cwiseAbs().maxCoeff() <= 1e-9 * (1.0 + a.z.cwiseAbs().maxCoeff()));
}

TEST_CASE("lcp degenerate: duplicated contacts - repeated rows and zero blocks of q") {
  std::mt19937_64 rng(11);
  const Index m = 40;
  // Each contact appears twice (rows of J duplicated): M = J J^T is PSD with
  // pairs of identical rows and columns, q has the same pairs.
  DenseMatrix J0 = gaussian(rng, m, 30);
  DenseMatrix J(2 * m, 30);
  J << J0, J0;
  const DenseMatrix M = J * J.transpose();
  Vector q(2 * m);
  const Vector q0 = gaussian(rng, m);
  q << q0, q0;
  check_solved(Lcp{M, q});

  // Zero block of q (as in the friction LCPs): q = [negative; 0].
  Vector qz = Vector::Zero(2 * m);
  qz.head(m) = -gaussian(rng, m).cwiseAbs();
  check_solved(Lcp{M, qz});

  // Every ratio ties: M = 1 1^T + I, q = -1.
  const Index n = 50;
  const DenseMatrix ones = DenseMatrix::Ones(n, n) + DenseMatrix::Identity(n, n);
  check_solved(Lcp{ones, Vector::Constant(n, -1.0)});
}

TEST_CASE("lcp degenerate: the pivots do not depend on the scale of the problem") {
  std::mt19937_64 rng(5);
  const Index n = 80;
  const DenseMatrix B = gaussian(rng, n, 50);
  const DenseMatrix M = B * B.transpose();
  const Vector q = feasible_q(rng, M);
  const Result reference = solve_lemke(Lcp{M, q});
  REQUIRE(reference.status == Status::solved);
  for (const double s : {1e-6, 1e6}) {
    CAPTURE(s);
    const Lcp scaled{DenseMatrix(s * M), Vector(s * q)};
    const Result r = solve_lemke(scaled);
    REQUIRE(r.status == Status::solved);
    CHECK(r.pivots == reference.pivots);
    check_complementary(scaled, r.z, 1e-9);
  }
}

TEST_CASE("lcp: q >= 0 is solved by z = 0 without pivots") {
  const Lcp lcp{DenseMatrix(-DenseMatrix::Identity(3, 3)), Vector::Constant(3, 2.0)};
  const Result r = solve_lemke(lcp);
  CHECK(r.status == Status::solved);
  CHECK(r.pivots == 0);
  CHECK(r.z.isZero());
  CHECK(r.residual == 0.0);
}

TEST_CASE("lcp: an infeasible copositive-plus LCP ends on a ray") {
  // z1 - z2 - 1 >= 0 and z2 - z1 - 1 >= 0 cannot both hold.
  DenseMatrix M(2, 2);
  M << 1, -1, -1, 1;
  const Result r = solve_lemke(Lcp{M, Vector::Constant(2, -1.0)});
  CHECK(r.status == Status::ray);
  CHECK(r.residual > 0.1);
}

TEST_CASE("lcp: the pivot limit is reported and a malformed LCP is refused") {
  std::mt19937_64 rng(1);
  const DenseMatrix A = gaussian(rng, 30, 30);
  const Lcp lcp{DenseMatrix(A * A.transpose()), Vector::Constant(30, -1.0)};
  LemkeOptions options;
  options.max_pivots = 3;
  const Result r = solve_lemke(lcp, options);
  CHECK(r.status == Status::pivot_limit);
  CHECK(r.pivots == 3);

  CHECK_THROWS_AS(solve_lemke(Lcp{DenseMatrix::Identity(3, 3), Vector::Ones(2)}), RunError);
  DenseMatrix bad = DenseMatrix::Identity(2, 2);
  bad(0, 1) = std::numeric_limits<double>::quiet_NaN();
  CHECK_THROWS_AS(solve_lemke(Lcp{bad, Vector::Ones(2)}), RunError);
  options.covering = Vector::Zero(30);
  CHECK_THROWS_AS(solve_lemke(lcp, options), RunError);
}

TEST_CASE("lcp warm start: Lemke from an earlier basis solves a nearby LCP in few pivots, or says it did not") {
  // For a P-matrix (here symmetric positive definite) the LCP has one solution, so the warm
  // start must find the same z as a cold solve. From the basis of the LCP's own solution it
  // needs no pivot; from the basis of a nearby q (a step of a jam later) it needs fewer
  // than the cold solve. A start from a singular basis is refused (failed), never "solved".
  std::mt19937_64 rng(20261201);
  const Index n = 200;
  const DenseMatrix A = gaussian(rng, n, n);
  const DenseMatrix M = A * A.transpose() / static_cast<double>(n) + 0.05 * DenseMatrix::Identity(n, n);
  const Lcp first{M, gaussian(rng, n)};
  const Result cold = solve_lemke(first);
  REQUIRE(cold.status == Status::solved);
  REQUIRE(cold.z_basic.size() == static_cast<std::size_t>(n));
  LemkeOptions warm;
  warm.start = &cold.z_basic;
  const Result again = solve_lemke(first, warm);
  REQUIRE(again.status == Status::solved);
  CHECK(again.pivots == 0);
  CHECK((again.z - cold.z).norm() <= 1e-9 * (1.0 + cold.z.norm()));

  const Lcp nearby{M, first.q + 0.05 * gaussian(rng, n)};
  const Result nearby_cold = solve_lemke(nearby);
  const Result nearby_warm = solve_lemke(nearby, warm);
  REQUIRE(nearby_cold.status == Status::solved);
  REQUIRE(nearby_warm.status == Status::solved);
  MESSAGE("pivots: cold " << nearby_cold.pivots << ", warm " << nearby_warm.pivots);
  CHECK(nearby_warm.pivots < nearby_cold.pivots);
  check_complementary(nearby, nearby_warm.z, 1e-9);
  CHECK((nearby_warm.z - nearby_cold.z).norm() <= 1e-8 * (1.0 + nearby_cold.z.norm()));

  // A singular start: z_0 and z_1 basic with identical columns.
  DenseMatrix S = M;
  S.col(1) = S.col(0);
  S.row(1) = S.row(0);
  std::vector<std::uint8_t> singular(static_cast<std::size_t>(n), 0);
  singular[0] = singular[1] = 1;
  warm.start = &singular;
  CHECK(solve_lemke(Lcp{S, first.q}, warm).status == Status::failed);
  std::vector<std::uint8_t> short_start(3, 0);
  warm.start = &short_start;
  CHECK_THROWS_AS(solve_lemke(first, warm), RunError);
}

TEST_SUITE_END();

}  // namespace
}  // namespace floesim::lcp
