// The semismooth Newton method (contact/lcp/newton.hpp) on the LCP collections,
// its warm start, and its place in the fallback chain (fallback.hpp), with the
// chain's warm-started Lemke step. Every answer is checked by recomputing
// w = M z + q (lcp_checks.hpp), not by trusting the solver's status.
#include <doctest/doctest.h>

#include <fstream>
#include <string>
#include <vector>

#include "contact/lcp/fallback.hpp"
#include "contact/lcp/newton.hpp"
#include "contact/lcp/siconos_io.hpp"
#include "core/error.hpp"
#include "tests/contact/lcp_checks.hpp"

namespace floesim::lcp {
namespace {

TEST_SUITE_BEGIN("contact");

using testing::check_complementary;
using testing::lcp_data;
using testing::read_guess;

TEST_CASE("lcp newton: solves the frictionless contact LCPs of data/lcp from z = 0") {
  // Symmetric positive (semi)definite Delassus LCPs, 10 to 200 contacts, some
  // with redundant contacts (delassus_red_*): a few iterations each.
  for (const char* name : {"delassus_m10_s1", "delassus_m10_s2", "delassus_m50_s1", "delassus_m50_s2",
                           "delassus_m200_s1", "delassus_m200_s2", "delassus_red_m10_s1", "delassus_red_m10_s2",
                           "delassus_red_m50_s1", "delassus_red_m50_s2", "delassus_red_m200_s1",
                           "delassus_red_m200_s2"}) {
    CAPTURE(name);
    const Lcp lcp = read_siconos_lcp(lcp_data(std::string("contact/") + name + ".dat"));
    NewtonStats stats;
    const Result r = solve_newton(lcp, {}, &stats);
    REQUIRE(r.status == Status::solved);
    CHECK(r.residual <= 1e-9);
    CHECK(r.iterations <= 20);
    CHECK(stats.factorisations == r.iterations);
    check_complementary(lcp, r.z, 1e-9);
  }
}

TEST_CASE("lcp newton: the Siconos problems it solves including two where Lemke cannot or is slow") {
  // lcp_CPS_3: copositive, not copositive-plus; Lemke ends on a secondary ray
  // although a solution exists (data/lcp/README.md). lcp_exp_murty2: Murty's
  // example, 2^6 = 64 Lemke pivots.
  for (const char* name : {"lcp_CPS_1", "lcp_CPS_2", "lcp_CPS_3", "lcp_CPS_4", "lcp_CPS_5", "lcp_deudeu",
                           "lcp_ortiz", "lcp_trivial", "lcp_enum_fails", "lcp_exp_murty", "lcp_exp_murty2",
                           "lcp_mmc"}) {
    CAPTURE(name);
    const Lcp lcp = read_siconos_lcp(lcp_data(std::string("siconos/") + name + ".dat"));
    const Result r = solve_newton(lcp);
    REQUIRE(r.status == Status::solved);
    CHECK(r.residual <= 1e-9);
    CHECK(r.iterations <= 6);
    check_complementary(lcp, r.z, 1e-9);
  }
}

TEST_CASE("lcp newton: a warm start from the answer's active set solves in one iteration") {
  const Lcp lcp = read_siconos_lcp(lcp_data("contact/delassus_red_m200_s1.dat"));
  const Result cold = solve_newton(lcp);
  REQUIRE(cold.status == Status::solved);
  REQUIRE(cold.iterations > 1);
  NewtonOptions warm;
  warm.start = &cold.z_basic;
  const Result r = solve_newton(lcp, warm);
  REQUIRE(r.status == Status::solved);
  CHECK(r.iterations == 1);
  check_complementary(lcp, r.z, 1e-9);
}

TEST_CASE("lcp newton: its status agrees with the residual and a wrong-sized start is refused") {
  // Frictional contact (Stewart–Trinkle) LCPs: the method may not converge on
  // them (newton.hpp); whatever it returns, "solved" means within tolerance
  // and anything else is above it.
  for (const char* name : {"friction_m10_s1", "friction_m50_s1", "friction_m100_s1"}) {
    CAPTURE(name);
    const Lcp lcp = read_siconos_lcp(lcp_data(std::string("contact/") + name + ".dat"));
    const Result r = solve_newton(lcp);
    CHECK(r.z.size() == lcp.size());
    CHECK(r.z.minCoeff() >= 0.0);
    CHECK(r.residual == doctest::Approx(residual(lcp, r.z)).epsilon(1e-12));
    if (r.status == Status::solved) CHECK(r.residual <= 1e-9);
    else CHECK(r.residual > 1e-9);
  }
  const Lcp lcp = read_siconos_lcp(lcp_data("contact/delassus_m10_s1.dat"));
  const std::vector<std::uint8_t> short_start(3, 1);
  NewtonOptions bad;
  bad.start = &short_start;
  CHECK_THROWS_AS(solve_newton(lcp, bad), RunError);
  NewtonOptions bad_point;
  bad_point.start_point = Vector::Zero(4);
  CHECK_THROWS_AS(solve_newton(lcp, bad_point), RunError);
}

TEST_CASE("lcp fallback: Newton first from newton_min_size unknowns, Lemke after it when it fails") {
  FallbackOptions options;
  options.newton_min_size = 100;
  // Below the size: Lemke alone.
  const FallbackResult small = solve_with_fallbacks(read_siconos_lcp(lcp_data("contact/delassus_m50_s1.dat")), options);
  REQUIRE(small.attempts.size() == 1);
  CHECK(small.method == Method::lemke);
  // Frictionless, 200 unknowns: Newton's answer is taken.
  const Lcp delassus = read_siconos_lcp(lcp_data("contact/delassus_m200_s1.dat"));
  const FallbackResult d = solve_with_fallbacks(delassus, options);
  REQUIRE(d.solved());
  CHECK(d.method == Method::newton);
  CHECK(d.attempts.size() == 1);
  check_complementary(delassus, d.result.z, 1e-9);
  // Frictional, 400 unknowns: Newton stops at its limit, Lemke solves it.
  const Lcp friction = read_siconos_lcp(lcp_data("contact/friction_m100_s1.dat"));
  const FallbackResult f = solve_with_fallbacks(friction, options);
  REQUIRE(f.solved());
  REQUIRE(f.attempts.size() == 2);
  CHECK(f.attempts[0].method == Method::newton);
  CHECK(f.attempts[0].status != Status::solved);
  CHECK(f.method == Method::lemke);
  check_complementary(friction, f.result.z, 1e-9);
}

TEST_CASE("lcp fallback: a warm-started Lemke is tried first and redone from scratch when it fails") {
  const Lcp lcp = read_siconos_lcp(lcp_data("contact/friction_m50_s1.dat"));
  const FallbackResult cold = solve_with_fallbacks(lcp);
  REQUIRE(cold.solved());
  // From the answer's own basis: a handful of pivots (z0 entering and leaving,
  // degenerate rows), against 135 from scratch.
  FallbackOptions warm;
  warm.lemke.start = &cold.result.z_basic;
  const FallbackResult w = solve_with_fallbacks(lcp, warm);
  REQUIRE(w.solved());
  CHECK(w.method == Method::lemke_warm);
  CHECK(w.attempts.size() == 1);
  CHECK(w.result.pivots * 10 < cold.result.pivots);
  // Every beta+ and beta- basic together: a singular start, then Lemke from scratch.
  std::vector<std::uint8_t> singular(static_cast<std::size_t>(lcp.size()), 1);
  warm.lemke.start = &singular;
  const FallbackResult s = solve_with_fallbacks(lcp, warm);
  REQUIRE(s.solved());
  REQUIRE(s.attempts.size() == 2);
  CHECK(s.attempts[0].method == Method::lemke_warm);
  CHECK(s.attempts[0].status != Status::solved);
  CHECK(s.method == Method::lemke);
  CHECK(s.result.pivots == cold.result.pivots);
}

TEST_CASE("lcp fallback: a jam LCP of 1400 unknowns is solved from its warm start with Newton or without") {
  // data/lcp/jam: an LCP of bench jam_500 and the warm start the contact
  // layer gave it. Newton does not converge on it (docs/contact.md, "Jam
  // solver"); the chain goes on to Lemke from the warm start.
  const Lcp lcp = read_siconos_lcp(lcp_data("jam/jam500_n1400.dat"));
  REQUIRE(lcp.size() == 1400);
  const std::vector<std::uint8_t> guess = read_guess(lcp_data("jam/jam500_n1400.guess"));
  REQUIRE(guess.size() == 1400);
  for (const Index newton_min_size : {Index{0}, Index{1000}}) {
    CAPTURE(newton_min_size);
    FallbackOptions options;
    options.newton_min_size = newton_min_size;
    options.newton.start = &guess;
    options.lemke.start = &guess;
    options.lemke.max_pivots = 15 * 1400 + 1000;  // the collision LCPs' limit (contact/impulse.hpp)
    const FallbackResult r = solve_with_fallbacks(lcp, options);
    REQUIRE(r.solved());
    CHECK(r.method == Method::lemke_warm);
    CHECK(r.result.residual <= 1e-9);
    CHECK(r.attempts.size() == (newton_min_size > 0 ? 2u : 1u));
    check_complementary(lcp, r.result.z, 1e-9);
  }
}

TEST_CASE("lcp fallback: a warm start that ends on a ray is followed by Lemke from its normal flags") {
  // data/lcp/jam/jam500_n864_ray: an LCP of bench jam_500 whose warm start
  // ends on a secondary ray after 2 pivots. The chain then starts Lemke
  // from the start's normal flags alone (Method::lemke_warm_normal), which
  // solves it in fewer pivots than Lemke from scratch (391 against 602,
  // measured); without that step the chain goes on from scratch.
  const Lcp lcp = read_siconos_lcp(lcp_data("jam/jam500_n864_ray.dat"));
  REQUIRE(lcp.size() == 864);
  const std::vector<std::uint8_t> guess = read_guess(lcp_data("jam/jam500_n864_ray.guess"));
  REQUIRE(guess.size() == 864);
  long pivots[2] = {0, 0};
  for (const bool retry : {true, false}) {
    CAPTURE(retry);
    FallbackOptions options;
    options.friction = {216, 0.7};
    options.lemke.start = &guess;
    options.lemke.max_pivots = 15 * 864 + 1000;  // the collision LCPs' limit (contact/impulse.hpp)
    options.warm_normal_retry = retry;
    const FallbackResult r = solve_with_fallbacks(lcp, options);
    REQUIRE(r.solved());
    REQUIRE(r.attempts.size() == 2u);
    CHECK(r.attempts[0].method == Method::lemke_warm);
    CHECK(r.attempts[0].status != Status::solved);
    CHECK(r.method == (retry ? Method::lemke_warm_normal : Method::lemke));
    CHECK(r.result.residual <= 1e-9);
    check_complementary(lcp, r.result.z, 1e-9);
    pivots[retry ? 0 : 1] = r.attempts[1].pivots;
  }
  CHECK(pivots[0] < pivots[1]);
}

TEST_SUITE_END();

}  // namespace
}  // namespace floesim::lcp
