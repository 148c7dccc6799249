// [contact] dump_failed_lcps (contact/impulse.hpp): an LCP the fallback chain
// does not solve is written in the Siconos format, and the file is that LCP:
// read back, it has the collision LCP's size (4 unknowns per contact) and the
// default Lemke solves it.
#include <doctest/doctest.h>

#include <filesystem>
#include <string>
#include <unistd.h>

#include "contact/detection.hpp"
#include "contact/impulse.hpp"
#include "contact/lcp/lemke.hpp"
#include "contact/lcp/siconos_io.hpp"

using namespace floesim;
namespace fs = std::filesystem;

TEST_SUITE_BEGIN("contact");

namespace {

FloeInput square(double cx, double side, Vec2 velocity) {
  FloeInput f;
  const double h = side / 2;
  f.vertices = {{cx - h, -h}, {cx + h, -h}, {cx + h, h}, {cx - h, h}};
  f.velocity = velocity;
  return f;
}

}  // namespace

TEST_CASE("impulse: a failed collision LCP is written to dump_failed_lcps and reads back solvable") {
  Floes f;
  for (const FloeInput& in : {square(0.0, 10.0, {0.5, 0.0}), square(10.005, 10.0, {-0.3, 0.0})})
    f.add(make_floe_shape(in), in);
  const contact::Detection det = contact::detect(f, contact::build_collision_shapes(f), {});
  REQUIRE(!det.contacts.empty());
  const fs::path dir = fs::temp_directory_path() / ("floesim_dump_test_" + std::to_string(getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);

  contact::ImpulseOptions o;
  o.friction = 0.7;
  o.dump_failed_lcps = dir.string();
  // A chain that cannot succeed: one pivot for Lemke (it needs at least two),
  // no Gauss–Seidel sweep, no projected Gauss–Seidel, no velocity tolerance.
  o.solver.lemke.max_pivots = 1;
  o.solver.coulomb_gs.max_sweeps = 0;
  o.solver.allow_pgs = false;
  o.velocity_tolerance = 0.0;
  contact::CollisionStats stats;
  const double vx0 = f.state[0].vx;
  contact::resolve_collisions(f, det.contacts, o, stats);
  REQUIRE(stats.failures == 1);
  CHECK(f.state[0].vx == vx0);  // a failed solve leaves the velocities alone

  const fs::path file = dir / "failed_lcp_1.dat";
  REQUIRE(fs::exists(file));
  const lcp::Lcp back = lcp::read_siconos_lcp(file.string());
  CHECK(back.size() == static_cast<lcp::Index>(4 * det.contacts.size()));
  CHECK(back.q.minCoeff() < 0.0);  // the approach: something to solve
  const lcp::Result r = lcp::solve_lemke(back);
  CHECK(r.status == lcp::Status::solved);
  CHECK(r.residual <= 1e-9);
  fs::remove_all(dir);
}

TEST_SUITE_END();
