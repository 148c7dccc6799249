// Projected Gauss–Seidel and the fallback chain: each step is reached when the
// previous fails, reported in order, and the PGS answer is flagged.
#include <doctest/doctest.h>

#include "contact/lcp/fallback.hpp"
#include "contact/lcp/siconos_io.hpp"
#include "core/error.hpp"
#include "tests/contact/lcp_checks.hpp"

namespace floesim::lcp {
namespace {

TEST_SUITE_BEGIN("contact");

using testing::check_complementary;
using testing::lcp_data;

TEST_CASE("lcp pgs: solves a symmetric positive definite contact LCP to tolerance") {
  const Lcp lcp = read_siconos_lcp(lcp_data("contact/delassus_m50_s1.dat"));
  PgsOptions options;
  options.tolerance = 1e-11;
  const Result r = solve_pgs(lcp, options);
  REQUIRE(r.status == Status::solved);
  CHECK(r.residual <= 1e-11);
  CHECK(r.iterations > 0);
  check_complementary(lcp, r.z, 1e-9);
}

TEST_CASE("lcp pgs: refuses a zero diagonal and stops at the iteration limit") {
  const Lcp friction = read_siconos_lcp(lcp_data("contact/friction_m10_s1.dat"));
  CHECK(solve_pgs(friction).status == Status::failed);  // the beta block has M_ii = 0

  const Lcp lcp = read_siconos_lcp(lcp_data("contact/delassus_m50_s1.dat"));
  PgsOptions few;
  few.max_iterations = 2;
  few.tolerance = 1e-14;
  const Result r = solve_pgs(lcp, few);
  CHECK(r.status == Status::pivot_limit);
  CHECK(r.iterations == 2);
}

TEST_CASE("lcp fallback: a Lemke success is taken at once") {
  const Lcp lcp = read_siconos_lcp(lcp_data("contact/friction_m10_s2.dat"));
  const FallbackResult r = solve_with_fallbacks(lcp);
  CHECK(r.solved());
  CHECK(r.method == Method::lemke);
  CHECK(r.attempts.size() == 1);
  CHECK_FALSE(r.flagged);
}

TEST_CASE("lcp fallback: every step is tried and reported - PGS answers are flagged") {
  // A pivot limit too small for any Lemke step leaves PGS as the last resort.
  const Lcp lcp = read_siconos_lcp(lcp_data("contact/delassus_m50_s2.dat"));
  FallbackOptions options;
  options.lemke.max_pivots = 2;
  const FallbackResult r = solve_with_fallbacks(lcp, options);
  REQUIRE(r.attempts.size() == 4);
  CHECK(r.attempts[0].method == Method::lemke);
  CHECK(r.attempts[1].method == Method::lemke_other_covering);
  CHECK(r.attempts[2].method == Method::lemke_regularised);
  CHECK(r.attempts[3].method == Method::pgs);
  for (int k = 0; k < 3; ++k) CHECK(r.attempts[k].status == Status::pivot_limit);
  CHECK(r.solved());
  CHECK(r.method == Method::pgs);
  CHECK(r.flagged);
  check_complementary(lcp, r.result.z, 1e-8);

  options.allow_pgs = false;
  const FallbackResult without = solve_with_fallbacks(lcp, options);
  CHECK(without.attempts.size() == 3);
  CHECK_FALSE(without.solved());
  CHECK_FALSE(without.flagged);
}

TEST_CASE("lcp fallback: an infeasible LCP fails every step - the regularised one included") {
  // Copositive-plus and infeasible. M + delta I is positive definite, so the
  // regularised LCP has a solution, of order 1/delta: whether Lemke reaches it
  // within its tolerances or not, it must not pass on the ORIGINAL LCP.
  DenseMatrix M(2, 2);
  M << 1, -1, -1, 1;
  const Lcp lcp{M, Vector::Constant(2, -1.0)};
  const FallbackResult r = solve_with_fallbacks(lcp);
  REQUIRE(r.attempts.size() == 4);
  CHECK(r.attempts[0].status == Status::ray);
  CHECK(r.attempts[2].method == Method::lemke_regularised);
  CHECK(r.attempts[2].status != Status::solved);
  CHECK(r.attempts[2].residual > 1e-3);
  CHECK_FALSE(r.solved());
}

TEST_CASE("lcp contact-wise Gauss–Seidel: solves Stewart–Trinkle LCPs from zero and polishes a near solution") {
  // The friction_* problems (data/lcp/README.md): m contacts, mu = 0.5, the layout of
  // contact/impulse.hpp. Judged by check_complementary, which recomputes w = M z + q itself.
  for (const char* name : {"contact/friction_m10_s1.dat", "contact/friction_m100_s2.dat", "contact/friction_m200_s1.dat"}) {
    CAPTURE(name);
    const Lcp lcp = read_siconos_lcp(lcp_data(name));
    const FrictionLayout layout{static_cast<std::size_t>(lcp.size() / 4), 0.5};
    const Result r = solve_coulomb_gs(lcp, layout, Vector());
    REQUIRE(r.status == Status::solved);
    CHECK(r.residual <= 1e-9);
    check_complementary(lcp, r.z, 1e-8);
    // From Lemke's answer disturbed by 1e-6 (the state a failed final factorisation leaves):
    // back within tolerance in far fewer sweeps than from zero.
    const Result exact = solve_lemke(lcp);
    REQUIRE(exact.status == Status::solved);
    Vector start = exact.z;
    for (Index i = 0; i < start.size(); ++i) start(i) = std::max(0.0, start(i) + 1e-6 * std::sin(1.0 + static_cast<double>(i)));
    REQUIRE(residual(lcp, start) > 1e-8);
    const Result polished = solve_coulomb_gs(lcp, layout, start);
    REQUIRE(polished.status == Status::solved);
    CHECK(polished.iterations < r.iterations);
    MESSAGE("sweeps from zero " << r.iterations << ", from Lemke's answer disturbed " << polished.iterations);
    check_complementary(lcp, polished.z, 1e-8);
  }
  // A wrong layout is refused (a RunError: LCPs are built during a run), not answered.
  const Lcp lcp = read_siconos_lcp(lcp_data("contact/friction_m10_s1.dat"));
  CHECK_THROWS_AS(solve_coulomb_gs(lcp, FrictionLayout{11, 0.5}, Vector()), RunError);
}

TEST_CASE("lcp fallback: a Stewart–Trinkle LCP that Lemke cannot finish is answered by the contact-wise Gauss–Seidel") {
  const Lcp lcp = read_siconos_lcp(lcp_data("contact/friction_m100_s1.dat"));
  FallbackOptions options;
  options.lemke.max_pivots = 2;  // no Lemke step can finish
  options.friction = {static_cast<std::size_t>(lcp.size() / 4), 0.5};
  const FallbackResult r = solve_with_fallbacks(lcp, options);
  REQUIRE(r.attempts.size() == 2);  // Lemke, then the contact-wise Gauss–Seidel from where it stopped
  CHECK(r.attempts[0].status == Status::pivot_limit);
  CHECK(r.attempts[1].method == Method::coulomb_gs);
  CHECK(r.solved());
  CHECK(r.method == Method::coulomb_gs);
  CHECK_FALSE(r.flagged);  // accepted on the residual Lemke's answers are held to
  CHECK(r.result.residual <= options.accept_residual);
  check_complementary(lcp, r.result.z, 1e-8);
}

TEST_SUITE_END();

}  // namespace
}  // namespace floesim::lcp
