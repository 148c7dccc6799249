// Random packs: floes valid, convex, inside the box, pairwise disjoint with the
// requested gap (checked here by brute force, independently of the generator's
// own sweep), concentration as asked, deterministic for a seed, sizes following
// the requested law (power-law exponent recovered by maximum likelihood).
#include <doctest/doctest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <numeric>

#include "core/convex_partition.hpp"
#include "core/error.hpp"
#include "core/pack.hpp"
#include "core/pack_generator.hpp"

using namespace floesim;

namespace {

using Polygon = std::vector<Vec2>;

std::vector<Polygon> world_polygons(const Floes& f) {
  std::vector<Polygon> out;
  for (std::size_t i = 0; i < f.size(); ++i) out.push_back(f.world_vertices(i));
  return out;
}

// Separating-axis theorem for two convex CCW polygons: the largest separation
// along an edge normal of either. > 0 means disjoint (the polygons do not even
// touch); <= 0 means they overlap or touch.
double separation(const Polygon& a, const Polygon& b) {
  double best = -std::numeric_limits<double>::infinity();
  for (int pass = 0; pass < 2; ++pass) {
    const Polygon& p = pass ? b : a;
    const Polygon& q = pass ? a : b;
    for (std::size_t k = 0; k < p.size(); ++k) {
      const Vec2 e = p[(k + 1) % p.size()] - p[k];
      const Vec2 n = Vec2(e.y(), -e.x()).normalized();  // outward for CCW
      double lo = std::numeric_limits<double>::infinity();
      for (const Vec2& v : q) lo = std::min(lo, n.dot(v - p[k]));
      best = std::max(best, lo);
    }
  }
  return best;
}

double segment_distance(const Vec2& p, const Vec2& a, const Vec2& b) {
  const Vec2 ab = b - a;
  const double t = std::clamp((p - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0);
  return (p - a - t * ab).norm();
}

// Distance of two disjoint polygons, brute force over vertex–edge pairs.
double distance(const Polygon& a, const Polygon& b) {
  double d = std::numeric_limits<double>::infinity();
  for (const Vec2& p : a)
    for (std::size_t k = 0; k < b.size(); ++k) d = std::min(d, segment_distance(p, b[k], b[(k + 1) % b.size()]));
  for (const Vec2& p : b)
    for (std::size_t k = 0; k < a.size(); ++k) d = std::min(d, segment_distance(p, a[k], a[(k + 1) % a.size()]));
  return d;
}

// Every pair (walls among themselves excepted) whose x-extents come within the
// smallest gap found so far: disjoint, and the smallest gap. Pairs farther
// apart in x cannot be closer, so the result is the exact minimum.
double check_disjoint(const GeneratedPack& pack) {
  const auto polys = world_polygons(pack.floes);
  std::vector<std::size_t> order(polys.size());
  std::iota(order.begin(), order.end(), 0);
  auto xmin = [&](std::size_t i) {
    double x = polys[i][0].x();
    for (const Vec2& p : polys[i]) x = std::min(x, p.x());
    return x;
  };
  auto xmax = [&](std::size_t i) {
    double x = polys[i][0].x();
    for (const Vec2& p : polys[i]) x = std::max(x, p.x());
    return x;
  };
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return xmin(a) < xmin(b); });
  double smallest = std::numeric_limits<double>::infinity();
  int overlaps = 0;
  std::size_t pairs = 0;
  for (std::size_t a = 0; a < order.size(); ++a)
    for (std::size_t b = a + 1; b < order.size() && xmin(order[b]) <= xmax(order[a]) + smallest; ++b) {
      const std::size_t i = order[a], j = order[b];
      if (pack.floes.is_static[i] && pack.floes.is_static[j]) continue;
      ++pairs;
      if (separation(polys[i], polys[j]) <= 0.0) ++overlaps;
      else smallest = std::min(smallest, distance(polys[i], polys[j]));
    }
  CHECK(overlaps == 0);
  CHECK(pairs >= polys.size() - 1);  // the sweep looked at neighbours at least
  return smallest;
}

