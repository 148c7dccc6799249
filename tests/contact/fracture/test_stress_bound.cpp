// Responder::stress_bound (response.hpp): an upper bound of the largest
// tensile principal stress of a load case, from the energy an impulse can
// give the elastic modes (at most j_r^T M^-1 j_r / 2) and the least strain
// energy a triangle holds at a given sigma_1. Percussion skips the cases it
// puts below the strength, which is exact only if the bound is never below
// the response's own largest sigma_1: checked here over floes, meshes,
// collision durations and load cases (impacts on the outline and inside,
// several at once, with static forces).
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "contact/fracture/floe_fracture.hpp"

using namespace floesim;
using namespace floesim::fracture;

TEST_SUITE_BEGIN("contact");

TEST_CASE("stress bound: never below the analysed largest principal stress, and within a modest factor of it") {
  const std::vector<std::vector<Vec2>> floes = {
      {{0, 0}, {40, 0}, {40, 40}, {0, 40}},
      {{0, 0}, {60, 0}, {60, 20}, {20, 20}, {20, 50}, {0, 50}},  // non-convex (an L)
      {{10, 0}, {30, 0}, {40, 17}, {30, 34}, {10, 34}, {0, 17}},
  };
  double worst = 0.0;
  std::vector<double> ratios_short, ratios_long;  // bound / stress, tau = 10 ms and 0.3 s
  int cases = 0;
  for (const auto& polygon : floes)
    for (const double mesh : {2.0, 6.0})
      for (const double tau : {0.01, 0.3}) {
        FractureParams params;
        params.mesh_size = mesh;
        params.duration = tau;
        params.load_radius = 2.0;
        FloeFracture floe(polygon, 1.0, 917.0, params);
        Vec2 centre = Vec2::Zero();
        for (const Vec2& p : polygon) centre += p / static_cast<double>(polygon.size());
        std::vector<std::vector<PointLoad>> loads;
        for (std::size_t k = 0; k < polygon.size(); ++k) {
          // on the middle of each side, inward at an angle, and a point inside
          const Vec2 a = polygon[k], b = polygon[(k + 1) % polygon.size()];
          const Vec2 mid = 0.5 * (a + b), inward = Vec2{a.y() - b.y(), b.x() - a.x()}.normalized();
          const Vec2 along = (b - a).normalized();
          loads.push_back({{mid, 1e4 * (inward + 0.3 * along), true}});
          loads.push_back({{mid, 1e4 * inward, true}, {0.5 * (mid + centre), -3e3 * along, true}});
          // an impact with the step's sustained forces beside it
          loads.push_back({{mid, 5e3 * inward, true}, {a + 0.25 * (b - a), 2e5 * inward, false},
                           {a + 0.75 * (b - a), 2e5 * inward, false}});
        }
        for (const auto& l : loads) {
          const double bound = floe.responder().stress_bound(l);
          const double stress = floe.analyse(l).response.peak_stress.max_principal;
          REQUIRE(stress > 0.0);
          CHECK(bound >= stress);
          worst = std::max(worst, stress / bound);
          (tau < 0.1 ? ratios_short : ratios_long).push_back(bound / stress);
          ++cases;
        }
      }
  auto median = [](std::vector<double> v) {
    std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
    return v[v.size() / 2];
  };
  MESSAGE(cases << " cases: largest stress / bound " << worst << "; bound / stress median "
                << median(ratios_short) << " (tau 10 ms), " << median(ratios_long) << " (tau 0.3 s)");
  // The bound takes every mode, up to the mesh's shortest, as struck by a
  // blow, and all the energy in the smallest triangle: loose (measured median
  // 123 for tau = 10 ms, 4700 for 0.3 s, these meshes of 2 and 6 m), but
  // the stresses of a pack's impacts are mostly far below a strength that
  // nothing reaches (docs/fracture.md, "Cost"). A looser bound fails here.
  CHECK(median(ratios_short) < 200.0);
}

