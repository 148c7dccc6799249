// The contact Newton method (contact/lcp/contact_newton.hpp) on the
// Stewart–Trinkle LCPs of data/lcp, its warm start and its place in the
// fallback chain; the repair of a singular Lemke start basis
// (basis_repair.hpp). Answers are checked by recomputing w = M z + q
// (lcp_checks.hpp) and, independently of the LCP's encoding, against
// Signorini's and Coulomb's laws per contact in the contact form.
#include <doctest/doctest.h>

#include <cmath>
#include <string>
#include <vector>

#include "contact/lcp/basis_repair.hpp"
#include "contact/lcp/contact_newton.hpp"
#include "contact/lcp/fallback.hpp"
#include "contact/lcp/lemke.hpp"
#include "contact/lcp/siconos_io.hpp"
#include "core/error.hpp"
#include "tests/contact/lcp_checks.hpp"

namespace floesim::lcp {
namespace {

TEST_SUITE_BEGIN("contact");

using testing::check_complementary;
using testing::lcp_data;

// data/lcp/contact/friction_*: m = n / 4 contacts, mu = 0.5 (data/lcp/README.md).
FrictionLayout layout_of(const Lcp& lcp, double mu) { return {static_cast<std::size_t>(lcp.size() / 4), mu}; }

// Signorini and Coulomb per contact at the impulses of z, to `tol` (relative to
// the largest impulse and velocity).
void check_coulomb(const Lcp& lcp, const FrictionLayout& layout, const Vector& z, double tol) {
  const ContactForm f = contact_form(lcp, layout, "test");
  const Vector r = contact_impulses(z, layout.contacts);
  const Vector u = f.W * r + f.b;
  const double rs = std::max(1.0, r.cwiseAbs().maxCoeff()), us = std::max(1.0, u.cwiseAbs().maxCoeff());
  const double mu = layout.friction;
  for (Index k = 0; k < static_cast<Index>(layout.contacts); ++k) {
    CAPTURE(k);
    const double l = r(2 * k), b = r(2 * k + 1), un = u(2 * k), ut = u(2 * k + 1);
    CHECK(l >= 0.0);
    CHECK(un >= -tol * us);
    CHECK(std::min(l / rs, un / us) <= tol);       // no force on a separating contact
    CHECK(std::abs(b) <= mu * l + tol * rs);       // inside the cone
    if (std::abs(ut) > tol * us) CHECK(b * ut <= 0.0);  // sliding: friction opposes it...
    if (std::abs(ut) > tol * us) CHECK(std::abs(std::abs(b) - mu * l) <= tol * rs);  // ...at the cone's edge
  }
}

const char* const kFriction[] = {"friction_m10_s1",  "friction_m10_s2",  "friction_m50_s1",  "friction_m50_s2",
                                 "friction_m100_s1", "friction_m100_s2", "friction_m200_s1", "friction_m200_s2"};

TEST_CASE("lcp contact newton: solves every friction LCP of data/lcp from z = 0") {
  // The LCP Newton method (newton.hpp) solves 3 of these 8 from z = 0
  // (docs/contact.md); choosing states per contact solves all of them.
  for (const char* name : kFriction) {
    CAPTURE(name);
    const Lcp lcp = read_siconos_lcp(lcp_data(std::string("contact/") + name + ".dat"));
    const FrictionLayout layout = layout_of(lcp, 0.5);
    ContactNewtonStats stats;
    const Result r = solve_contact_newton(lcp, layout, {}, &stats);
    REQUIRE(r.status == Status::solved);
    CHECK(r.residual <= 1e-9);
    CHECK(r.iterations == stats.solves);
    CHECK(stats.factorisations <= stats.solves);
    check_complementary(lcp, r.z, 1e-9);
    check_coulomb(lcp, layout, r.z, 1e-8);
  }
}

TEST_CASE("lcp contact newton: started from the states of its own answer it needs at most two solves") {
  // The right states give the answer in one solve (up to the proximal
  // centre's convergence on redundant directions).
  const Lcp lcp = read_siconos_lcp(lcp_data("contact/friction_m100_s1.dat"));
  const FrictionLayout layout = layout_of(lcp, 0.5);
  const Result cold = solve_contact_newton(lcp, layout);
  REQUIRE(cold.status == Status::solved);
  ContactNewtonOptions warm;
  warm.start = &cold.z_basic;
  warm.proximal_start = warm.proximal;
  const Result r = solve_contact_newton(lcp, layout, warm);
  REQUIRE(r.status == Status::solved);
  CHECK(r.iterations <= 2);
  check_complementary(lcp, r.z, 1e-9);
}

TEST_CASE("lcp contact newton: its status agrees with the residual on a jam LCP; wrong inputs are refused") {
  // data/lcp/jam/jam500_n1400: 350 contacts, friction 0.7. It may or may not
  // converge within its limit (docs/contact.md); "solved" must mean within tolerance.
  const Lcp lcp = read_siconos_lcp(lcp_data("jam/jam500_n1400.dat"));
  const FrictionLayout layout{350, 0.7};
  const Result r = solve_contact_newton(lcp, layout);
  CHECK((r.status == Status::solved) == (r.residual <= 1e-9));
  CHECK((r.z.array() >= 0.0).all());
  CHECK(r.z_basic.size() == static_cast<std::size_t>(lcp.size()));
  CHECK_THROWS_AS(solve_contact_newton(lcp, {349, 0.7}), RunError);
  ContactNewtonOptions bad;
  const std::vector<std::uint8_t> short_start(10, 1);
  bad.start = &short_start;
  CHECK_THROWS_AS(solve_contact_newton(lcp, layout, bad), RunError);
}

TEST_CASE("lcp fallback: the contact Newton step runs only when asked and for friction LCPs") {
  const Lcp lcp = read_siconos_lcp(lcp_data("contact/friction_m50_s1.dat"));
  FallbackOptions options;
  options.friction = layout_of(lcp, 0.5);
  // Off by default: Lemke alone.
  const FallbackResult off = solve_with_fallbacks(lcp, options);
  REQUIRE(off.solved());
  CHECK(off.method == Method::lemke);
  options.contact_newton_min_size = 100;
  const FallbackResult on = solve_with_fallbacks(lcp, options);
  REQUIRE(on.solved());
  CHECK(on.method == Method::contact_newton);
  CHECK(on.attempts.size() == 1);
  check_complementary(lcp, on.result.z, 1e-9);
  // A failing contact Newton step hands over to Lemke.
  options.contact_newton.max_iterations = 1;
  const FallbackResult short_run = solve_with_fallbacks(lcp, options);
  REQUIRE(short_run.solved());
  CHECK(short_run.attempts.front().method == Method::contact_newton);
  CHECK(short_run.attempts.front().status != Status::solved);
  CHECK(short_run.method == Method::lemke);
}

TEST_CASE("lcp basis repair: a singular warm start is repaired and Lemke solves from it") {
  // delassus_red_m50: a Delassus matrix of rank about 3/4 of its size
  // (redundant contacts). All z's basic is a singular start basis; its repair
  // keeps a maximal independent set of columns.
  const Lcp lcp = read_siconos_lcp(lcp_data("contact/delassus_red_m50_s1.dat"));
  const std::vector<std::uint8_t> all(static_cast<std::size_t>(lcp.size()), 1);
  LemkeOptions plain;
  plain.start = &all;
  const Result failed = solve_lemke(lcp, plain);
  CHECK(failed.status == Status::failed);
  CHECK(failed.pivots == 0);
  long dropped = 0;
  const std::vector<std::uint8_t> repaired = repair_basis(sparse_copy(lcp), all, {}, &dropped);
  CHECK(dropped > 0);
  CHECK(dropped < lcp.size());
  LemkeOptions fixed = plain;
  fixed.repair_start.rounds = 3;
  const Result r = solve_lemke(lcp, fixed);
  REQUIRE(r.status == Status::solved);
  check_complementary(lcp, r.z, 1e-9);
  // A nonsingular start is left alone.
  const std::vector<std::uint8_t> none(static_cast<std::size_t>(lcp.size()), 0);
  CHECK(repair_basis(sparse_copy(lcp), none) == none);
}

TEST_SUITE_END();

}  // namespace
}  // namespace floesim::lcp