void check_floes_valid(const GeneratedPack& pack, double W, double H) {
  const Floes& f = pack.floes;
  for (std::size_t i = 0; i < f.size(); ++i) {
    CAPTURE(i);
    const Polygon w = f.world_vertices(i);
    CHECK(is_convex(w));
    FloeInput in;
    in.vertices = w;
    in.thickness = f.thickness[i];
    in.density = f.density[i];
    const FloeShape shape = make_floe_shape(in);  // throws if invalid
    CHECK_FALSE(shape.reoriented);
    CHECK(shape.props.area == doctest::Approx(f.area[i]).epsilon(1e-9));
    if (f.is_static[i]) continue;
    for (const Vec2& p : w) {
      CHECK(p.x() > 0.0);
      CHECK(p.x() < W);
      CHECK(p.y() > 0.0);
      CHECK(p.y() < H);
    }
  }
}

double floe_area(const GeneratedPack& pack) {
  double a = 0.0;
  for (std::size_t i = 0; i < pack.floes.size(); ++i)
    if (!pack.floes.is_static[i]) a += pack.floes.area[i];
  return a;
}

// Maximum-likelihood exponent of p(d) ∝ d^-alpha on [a, b] (golden section on
// the log-likelihood, which is concave in alpha):
//   l(alpha) = n log((alpha-1) / (a^(1-alpha) - b^(1-alpha))) - alpha Σ log d_i.
double fit_power_law(const std::vector<double>& d, double a, double b) {
  double sum_log = 0.0;
  for (double x : d) sum_log += std::log(x);
  const double n = static_cast<double>(d.size());
  auto loglik = [&](double alpha) {
    const double q = 1.0 - alpha;
    return n * std::log(-q / (std::pow(a, q) - std::pow(b, q))) - alpha * sum_log;
  };
  double lo = 1.001, hi = 8.0;
  const double r = (std::sqrt(5.0) - 1.0) / 2.0;
  for (int it = 0; it < 200; ++it) {
    const double m1 = hi - r * (hi - lo), m2 = lo + r * (hi - lo);
    if (loglik(m1) < loglik(m2)) lo = m1;
    else hi = m2;
  }
  return 0.5 * (lo + hi);
}

PackOptions options(std::size_t floes, double concentration, std::uint64_t seed) {
  PackOptions o;
  o.floes = floes;
  o.concentration = concentration;
  o.seed = seed;
  return o;
}

}  // namespace

