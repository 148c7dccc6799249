// The poison mode's check of the sea (coupling/poison_mode.hpp,
// UnheldPoison::check_sea; fluid::Sea::finite_state): a NaN pressure that a
// phase made from a poisoned floe and kicked into the sea is reported for
// that phase, on a spectral sea (whose kicks wait, deferred, until the next
// flow) and on a BEM sea. docs/parallel.md, "The poison mode of the run".
#include <doctest/doctest.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "coupling/poison_mode.hpp"
#include "fluid/sea.hpp"
#include "tests/fluid/sea_cases.hpp"

using namespace floesim;

TEST_SUITE_BEGIN("coupling");

namespace {

// The mode opened on two floes, the second not held (poisoned).
UnheldPoison opened_poison() {
  UnheldPoison poison(PoisonOptions{}, 1);
  std::vector<FloeState> state(2);
  std::vector<double> reach(2, 1.0);
  const std::vector<std::uint8_t> held{1, 0};
  poison.poison(held, held, state, nullptr, reach, contact::Domain{});
  return poison;
}

// A pressure on the sea's grid, one cell NaN (a poisoned floe's load).
std::vector<double> poisoned_pressure(const fluid::Sea& sea) {
  std::vector<double> p(static_cast<std::size_t>(sea.grid().size()), 0.0);
  for (std::size_t c = 0; c < p.size(); ++c) p[c] = 10.0 * std::sin(0.3 * static_cast<double>(c));
  p[p.size() / 3] = std::numeric_limits<double>::quiet_NaN();
  return p;
}

void check_reported(fluid::Sea& sea) {
  UnheldPoison poison = opened_poison();
  REQUIRE(sea.finite_state());
  poison.check_sea("first half kick", sea.finite_state());
  CHECK(poison.reports().empty());
  sea.kick(poisoned_pressure(sea), 0.01);
  // Before any flow: a spectral sea holds the kick deferred, its load NaN.
  CHECK_FALSE(sea.finite_state());
  poison.check_sea("sea", sea.finite_state());
  REQUIRE(poison.reports().size() == 1);
  CHECK(poison.reports()[0] == "poison: rank 1: after sea: the sea's modal state is NaN");
  poison.check_sea("sea", sea.finite_state());  // once a phase
  CHECK(poison.reports().size() == 1);
  sea.flow(0.01);  // applied: the modes themselves are NaN now
  CHECK_FALSE(sea.finite_state());
  poison.check_sea("second half kick", sea.finite_state());
  CHECK(poison.reports().size() == 2);
}

}  // namespace

TEST_CASE("poison mode: a NaN kicked into a spectral sea is reported after its phase") {
  SeaParams p = fluid::cases::lab_box_1d(16);
  p.dims = 2;
  p.cells = {16, 8};
  auto sea = fluid::make_sea(p, 1);
  check_reported(*sea);
}

TEST_CASE("poison mode: a NaN kicked into a BEM sea is reported after its phase") {
  auto sea = fluid::make_sea(fluid::cases::lab_tank_bem(16), 1);
  check_reported(*sea);
}

TEST_CASE("poison mode: a finite sea is not reported, nor a NaN sea before the first poison") {
  SeaParams p = fluid::cases::lab_box_1d(16);
  auto sea = fluid::make_sea(p, 1);
  std::vector<double> pressure(static_cast<std::size_t>(sea->grid().size()), 5.0);
  pressure[1] = -5.0;
  sea->kick(pressure, 0.01);
  sea->flow(0.01);
  CHECK(sea->finite_state());
  UnheldPoison closed(PoisonOptions{}, 0);
  sea->kick(poisoned_pressure(*sea), 0.01);
  closed.check_sea("sea", sea->finite_state());  // no window opened yet: no check
  CHECK(closed.reports().empty());
  UnheldPoison poison = opened_poison();
  poison.check_sea("sea", sea->finite_state());
  CHECK(poison.reports().size() == 1);
}
