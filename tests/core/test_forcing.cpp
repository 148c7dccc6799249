// Forcing series: interpolation and input checks.
#include <doctest/doctest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "core/config.hpp"
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
// A string literal with its embedded NUL bytes (binary data).
template <std::size_t N>
std::string bytes(const char (&a)[N]) {
  return std::string(a, N - 1);
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

// Every malformed series is an InputError naming the file, the line and what was
// expected (issue 17: each of these aborted `floesim run` with a double free).
TEST_CASE("malformed CSV series are refused naming file, line and what was expected") {
  const std::string H = "t_s,wind_u,wind_v,current_u,current_v\n";
  struct Case {
    const char* name;
    std::string text;
    std::vector<std::string> fragments;
  };
  const std::vector<Case> cases = {
      {"missing column", H + "0,1,2,3\n", {":2:", "expected 5 columns", "got 4"}},
      {"long row", H + "0,1,2,3,4,5\n", {":2:", "expected 5 columns", "got 6"}},
      {"short row later", H + "0,1,2,3,4\n10,1,2\n", {":3:", "expected 5 columns", "got 3"}},
      {"empty row of commas", H + ",,,,\n", {":2:", "column 1 (t_s): expected a number, got ''"}},
      {"text in a number", H + "0,1,2,3,x\n", {":2:", "column 5 (current_v): expected a number, got 'x'"}},
      {"trailing junk", H + "0,1.5m/s,2,3,4\n", {":2:", "column 2 (wind_u): expected a number, got '1.5m/s'"}},
      {"nan", H + "0,1,2,3,nan\n", {":2:", "column 5 (current_v): expected a finite number, got 'nan'"}},
      {"inf time", H + "inf,1,2,3,4\n", {":2:", "column 1 (t_s): expected a finite number"}},
      {"overflow", H + "0,1e400,2,3,4\n", {":2:", "column 2 (wind_u): expected a number, got '1e400'"}},
      {"duplicate time", H + "0,1,2,3,4\n0,1,2,3,4\n", {":3:", "expected times increasing strictly, got t_s = 0 after 0"}},
      {"decreasing time", H + "0,1,2,3,4\n10,1,2,3,4\n5,1,2,3,4\n",
       {":4:", "expected times increasing strictly, got t_s = 5 after 10"}},
      {"decreasing after comments", H + "0,1,2,3,4\n# gap\n\n10,1,2,3,4\n# again\n9.5,1,2,3,4\n",
       {":7:", "increasing strictly", "9.5 after 10"}},
      {"decreasing at the end", H + "0,0,0,0,0\n1,0,0,0,0\n2,0,0,0,0\n1.999,0,0,0,0\n", {":5:", "increasing strictly"}},
      {"empty file", "", {"no data row", "expected the header"}},
      {"only a header", H, {"no data row"}},
      {"only comments", "# nothing\n\n# here\n", {"no data row"}},
      {"wrong header names", "time,wind_u,wind_v,current_u,current_v\n0,1,2,3,4\n",
       {":1:", "expected the header t_s,wind_u,wind_v,current_u,current_v, got 'time,wind_u"}},
      {"header in another order", "t_s,current_u,current_v,wind_u,wind_v\n0,1,2,3,4\n", {":1:", "expected the header"}},
      {"header short", "t_s,wind_u,wind_v,current_u\n0,1,2,3,4\n", {":1:", "expected the header"}},
      {"header twice", H + "0,1,2,3,4\n" + H, {":3:", "column 1 (t_s): expected a number, got 't_s'"}},
      {"binary data", bytes("\x89PNG\r\n\x1a\n\0\0\0\rIHDR\xff\xfe"), {":1:", "expected the header", "'?PNG"}},
      {"binary row", H + bytes("0,1,\0\x01\x02,3,4\n"), {":2:", "column 3 (wind_v): expected a number, got '\?\?\?'"}},
  };
  for (const Case& c : cases) {
    CAPTURE(c.name);
    const std::string p = write_tmp("floesim_bad_forcing.csv", c.text);
    try {
      ForcingSeries::from_csv(p, SeriesInterpolation::linear);
      FAIL("accepted: " << c.name);
    } catch (const InputError& e) {
      const std::string m = e.what();
      CHECK_MESSAGE(m.rfind(p, 0) == 0, m);  // the message starts with the file
      for (const std::string& f : c.fragments) CHECK_MESSAGE(m.find(f) != std::string::npos, "'" << f << "' not in: " << m);
    }
  }
  // A folder and a missing file.
  const auto dir = std::filesystem::temp_directory_path() / "floesim_forcing_dir";
  std::filesystem::create_directories(dir);
  CHECK_THROWS_WITH_AS(ForcingSeries::from_csv(dir.string(), SeriesInterpolation::linear),
                       doctest::Contains("is a folder; expected a CSV file"), InputError);
  CHECK_THROWS_WITH_AS(ForcingSeries::from_csv((dir / "none.csv").string(), SeriesInterpolation::linear),
                       doctest::Contains("cannot open the forcing series"), InputError);
  // A device (found by fuzz/fuzz_config, tests/data/fuzz/config/series_dev_zero.toml):
  // /dev/zero was read as one endless line until memory ran out.
  CHECK_THROWS_WITH_AS(ForcingSeries::from_csv("/dev/zero", SeriesInterpolation::linear),
                       doctest::Contains("/dev/zero: the forcing series is not a regular file"), InputError);
}

TEST_CASE("a series without header and with comments, blank lines and CRLF is read") {
  const std::string p = write_tmp("floesim_forcing_plain.csv", "# wind ramps\r\n\r\n0, 0, 0, 0, 0\r\n60,5,0,0.1,0\r\n");
  const ForcingSeries s = ForcingSeries::from_csv(p, SeriesInterpolation::linear);
  CHECK(s.rows() == 2);
  CHECK(s.at(30).wind[0] == doctest::Approx(2.5));
}

// The configuration loader checks the series (the GCC 12 double free of issue 17
// was in building the scenario after a reader error; now the error comes at load).
TEST_CASE("a bad series is refused at load, naming the key and the CSV line") {
  const std::string csv = write_tmp("floesim_bad_series.csv", "t_s,wind_u,wind_v,current_u,current_v\n5,0,0,0,0\n1,0,0,0,0\n");
  const std::string dir = std::filesystem::path(csv).parent_path().string();
  try {
    parse_config("[forcing]\nseries = \"floesim_bad_series.csv\"\n", "case.toml", dir);
    FAIL("accepted a decreasing series");
  } catch (const InputError& e) {
    const std::string m = e.what();
    CHECK_MESSAGE(m.find("case.toml:2: key '[forcing] series': " + csv + ":3: expected times increasing strictly") !=
                      std::string::npos,
                  m);
  }
}

TEST_SUITE_END();