TEST_CASE("pack test helpers: separation and distance of two squares") {
  const Polygon a{{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  const Polygon b{{1.25, 0.5}, {2, 0.5}, {2, 2}, {1.25, 2}};  // 0.25 to the right
  const Polygon c{{0.9, 0.9}, {2, 0.9}, {2, 2}, {0.9, 2}};    // overlaps a's corner
  const Polygon d{{1, 0}, {2, 0}, {2, 1}, {1, 1}};            // touches a along x = 1
  CHECK(separation(a, b) == doctest::Approx(0.25));
  CHECK(distance(a, b) == doctest::Approx(0.25));
  CHECK(separation(a, c) < 0.0);
  CHECK(separation(a, d) <= 0.0);
}

TEST_CASE("pack: floes valid, inside the box, disjoint with the requested gap") {
  PackOptions o = options(300, 0.7, 7);
  o.width = 1000.0;
  o.height = 600.0;
  o.thickness_min = 0.5;
  o.thickness_max = 2.0;
  const GeneratedPack pack = generate_pack(o);
  REQUIRE(pack.floes.size() == 300);
  CHECK(pack.walls == 0);
  check_floes_valid(pack, o.width, o.height);
  const double gap = check_disjoint(pack);
  CHECK(gap >= pack.required_gap);
  CHECK(pack.min_gap == doctest::Approx(gap).epsilon(1e-12));  // the generator's gap is exact
  CHECK(pack.required_gap == doctest::Approx(1e-3 * std::sqrt(4.0 * 0.7 * 600000.0 / (std::numbers::pi * 300))));
  for (double h : pack.floes.thickness) {
    CHECK(h >= 0.5);
    CHECK(h <= 2.0);
  }
  const auto [lo, hi] = std::minmax_element(pack.floes.thickness.begin(), pack.floes.thickness.end());
  CHECK(*hi - *lo > 1.0);  // the range is used, not a constant
  CHECK(pack.window == std::array<double, 4>{0.0, 1000.0, 0.0, 600.0});
}

TEST_CASE("pack: achieved concentration within 2% of the target") {
  for (double c : {0.1, 0.3, 0.5, 0.7, 0.9, 0.95}) {
    CAPTURE(c);
    PackOptions o = options(200, c, 3);
    o.width = 500.0;
    o.height = 800.0;
    const GeneratedPack pack = generate_pack(o);
    const double achieved = floe_area(pack) / (o.width * o.height);
    CHECK(achieved == doctest::Approx(c).epsilon(0.02));
    CHECK(pack.concentration == doctest::Approx(achieved).epsilon(1e-12));
    CHECK(pack.max_area_error < 1e-6);
    CHECK(check_disjoint(pack) >= pack.required_gap);
  }
}

TEST_CASE("pack: the same seed gives the same pack, another seed another") {
  PackOptions o = options(150, 0.6, 11);
  o.sizes.kind = SizeDistribution::Kind::power_law;
  o.sizes.exponent = 2.0;
  o.thickness_max = 3.0;
  const GeneratedPack a = generate_pack(o), b = generate_pack(o);
  CHECK(a.floes.body == b.floes.body);
  CHECK(a.floes.offsets == b.floes.offsets);
  CHECK(a.floes.thickness == b.floes.thickness);
  bool same_state = true;
  for (std::size_t i = 0; i < a.floes.size(); ++i)
    same_state = same_state && a.floes.state[i].x == b.floes.state[i].x && a.floes.state[i].y == b.floes.state[i].y;
  CHECK(same_state);
  o.seed = 12;
  const GeneratedPack c = generate_pack(o);
  CHECK(c.floes.body != a.floes.body);
}

TEST_CASE("pack: power-law sizes recover the requested exponent") {
  for (double alpha : {1.5, 2.5}) {
    CAPTURE(alpha);
    PackOptions o = options(3000, 0.6, 5);
    o.width = o.height = 10000.0;
    o.sizes.kind = SizeDistribution::Kind::power_law;
    o.sizes.exponent = alpha;
    o.sizes.min_size = 10.0;
    o.sizes.max_size = 200.0;
    const GeneratedPack pack = generate_pack(o);
    const auto [a, b] = pack.size_range;
    CHECK(b / a == doctest::Approx(20.0));
    std::vector<double> d;
    for (double area : pack.floes.area) d.push_back(equivalent_diameter(area));
    const auto [dmin, dmax] = std::minmax_element(d.begin(), d.end());
    CHECK(*dmin >= a * (1.0 - 1e-6));
    CHECK(*dmax <= b * (1.0 + 1e-6));
    // Standard error of the MLE ~ (alpha - 1) / sqrt(n) ~ 0.01–0.03 here.
    const double fitted = fit_power_law(d, a, b);
    MESSAGE("alpha " << alpha << ": fitted " << fitted << ", size range [" << a << ", " << b << "] m");
    CHECK(fitted == doctest::Approx(alpha).epsilon(0.05));
    CHECK(check_disjoint(pack) >= pack.required_gap);
  }
}

TEST_CASE("pack: uniform law with equal sizes gives equal floe areas") {
  PackOptions o = options(400, 0.8, 9);
  const GeneratedPack pack = generate_pack(o);
  const auto [lo, hi] = std::minmax_element(pack.floes.area.begin(), pack.floes.area.end());
  CHECK(*hi / *lo == doctest::Approx(1.0).epsilon(1e-6));
  CHECK(*lo == doctest::Approx(0.8 * 1e6 / 400).epsilon(1e-6));
}

TEST_CASE("pack: static walls around the box keep the gap") {
  PackOptions o = options(100, 0.85, 2);
  o.wall_width = 20.0;
  const GeneratedPack pack = generate_pack(o);
  REQUIRE(pack.floes.size() == 104);
  CHECK(pack.walls == 4);
  for (std::size_t i = 0; i < 104; ++i) CHECK(pack.floes.is_static[i] == (i >= 100 ? 1 : 0));
  check_floes_valid(pack, o.width, o.height);
  CHECK(check_disjoint(pack) >= pack.required_gap);
  CHECK(floe_area(pack) / 1e6 == doctest::Approx(0.85).epsilon(0.02));  // walls not counted
}

TEST_CASE("pack: floes are numbered along a space-filling curve, neighbours near each other") {
  // Z-order numbering (pack_generator.hpp, step 5): in a random order the mean distance
  // between floes i and i + 1 would be about 0.52 of the box side (two uniform points in a
  // unit square); along a Z curve of N cells it is a few floe sizes, and half the first
  // floes lie in the box's lower-left quarter.
  PackOptions o = options(2000, 0.5, 4);
  o.wall_width = 10.0;
  const GeneratedPack pack = generate_pack(o);
  REQUIRE(pack.floes.size() == 2004);
  const std::size_t n = 2000;
  const double size = std::sqrt(o.width * o.height / static_cast<double>(n));  // box per floe
  double step = 0.0;
  std::size_t lower_left = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const FloeState& s = pack.floes.state[i];
    if (i + 1 < n) step += std::hypot(pack.floes.state[i + 1].x - s.x, pack.floes.state[i + 1].y - s.y);
    if (i < n / 4 && s.x < 0.5 * o.width && s.y < 0.5 * o.height) ++lower_left;
  }
  step /= static_cast<double>(n - 1);
  MESSAGE("mean distance of consecutive floes " << step / size << " floe spacings, " << lower_left
                                                << " of the first " << n / 4 << " in the lower-left quarter");
  CHECK(step < 3.0 * size);
  CHECK(lower_left > 0.9 * static_cast<double>(n / 4));
  for (std::size_t i = n; i < pack.floes.size(); ++i) CHECK(pack.floes.is_static[i]);  // walls last
}

TEST_CASE("pack: a larger requested gap is honoured, an impossible one refused") {
  PackOptions o = options(200, 0.5, 4);
  o.min_gap = 2.0;  // m; mean size ~ 56 m
  GeneratedPack pack = generate_pack(o);
  CHECK(pack.required_gap == 2.0);
  CHECK(check_disjoint(pack) >= 2.0);
  o.concentration = 0.95;
  o.min_gap = 20.0;
  CHECK_THROWS_AS(generate_pack(o), InputError);
}

TEST_CASE("pack: a single floe and two floes") {
  PackOptions o;
  o.floes = 1;
  o.concentration = 0.5;
  GeneratedPack pack = generate_pack(o);
  REQUIRE(pack.floes.size() == 1);
  CHECK(pack.floes.area[0] == doctest::Approx(0.5e6));
  o.floes = 2;
  pack = generate_pack(o);
  REQUIRE(pack.floes.size() == 2);
  CHECK(check_disjoint(pack) >= pack.required_gap);
}

TEST_CASE("pack: bad options are refused with the option named") {
  auto refused = [](PackOptions o, const char* word) {
    try {
      generate_pack(o);
      return false;
    } catch (const InputError& e) {
      CAPTURE(e.what());
      return std::string(e.what()).find(word) != std::string::npos;
    }
  };
  PackOptions o;
  CHECK(refused([&] { auto p = o; p.floes = 0; return p; }(), "floes"));
  CHECK(refused([&] { auto p = o; p.concentration = 0.0; return p; }(), "concentration"));
  CHECK(refused([&] { auto p = o; p.concentration = 0.99; return p; }(), "concentration"));
  CHECK(refused([&] { auto p = o; p.width = -1.0; return p; }(), "width"));
  CHECK(refused([&] { auto p = o; p.height = std::nan(""); return p; }(), "height"));
  CHECK(refused([&] { auto p = o; p.sizes.min_size = 5.0; p.sizes.max_size = 1.0; return p; }(), "max_size"));
  CHECK(refused([&] { auto p = o; p.sizes.min_size = 5.0; return p; }(), "min_size"));
  CHECK(refused([&] {
    auto p = o;
    p.sizes.kind = SizeDistribution::Kind::power_law;
    p.sizes.exponent = -1.0;
    return p;
  }(), "exponent"));
  CHECK(refused([&] { auto p = o; p.thickness_min = 2.0; p.thickness_max = 1.0; return p; }(), "thickness"));
}

TEST_CASE("pack: write_pack / read_pack round trip") {
  PackOptions o = options(50, 0.6, 8);
  o.wall_width = 5.0;
  const GeneratedPack pack = generate_pack(o);
  const auto path = (std::filesystem::temp_directory_path() / "floesim_test_pack_generator.h5").string();
  write_pack(path, pack.floes, pack.window);
  const Pack read = read_pack(path);
  std::remove(path.c_str());
  REQUIRE(read.floes.size() == 54);
  REQUIRE(read.window.has_value());
  CHECK(*read.window == pack.window);
  for (std::size_t i = 0; i < 54; ++i) {
    const FloeShape s = make_floe_shape(read.floes[i]);
    CHECK(s.props.area == doctest::Approx(pack.floes.area[i]).epsilon(1e-12));
    CHECK(read.floes[i].is_static == (i >= 50));
  }
}
