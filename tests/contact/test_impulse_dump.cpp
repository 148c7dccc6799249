// [contact] dump_failed_lcps (contact/impulse.hpp): an LCP the fallback chain
// does not solve is written in the Siconos format, and the file is that LCP:
// read back, it has the collision LCP's size (4 unknowns per contact) and the
// default Lemke solves it. A share of the step-start collisions (a rank's
// part, contact::resolve_step_collisions_share) writes no dump: it reports
// the failure, and the whole solve that follows numbers the run's dumps; so
// does a share of the advance (contact::ShareAdvance).
#include <doctest/doctest.h>

#include <filesystem>
#include <string>
#include <unistd.h>

#include "contact/detection.hpp"
#include "contact/impulse.hpp"
#include "contact/lcp/lemke.hpp"
#include "contact/lcp/siconos_io.hpp"
#include "contact/substep.hpp"

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

// A chain that cannot succeed: one pivot for Lemke (it needs at least two),
// no Gauss–Seidel sweep, no projected Gauss–Seidel, no velocity tolerance.
void make_fail(contact::ImpulseOptions& o) {
  o.solver.lemke.max_pivots = 1;
  o.solver.coulomb_gs.max_sweeps = 0;
  o.solver.allow_pgs = false;
  o.velocity_tolerance = 0.0;
}

Floes two_squares() {
  Floes f;
  for (const FloeInput& in : {square(0.0, 10.0, {0.5, 0.0}), square(10.005, 10.0, {-0.3, 0.0})})
    f.add(make_floe_shape(in), in);
  return f;
}

fs::path fresh_dir(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / (name + "_" + std::to_string(getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

}  // namespace

TEST_CASE("impulse: a failed collision LCP is written to dump_failed_lcps and reads back solvable") {
  Floes f = two_squares();
  const contact::Detection det = contact::detect(f, contact::build_collision_shapes(f), {});
  REQUIRE(!det.contacts.empty());
  const fs::path dir = fresh_dir("floesim_dump_test");

  contact::ImpulseOptions o;
  o.friction = 0.7;
  o.dump_failed_lcps = dir.string();
  make_fail(o);
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

TEST_CASE("impulse: a rank's share of the step-start collisions dumps no failed LCP, the whole solve after it does") {
  const Floes start = two_squares();
  const contact::Detection det = contact::detect(start, contact::build_collision_shapes(start), {});
  REQUIRE(!det.contacts.empty());
  const fs::path dir = fresh_dir("floesim_share_dump_test");
  contact::ImpulseOptions o;
  o.friction = 0.7;
  o.dump_failed_lcps = dir.string();
  make_fail(o);
  const std::vector<int> owner(start.size(), 0);

  Floes f = start;
  contact::CollisionStats stats;
  const contact::StepCollisionShare share =
      contact::resolve_step_collisions_share(f, start.state, det, 0.1, o, contact::ClusterShare{owner, 0}, stats);
  CHECK(share.conflict == contact::StepCollisionShare::Conflict::failed_lcp);
  CHECK(stats.failures == 1);
  CHECK(fs::is_empty(dir));  // the share's failure count starts at zero: its dump would overwrite the run's

  // The fallback: the whole solve on the run's count writes the dump.
  f = start;
  contact::CollisionStats whole;
  contact::resolve_step_collisions(f, start.state, det, 0.1, o, whole);
  CHECK(whole.failures == 1);
  CHECK(fs::exists(dir / "failed_lcp_1.dat"));
  fs::remove_all(dir);
}

TEST_CASE("impulse: a rank's share of the advance dumps no failed LCP, the whole advance after it does") {
  // Two squares 1 m apart closing at 1 m/s come within xi = 1 cm near the
  // end of the 0.997 s step: the advance sub-steps them to the collision,
  // whose LCP fails; what they close after it leaves them apart.
  Floes start;
  for (const FloeInput& in : {square(0.0, 10.0, {0.5, 0.0}), square(11.0, 10.0, {-0.5, 0.0})})
    start.add(make_floe_shape(in), in);
  const contact::CollisionShapes shapes = contact::build_collision_shapes(start);
  contact::DetectionOptions d;
  d.reach.assign(start.size(), 2.0);
  const contact::Detection det = contact::detect(start, shapes, d);
  REQUIRE(!det.pairs.empty());
  REQUIRE(det.contacts.empty());
  const fs::path dir = fresh_dir("floesim_advance_dump_test");
  contact::SubstepOptions o;
  o.impulse.friction = 0.7;
  o.impulse.dump_failed_lcps = dir.string();
  make_fail(o.impulse);
  const std::vector<int> owner(start.size(), 0);

  Floes f = start;
  {
    contact::ShareAdvance share(f, shapes, det, 0.997, o, contact::ClusterShare{owner, 0});
    const contact::ShareRooms rooms = share.rooms();
    REQUIRE(rooms.conflict == contact::ShareOutcome::Conflict::none);
    const contact::ShareOutcome out = share.advance(rooms);
    CHECK(out.conflict == contact::ShareOutcome::Conflict::failed_lcp);
    CHECK(share.stats().failures >= 1);
  }
  CHECK(fs::is_empty(dir));

  f = start;
  contact::CollisionStats stats;
  contact::SubstepReport report;
  contact::advance_with_collisions(f, shapes, det, 0.997, o, stats, report);
  CHECK(stats.failures >= 1);
  CHECK(fs::exists(dir / "failed_lcp_1.dat"));
  fs::remove_all(dir);
}

TEST_SUITE_END();
