// Floe construction: validation and exact mass properties.
#include <doctest/doctest.h>

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "core/floes.hpp"

using namespace floesim;

TEST_SUITE_BEGIN("core");

namespace {
FloeInput rect(double w, double h, double thick = 2.0, double rho = 900.0) {
  FloeInput f;
  f.vertices = {{10, 20}, {10 + w, 20}, {10 + w, 20 + h}, {10, 20 + h}};
  f.thickness = thick;
  f.density = rho;
  f.origin = "test floe";
  return f;
}
}  // namespace

TEST_CASE("rectangular floe: mass, inertias and body frame are exact") {
  // w x l rectangle, thickness t, density rho: M = rho t w l,
  // I_z = M (w² + l²)/12, I_x (roll) = M l²/12 + M t²/12, I_y = M w²/12 + M t²/12.
  const double w = 4.0, l = 6.0, t = 2.0, rho = 900.0;
  const FloeShape s = make_floe_shape(rect(w, l, t, rho));
  const double M = rho * t * w * l;
  CHECK(s.props.area == doctest::Approx(w * l));
  CHECK(s.props.mass == doctest::Approx(M));
  CHECK(s.props.inertia_z == doctest::Approx(M * (w * w + l * l) / 12));
  CHECK(s.props.inertia_x == doctest::Approx(M * l * l / 12 + M * t * t / 12));
  CHECK(s.props.inertia_y == doctest::Approx(M * w * w / 12 + M * t * t / 12));
  CHECK(s.centroid.x() == doctest::Approx(12.0));
  CHECK(s.centroid.y() == doctest::Approx(23.0));
  CHECK(s.body[0].x() == doctest::Approx(-2.0));
  CHECK(s.body[0].y() == doctest::Approx(-3.0));
  CHECK_FALSE(s.reoriented);
}

TEST_CASE("clockwise input is reoriented and keeps its properties") {
  FloeInput f = rect(4, 6);
  std::reverse(f.vertices.begin(), f.vertices.end());
  const FloeShape s = make_floe_shape(f);
  CHECK(s.reoriented);
  CHECK(s.props.area == doctest::Approx(24.0));
  CHECK(signed_area(s.body) > 0.0);
}

TEST_CASE("pack-style input: body vertices, position and yaw") {
  FloeInput f;
  f.vertices = {{0, 0}, {2, 0}, {2, 2}, {0, 2}};  // centroid (1, 1) in the input frame
  f.position = {100, 50};
  f.yaw = std::numbers::pi / 2;
  const FloeShape s = make_floe_shape(f);
  // world centroid = position + R(90°) (1, 1) = (99, 51)
  CHECK(s.centroid.x() == doctest::Approx(99.0));
  CHECK(s.centroid.y() == doctest::Approx(51.0));
}

TEST_CASE("bad floes are refused with a message naming the floe") {
  auto refused = [](FloeInput f, const std::string& fragment) {
    try {
      make_floe_shape(f);
    } catch (const InputError& e) {
      const std::string m = e.what();
      CHECK(m.find("test floe") != std::string::npos);
      CHECK_MESSAGE(m.find(fragment) != std::string::npos, m);
      return;
    }
    FAIL("accepted a bad floe: " << fragment);
  };
  FloeInput two = rect(1, 1);
  two.vertices.resize(2);
  refused(two, "at least 3 vertices");
  FloeInput line = rect(1, 1);
  line.vertices = {{0, 0}, {1, 1}, {2, 2}};
  refused(line, "zero area");
  FloeInput nan = rect(1, 1);
  nan.vertices[1].x() = std::numeric_limits<double>::quiet_NaN();
  refused(nan, "not a finite number");
  FloeInput bow = rect(1, 1);
  bow.vertices = {{0, 0}, {1, 1}, {1, 0}, {0, 1}};
  refused(bow, "intersects itself");
  refused(rect(1, 1, 0.0), "thickness");
  refused(rect(1, 1, 1.0, -1.0), "density");
  // Finite but absurd: refused for what they are (a 1e300 square's area
  // overflows to inf and used to be called "zero area").
  FloeInput huge = rect(1, 1);
  for (Vec2& p : huge.vertices) p *= 1e300;
  refused(huge, "coordinates too large");
  FloeInput far = rect(1, 1);
  far.position = {0.0, 2e9};
  refused(far, "coordinates too large");
  FloeInput fast = rect(1, 1);
  fast.velocity = {2e130, 0.0};
  refused(fast, "speed |velocity| = 2e+130 m/s is not physical");
  FloeInput bobbing = rect(1, 1);
  bobbing.heave_rate = -2e3;
  refused(bobbing, "heave_rate");
  // The spin bound is on the rim speed: 10 rad/s is fine on a 1 m floe, not on a 1 km one.
  FloeInput spin = rect(1, 1);
  spin.angular_velocity = 10.0;
  CHECK_NOTHROW(make_floe_shape(spin));
  FloeInput big_spin = rect(1000, 1000);
  big_spin.angular_velocity = 10.0;
  refused(big_spin, "rim speed");
  FloeInput drifting = rect(1, 1);
  drifting.velocity = {600.0, 0.0};  // within kMaxSpeed
  CHECK_NOTHROW(make_floe_shape(drifting));
}

TEST_CASE("Floes: contiguous storage, static floes have zero inverse mass") {
  Floes floes;
  FloeInput a = rect(2, 2), b = rect(3, 1);
  b.is_static = true;
  b.velocity = {1.0, 0.0};  // ignored for an obstacle
  floes.add(make_floe_shape(a), a);
  floes.add(make_floe_shape(b), b);
  REQUIRE(floes.size() == 2);
  CHECK(floes.vertices(1).size() == 4);
  CHECK(floes.offsets.back() == floes.body.size());
  CHECK(floes.inv_mass(0) == doctest::Approx(1.0 / floes.mass[0]));
  CHECK(floes.inv_mass(1) == 0.0);
  CHECK(floes.inv_inertia_z(1) == 0.0);
  CHECK(floes.state[1].vx == 0.0);
  CHECK(floes.draft(0, 1000.0) == doctest::Approx(900.0 * 2.0 / 1000.0));
  const auto w = floes.world_vertices(0);
  CHECK(w[0].x() == doctest::Approx(10.0));
  CHECK(w[0].y() == doctest::Approx(20.0));
}

// Issue 17: `Scenario s{config, {}, make_forcing(...)}` aborted with a double free
// when the forcing reader threw, GCC 12 destroying the `{}`-initialised Floes twice
// (an aggregate with default member initialisers). Floes has a constructor now.
TEST_CASE("an aggregate holding Floes{} is cleaned up once when a later member throws") {
  struct Holder {
    std::string name;
    Floes floes;
    std::vector<double> after;
  };
  auto throws = []() -> std::vector<double> { throw InputError("bad input"); };
  CHECK_THROWS_AS((Holder{std::string(100, 'a'), {}, throws()}), InputError);
}

TEST_SUITE_END();