// The time loop's energy bound (Responder::respond with a level): once the
// pulse has put its energy in, no later step can hold more, and no triangle
// can be more stressed than that energy in the smallest triangle allows. The
// loop stops when that and the stresses so far are below the level. Checked
// against the whole loop over the floes, meshes, durations and load cases
// above, at levels from half the analysed peak to 20 times it: a loop cut
// short never hides a step at or above the level, every later step's sigma_1
// is below the bound it stopped on, and FloeFracture::decide gives the
// verdict (and for an initiation the crack) of FloeFracture::analyse.
TEST_CASE("energy bound in the time loop: never below a later step's stress, and decide() judges as analyse()") {
  const std::vector<std::vector<Vec2>> floes = {
      {{0, 0}, {40, 0}, {40, 40}, {0, 40}},
      {{0, 0}, {60, 0}, {60, 20}, {20, 20}, {20, 50}, {0, 50}},
      {{10, 0}, {30, 0}, {40, 17}, {30, 34}, {10, 34}, {0, 17}},
  };
  const std::vector<double> levels = {0.5, 0.999, 1.001, 1.5, 3.0, 20.0};  // x the analysed peak
  int cases = 0, cut = 0, same = 0, loose = 0, loose_cut = 0;  // loose: level 20 x the peak
  long steps_run = 0, steps_all = 0;
  std::vector<double> tightness;  // bound / largest later sigma_1, where cut
  for (const auto& polygon : floes)
    for (const double mesh : {3.0, 8.0})
      for (const double tau : {0.01, 0.3}) {
        FractureParams params;
        params.mesh_size = mesh;
        params.duration = tau;
        params.load_radius = 2.0;
        FloeFracture floe(polygon, 1.0, 917.0, params);
        Responder& responder = floe.responder();
        Vec2 centre = Vec2::Zero();
        for (const Vec2& p : polygon) centre += p / static_cast<double>(polygon.size());
        for (std::size_t k = 0; k < polygon.size(); ++k) {
          const Vec2 a = polygon[k], b = polygon[(k + 1) % polygon.size()];
          const Vec2 mid = 0.5 * (a + b), inward = Vec2{a.y() - b.y(), b.x() - a.x()}.normalized();
          const Vec2 along = (b - a).normalized();
          for (const std::vector<PointLoad>& loads :
               {std::vector<PointLoad>{{mid, 1e4 * (inward + 0.3 * along), true}},
                std::vector<PointLoad>{{mid, 1e4 * inward, true}, {0.5 * (mid + centre), -3e3 * along, true}},
                std::vector<PointLoad>{{mid, 5e3 * inward, true}, {a + 0.25 * (b - a), 2e5 * inward, false},
                                       {a + 0.75 * (b - a), 2e5 * inward, false}}}) {
            std::vector<double> sigma;  // largest nodal sigma_1 at each instant of the whole loop
            const Response all = responder.respond(loads, [&](double, const Eigen::VectorXd& u) {
              double largest = -std::numeric_limits<double>::infinity();
              for (const Eigen::Vector3d& st : floe.model().nodal_stress(u)) largest = std::max(largest, principal(st).value);
              sigma.push_back(largest);
            });
            REQUIRE(all.peak_stress.max_principal > 0.0);
            REQUIRE(sigma.size() == static_cast<std::size_t>(all.steps) + 1);
            for (const double f : levels) {
              const double level = f * all.peak_stress.max_principal;
              const Response part = responder.respond(loads, {}, level);
              ++cases;
              if (f == 20.0) ++loose;
              steps_all += all.steps;
              steps_run += part.steps;
              if (!part.cut_short) {
                CHECK(part.steps == all.steps);
                continue;
              }
              ++cut;
              if (f == 20.0) ++loose_cut;
              CHECK(all.peak_stress.max_principal < level);
              CHECK(part.steps < all.steps);
              const double later = *std::max_element(sigma.begin() + part.steps + 1, sigma.end());
              CHECK(later <= part.later_bound);
              tightness.push_back(part.later_bound / later);
            }
            // decide() against analyse() at strengths about the peak
            for (const double f : {0.999, 1.001, 3.0}) {
              FractureParams judged = params;
              judged.strength = f * all.peak_stress.max_principal;
              FloeFracture other(polygon, 1.0, 917.0, judged);
              const Initiation full = other.analyse(loads).initiation, quick = other.decide(loads).initiation;
              CHECK(full.initiates == quick.initiates);
              CHECK(full.initiates == (f < 1.0));
              if (full.initiates) {
                CHECK(quick.stress == full.stress);
                CHECK(quick.time == full.time);
                CHECK((quick.point - full.point).norm() == 0.0);
                CHECK(quick.direction == full.direction);
                ++same;
              }
            }
          }
        }
      }
  std::nth_element(tightness.begin(), tightness.begin() + static_cast<std::ptrdiff_t>(tightness.size() / 2), tightness.end());
  MESSAGE(cases << " loops with a level, " << cut << " cut short, running " << steps_run << " of " << steps_all
                << " steps; bound / largest later stress, median " << tightness[tightness.size() / 2] << "; " << same
                << " initiations identical; at 20 x the peak " << loose_cut << " of " << loose << " cut short");
  // The bound is loose (all the energy in the smallest triangle: measured
  // median 18 times the later stresses here), but a level 20 times the peak
  // stops most loops (measured 166 of 192): a looser bound fails here.
  CHECK(loose_cut >= 0.8 * loose);
}

TEST_CASE("stress bound: static forces alone give the analysed stress itself") {
  FractureParams params;
  params.mesh_size = 3.0;
  FloeFracture floe(std::vector<Vec2>{{0, 0}, {30, 0}, {30, 30}, {0, 30}}, 1.0, 917.0, params);
  const std::vector<PointLoad> loads = {{{0, 15}, {1e6, 0}, false}, {{30, 15}, {-1e6, 0}, false}};
  const double stress = floe.analyse(loads).response.peak_stress.max_principal;
  CHECK(floe.responder().stress_bound(loads) == doctest::Approx(stress).epsilon(1e-12));
}

// A crack starts at the most stressed node, which a coarse mesh often puts on
// a corner of the floe, where the crack's line may only touch the floe from
// outside. It then starts at the centroid of that node's most stressed
// triangle (criteria.cpp), so on a convex floe every initiation is a crack
// through (an interior point's chord always is). Mesh 20 m on a 60 m square,
// load radius 20 m, blows near the corners and along the sides.
TEST_CASE("stress criterion: on a convex floe every initiation is a crack through, however coarse the mesh") {
  FractureParams params;
  params.mesh_size = 20.0;
  params.load_radius = 20.0;
  params.strength = 1.0;  // Pa: every load initiates
  const std::vector<Vec2> square = {{0, 0}, {60, 0}, {60, 60}, {0, 60}};
  FloeFracture floe(square, 1.0, 917.0, params);
  int cases = 0;
  for (const double s : {2.0, 8.0, 20.0, 30.0, 45.0, 58.0})
    for (const double slant : {-0.8, 0.0, 0.5}) {
      const std::vector<PointLoad> loads = {{{s, 0.0}, {slant * 1e4, 1e4}, true}};
      const Initiation init = floe.analyse(loads).initiation;
      REQUIRE(init.initiates);
      CHECK(init.through);
      CHECK((init.crack_to - init.crack_from).norm() > 1.0);
      ++cases;
    }
  CHECK(cases == 18);
}
