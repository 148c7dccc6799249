// Forcing series: interpolation and input checks.
#include <doctest/doctest.h>

#include <filesystem>
#include <fstream>

#include "core/error.hpp"
#include "core/forcing.hpp"

using namespace floesim;

TEST_SUITE_BEGIN("core");

namespace {
std::string write_tmp(const std::string& name, const std::string& text) {
  const auto p = std::filesystem::temp_directory_path() / name;
  std::ofstream(p) << text;
  return p.string();
}
}  // namespace

TEST_CASE("linear and previous interpolation of a CSV series") {
  const std::string p = write_tmp("floesim_forcing.csv",
                                  "# comment\nt_s,wind_u,wind_v,current_u,current_v\n0,0,0,0,0\n10,10,-2,1,0\n");
  const ForcingSeries lin = ForcingSeries::from_csv(p, SeriesInterpolation::linear);
  CHECK(lin.rows() == 2);
  CHECK(lin.at(2.5).wind[0] == doctest::Approx(2.5));
  CHECK(lin.at(2.5).wind[1] == doctest::Approx(-0.5));
  CHECK(lin.at(5.0).current[0] == doctest::Approx(0.5));
  CHECK(lin.at(-1.0).wind[0] == 0.0);   // clamped before the first row
  CHECK(lin.at(99.0).wind[0] == 10.0);  // and after the last
  const ForcingSeries prev = ForcingSeries::from_csv(p, SeriesInterpolation::previous);
  CHECK(prev.at(9.99).wind[0] == 0.0);
  CHECK(prev.at(10.0).wind[0] == 10.0);
}

TEST_CASE("constant forcing") {
  ForcingParams f;
  f.wind = {3, 4};
  f.current = {0.1, 0};
  const ForcingSeries s = make_forcing(f);
  CHECK(s.at(1e6).wind[1] == 4.0);
  CHECK(s.at(0).current[0] == 0.1);
}

TEST_CASE("bad CSV rows are refused naming file and line") {
  auto refused = [](const std::string& text, const std::string& fragment) {
    const std::string p = write_tmp("floesim_bad_forcing.csv", text);
    try {
      ForcingSeries::from_csv(p, SeriesInterpolation::linear);
    } catch (const InputError& e) {
      const std::string m = e.what();
      CHECK_MESSAGE(m.find(p) != std::string::npos, m);
      CHECK_MESSAGE(m.find(fragment) != std::string::npos, m);
      return;
    }
    FAIL("accepted: " << text);
  };
  refused("t_s,wind_u,wind_v,current_u,current_v\n0,1,2,3\n", ":2: expected 5 columns");
  refused("t_s,wind_u,wind_v,current_u,current_v\n0,1,2,3,x\n", ":2: column 5 is not a number");
  refused("t_s,wind_u,wind_v,current_u,current_v\n0,1,2,3,4\n0,1,2,3,4\n", ":3: times must increase");
  refused("t_s,wind_u,wind_v,current_u,current_v\n0,1,2,3,nan\n", "not finite");
  refused("t_s,wind_u,wind_v,current_u,current_v\n", "no data row");
}

TEST_SUITE_END();
