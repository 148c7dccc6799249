// Unit tests of the drawing layer (apps/viz): tick arithmetic, colour maps,
// sizes, and the canvas primitives the pictures rely on.
#include <doctest/doctest.h>

#include <cmath>

#include "apps/viz/canvas.hpp"
#include "apps/viz/colormap.hpp"
#include "apps/viz/frame.hpp"
#include "apps/viz/plot.hpp"
#include "apps/viz/size.hpp"
#include "core/error.hpp"

using namespace floesim::viz;

TEST_CASE("nice ticks cover the data with 1, 2 or 5 times a power of ten") {
  const double cases[][2] = {{0, 1}, {-0.249, 0.249}, {3.2e6, 6.3e6}, {1e-7, 9e-7}, {-17, 1234}, {5, 5}, {0, 0}};
  for (const auto& c : cases) {
    const auto t = nice_ticks(c[0], c[1], 5);
    REQUIRE(t.size() >= 2);
    CHECK(t.front() <= c[0]);
    CHECK(t.back() >= c[1]);
    const double step = t[1] - t[0];
    const double m = step / std::pow(10.0, std::floor(std::log10(step) + 1e-9));
    CHECK((std::abs(m - 1) < 1e-9 || std::abs(m - 2) < 1e-9 || std::abs(m - 5) < 1e-9));
    for (std::size_t k = 1; k < t.size(); ++k) CHECK(t[k] - t[k - 1] == doctest::Approx(step));
    CHECK(t.size() <= 12);
  }
  CHECK(nice_ticks(0, 0).front() == 0.0);  // a zero counter: [0, 1], not below zero
  CHECK(nice_ticks(0, 0).back() == 1.0);
}

TEST_CASE("tick labels tell ticks apart in one notation") {
  CHECK(tick_labels({0, 0.5, 1.0}) == std::vector<std::string>{"0.0", "0.5", "1.0"});
  CHECK(tick_labels({0, 200, 400}) == std::vector<std::string>{"0", "200", "400"});
  CHECK(tick_labels({0, 1e6, 2e6}) == std::vector<std::string>{"0e+00", "1e+06", "2e+06"});
  CHECK(tick_labels({5e5, 1e6}) == std::vector<std::string>{"5.0e+05", "1.0e+06"});
  CHECK(tick_labels({-0.2, 0.0, 0.2}) == std::vector<std::string>{"-0.2", "0.0", "0.2"});
}

TEST_CASE("colour maps interpolate between their anchors and clamp") {
  const ColorMap& m = sea_map();
  const Rgb lo = m(0), hi = m(1), mid = m(0.5);
  CHECK(lo.r == m.anchors().front().r);
  CHECK(hi.b == m.anchors().back().b);
  // Halfway between anchors 1 and 2 of 4.
  CHECK(mid.g == doctest::Approx(0.5 * (m.anchors()[1].g + m.anchors()[2].g)));
  CHECK(m(-3).r == lo.r);
  CHECK(m(7).r == hi.r);
  CHECK(m(NAN).r == 0.5);
  // The sea map gets lighter from trough to crest (crests read without the legend).
  double last = -1;
  for (int k = 0; k <= 20; ++k) {
    const Rgb c = m(k / 20.0);
    const double lightness = c.r + c.g + c.b;
    CHECK(lightness > last);
    last = lightness;
  }
}

TEST_CASE("value ranges: positive from zero, symmetric about zero, never empty") {
  CHECK(positive_range({0.5, 2.0, NAN}).hi == 2.0);
  CHECK(positive_range({0.0}).hi == 1.0);
  const Range s = symmetric_range({-0.3, 0.1, INFINITY});
  CHECK(s.lo == -0.3);
  CHECK(s.hi == 0.3);
  CHECK(s.normalise(0.0) == doctest::Approx(0.5));
}

TEST_CASE("picture sizes") {
  CHECK(parse_size("1280x720", "--size") == std::pair{1280, 720});
  CHECK_THROWS_AS(parse_size("1280", "--size"), floesim::InputError);
  CHECK_THROWS_AS(parse_size("12x720", "--size"), floesim::InputError);
  CHECK_THROWS_AS(parse_size("1280x720px", "--size"), floesim::InputError);
}

TEST_CASE("canvas: a filled polygon covers its inside and not its outside") {
  Canvas c(100, 80);
  const Point tri[] = {{10, 10}, {90, 10}, {10, 70}};
  c.polygon(tri, {1, 0, 0}, {0, 0, 0}, 0.0);
  CHECK(c.pixel(20, 20).r == 1.0);
  CHECK(c.pixel(20, 20).g == 0.0);
  CHECK(c.pixel(80, 60).g == 1.0);  // outside: still white
  // An image stretched onto a rectangle, nearest pixel: left half black, right half white.
  const std::uint32_t px[] = {0x000000, 0xffffff};
  c.image(px, 2, 1, {0, 0, 100, 80}, false);
  CHECK(c.pixel(10, 40).r == 0.0);
  CHECK(c.pixel(90, 40).r == 1.0);
}

TEST_CASE("frame layout keeps the world's aspect ratio") {
  FrameScales sc;
  sc.xmin = 0, sc.xmax = 200, sc.ymin = 0, sc.ymax = 100;
  const FrameLayout lay = frame_layout(1280, 720, sc);
  CHECK(lay.map.w / lay.map.h == doctest::Approx(2.0));
  CHECK(lay.map.x + lay.map.w < 1280);
  const Point corner = lay.to_pixel(200, 0);
  CHECK(corner.x == doctest::Approx(lay.map.x + lay.map.w));
  CHECK(corner.y == doctest::Approx(lay.map.y + lay.map.h));
}
