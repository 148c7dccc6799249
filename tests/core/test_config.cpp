// Configuration: defaults, every error names the file, the line and the key.
#include <doctest/doctest.h>

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include "core/config.hpp"
#include "core/detail/h5.hpp"
#include "core/error.hpp"

using namespace floesim;

TEST_SUITE_BEGIN("core");

namespace {
Config parse(const std::string& text) { return parse_config(text, "case.toml", "/tmp"); }

// Parsing must fail with a message holding every fragment.
void refused(const std::string& text, std::initializer_list<std::string> fragments) {
  try {
    parse(text);
  } catch (const InputError& e) {
    const std::string m = e.what();
    for (const auto& f : fragments) CHECK_MESSAGE(m.find(f) != std::string::npos, "'" << f << "' not in: " << m);
    return;
  }
  FAIL("accepted: " << text);
}
}  // namespace

TEST_CASE("an empty configuration gives the documented defaults") {
  const Config c = parse("");
  CHECK(c.run.t_end == 100.0);
  CHECK(c.run.dt_max == 0.05);
  CHECK(c.sea.model == SeaModel::none);
  CHECK(c.sea.rho == 1025.0);
  CHECK(std::isinf(c.sea.depth));
  CHECK(c.contact.restitution == 0.4);
  CHECK(c.coupling.law == PenaltyLaw::strong);
  CHECK(c.forcing.ocean_drag == 5.0e-3);
  CHECK(c.floes.floes.empty());
}

TEST_CASE("[run] crash_safe_output chooses how the run file is written") {
  CHECK(parse("").run.crash_safe_output);
  CHECK(parse("[run]\ncrash_safe_output = true\n").run.crash_safe_output);
  CHECK_FALSE(parse("[run]\ncrash_safe_output = false\n").run.crash_safe_output);
  refused("[run]\ncrash_safe_output = \"yes\"\n", {"case.toml", "[run] crash_safe_output", "expected true or false", "a string"});
  refused("[run]\ncrash_safe_output = 0\n", {"case.toml", "[run] crash_safe_output", "expected true or false"});
  // An execution setting: not in the resolved configuration a run file keeps,
  // so that a file written in place equals one written crash-safe.
  CHECK(resolved_toml(parse("[run]\ncrash_safe_output = false\n")) == resolved_toml(parse("")));
}

TEST_CASE("a full configuration is read") {
  const Config c = parse(R"(
[run]
t_end = 10
dt_max = 0.5
output_interval = 2.0
seed = 7
[sea]
model = "spectral"
dims = 1
size = [100.0, 5.0]
cells = [64, 1]
depth = 3.0
[sea.waves]
kind = "regular"
amplitude = 0.1
period = 2.0
[floes]
density = 900.0
[[floes.floe]]
vertices = [[0, 0], [1, 0], [1, 1]]
velocity = [0.5, 0]
[[floes.floe]]
vertices = [[5, 0], [6, 0], [6, 1]]
thickness = 0.3
static = true
[forcing]
wind = [10, 0]
latitude = 80.0
)");
  CHECK(c.run.seed == 7);
  CHECK(c.sea.cells[0] == 64);
  CHECK(c.sea.waves.kind == WaveKind::regular);
  REQUIRE(c.floes.floes.size() == 2);
  CHECK(c.floes.floes[0].density == 900.0);
  CHECK(c.floes.floes[0].thickness == 1.0);
  CHECK(c.floes.floes[1].thickness == 0.3);
  CHECK(c.floes.floes[1].is_static);
  // f = 2 Ω sin(80°)
  CHECK(c.forcing.coriolis == doctest::Approx(2 * 7.2921e-5 * std::sin(80.0 * M_PI / 180)));
}

TEST_CASE("unknown keys, wrong types and out-of-range values name file, line and key") {
  refused("[run]\nt_end = 1\nt_edn = 2\n", {"case.toml:3", "[run] t_edn", "unknown key"});
  refused("[run]\ndt_max = \"fast\"\n", {"case.toml:2", "[run] dt_max", "a string"});
  refused("[run]\ndt_max = -1.0\n", {"case.toml:2", "[run] dt_max", "> 0"});
  refused("[sea]\ndims = 3\n", {"case.toml:2", "[sea] dims", "1 or 2"});
  refused("[sea]\nmodel = \"fem\"\n", {"[sea] model", "\"spectral\""});
  refused("[sea]\ncells = [0, 4]\n", {"[sea] cells"});
  refused("[contact]\nrestitution = 1.5\n", {"[contact] restitution", "[0, 1]"});
  refused("[contact]\ndump_failed_lcps = \"no_such_folder\"\n", {"case.toml:2", "[contact] dump_failed_lcps",
                                                                   "existing folder", "/tmp/no_such_folder"});
  CHECK(parse("[contact]\ndump_failed_lcps = \".\"\n").contact.dump_failed_lcps == "/tmp/");  // relative to the file
  refused("[forcing]\nwind = [1]\n", {"[forcing] wind", "2 numbers"});
  refused("[forcing]\ncoriolis = 1e-4\nlatitude = 80\n", {"[forcing] latitude", "not both"});
  refused("[bogus]\nx = 1\n", {"case.toml:1", "bogus", "unknown key"});
  refused("[floes]\npack = \"does_not_exist.h5\"\n", {"[floes] pack", "not found"});
  refused("[[floes.floe]]\nvelocity = [1, 0]\n", {"[floes.floe] vertices"});
  refused("[[floes.floe]]\nvertices = [[0,0],[1,0],[1,1]]\ncolour = 1\n", {"case.toml:3", "colour"});
  refused("[[floes.floe]]\nvertices = [[0,0],[1,0],[1,1]]\nstatic = true\nvelocity = [1, 0]\n",
          {"[floes.floe] static", "cannot have a velocity"});
  refused("[coupling]\nblend = 0.5\n", {"[coupling] blend", "blend"});
  refused("[coupling]\nfootprint = \"round\"\n", {"[coupling] footprint", "\"tent\""});
  refused("[sea]\nmodel = \"bem\"\ndims = 1\n[coupling]\nfootprint = \"tent\"\n", {"case.toml:5", "[coupling] footprint", "periodic"});
  // A 3D basin's dense set-up is bounded (also with the default cells).
  refused("[sea]\nmodel = \"bem\"\ndims = 2\ncells = [128, 64]\n", {"[sea] cells", "at most 4096 surface cells", "128 x 64"});
  refused("[sea]\nmodel = \"bem\"\n", {"[sea] cells", "dense set-up"});
  CHECK(parse("[sea]\nmodel = \"bem\"\ndims = 2\ncells = [64, 64]\ndepth = 1.0\n").sea.cells[1] == 64);
  // With the lowest modes only (bem_modes = n) the bound is the LU's.
  refused("[sea]\nmodel = \"bem\"\ndims = 2\ncells = [128, 64]\n", {"keep the lowest modes only with bem_modes"});
  CHECK(parse("[sea]\nmodel = \"bem\"\ndims = 2\ncells = [96, 64]\ndepth = 1.0\nbem_modes = 300\n").sea.bem_modes == 300);
  refused("[sea]\nmodel = \"bem\"\ndims = 2\ncells = [128, 64]\nbem_modes = 300\n",
          {"[sea] cells", "at most 6144 surface cells", "with bem_modes > 0", "128 x 64"});
  refused("[sea]\nmodel = \"bem\"\ndims = 2\ncells = [4, 4]\nbem_modes = 15\n",
          {"[sea] bem_modes", "at most 14 modes", "got 15"});
  refused("[sea]\nmodel = \"bem\"\ndims = 2\ncells = [4, 4]\nbem_modes = -1\n", {"[sea] bem_modes", ">= 0"});
  refused("[sea]\nmodel = \"spectral\"\nbem_modes = 10\n", {"[sea] bem_modes", "dims = 2"});
  // The static correction of the lowest modes: only with them; floes on it need the implicit step.
  const std::string corrected = "[sea]\nmodel = \"bem\"\ndims = 2\ncells = [8, 4]\ndepth = 1.0\nbem_modes = 10\n"
                                "bem_static_correction = true\n";
  CHECK(parse(corrected).sea.bem_static_correction);
  CHECK(parse(corrected + "[[floes.floe]]\nvertices = [[0,0],[1,0],[1,1]]\n[coupling]\nintegrator = \"implicit\"\n")
            .sea.bem_static_correction);
  refused(corrected + "[[floes.floe]]\nvertices = [[0,0],[1,0],[1,1]]\n",
          {"[sea] bem_static_correction", "integrator = \"implicit\""});
  refused("[sea]\nmodel = \"bem\"\ndims = 2\ncells = [8, 4]\ndepth = 1.0\nbem_static_correction = true\n",
          {"[sea] bem_static_correction", "bem_modes = n > 0"});
  refused("[sea]\nmodel = \"bem\"\ndims = 2\ncells = [8, 4]\ndepth = 1.0\nbem_modes = 10\nbem_static_correction = 1\n",
          {"[sea] bem_static_correction", "true or false"});
  // A 3D basin's bottom grid (bottom_file): checked at load, with the line at fault.
  {
    const std::string dir = "/tmp/floesim_bottom_" + std::to_string(::getpid());
    std::filesystem::create_directories(dir);
    auto file = [&](const std::string& name, const std::string& text) {
      std::ofstream(dir + "/" + name) << text;
      return "[sea]\nmodel = \"bem\"\ndims = 2\ncells = [8, 4]\nbottom_file = \"" + dir + "/" + name + "\"\n";
    };
    const Config c = parse(file("ok.csv", "# z(x, y)\n-1.0, -0.5, -0.2\n\n-1.0, -0.6, -0.3\n"));
    CHECK(c.sea.bottom_nx == 3);
    CHECK(c.sea.bottom_ny == 2);
    CHECK(c.sea.bottom_grid[4] == -0.6);
    refused(file("ragged.csv", "-1, -1\n-1\n"), {"[sea] bottom_file", "ragged.csv:2", "expected 2 values"});
    refused(file("dry.csv", "-1, -1\n-1, 0.1\n"), {"dry.csv:2", "below the surface"});
    refused(file("text.csv", "-1, deep\n-1, -1\n"), {"text.csv:1", "comma-separated numbers"});
    refused(file("one.csv", "-1, -1\n"), {"at least 2 x 2", "2 x 1"});
    refused("[sea]\nmodel = \"bem\"\ndims = 2\ncells = [8, 4]\nbottom_file = \"/dev/zero\"\n", {"not a regular file"});
    refused("[sea]\nmodel = \"bem\"\ndims = 2\ncells = [8, 4]\nbottom_file = \"missing.csv\"\n", {"/tmp/missing.csv", "not found"});
    file("ok2.csv", "-1, -1\n-1, -1\n");
    refused("[sea]\nmodel = \"bem\"\ndims = 1\ndepth = 1.0\nbottom_file = \"" + dir + "/ok2.csv\"\n",
            {"[sea] bottom_file", "needs model = \"bem\" with dims = 2"});
    refused("[sea]\nmodel = \"bem\"\ndims = 2\ncells = [8, 4]\nbottom = [[0.0, -1.0], [200.0, -1.0]]\nbottom_file = \"" +
                dir + "/ok2.csv\"\n",
            {"bottom or bottom_file, not both"});
    // The same grid in HDF5: /z (ny, nx) with its grid /x, /y spanning the basin (200 m x 200 m by default).
    auto h5file = [&](const std::string& name, std::vector<hsize_t> zd, const std::vector<double>& z,
                      const std::vector<double>& x, const std::vector<double>& y, bool with_y = true) {
      h5::Handle f = h5::create_file(dir + "/" + name);
      h5::write_doubles(f, "z", zd, z.data());
      h5::write_doubles(f, "x", {x.size()}, x.data());
      if (with_y) h5::write_doubles(f, "y", {y.size()}, y.data());
      return "[sea]\nmodel = \"bem\"\ndims = 2\ncells = [8, 4]\nbottom_file = \"" + dir + "/" + name + "\"\n";
    };
    const std::vector<double> z = {-1.0, -0.5, -0.2, -1.0, -0.6, -0.3}, x = {0.0, 100.0, 200.0}, y = {0.0, 200.0};
    const Config h = parse(h5file("ok.h5", {2, 3}, z, x, y));
    CHECK(h.sea.bottom_nx == 3);
    CHECK(h.sea.bottom_ny == 2);
    CHECK(h.sea.bottom_grid == c.sea.bottom_grid);
    refused(h5file("flat.h5", {6}, z, x, y), {"[sea] bottom_file", "flat.h5: dataset /z", "2-D grid"});
    refused(h5file("dry.h5", {2, 3}, {-1.0, -0.5, -0.2, -1.0, 0.6, -0.3}, x, y),
            {"dry.h5: dataset /z", "below the surface", "got 0.6 at [1, 1]"});
    refused(h5file("noy.h5", {2, 3}, z, x, y, false), {"noy.h5: dataset '/y' is missing"});
    refused(h5file("shortx.h5", {2, 3}, z, {0.0, 200.0}, y), {"shortx.h5: dataset /x", "expected 3 coordinates"});
    refused(h5file("skew.h5", {2, 3}, z, {0.0, 120.0, 200.0}, y),
            {"skew.h5: dataset /x", "evenly spaced from 0 to 200 m", "got 120 at 1"});
    refused(h5file("small.h5", {2, 3}, z, x, {0.0, 100.0}), {"small.h5: dataset /y", "from 0 to 200 m"});
    std::filesystem::remove_all(dir);
  }
  // A bem basin's bottom: below the surface, x increasing, spanning [0, Lx].
  const std::string bem = "[sea]\nmodel = \"bem\"\ndims = 1\nsize = [1.0, 0.1]\ncells = [32, 1]\n";
  refused(bem + "bottom = [[0.0, -0.1], [0.5, 0.02], [1.0, -0.1]]\n",
          {"case.toml:6", "[sea] bottom", "below the surface", "point 1 is (0.5, 0.02) m"});
  refused(bem + "bottom = [[0.2, -0.1], [1.0, -0.1]]\n", {"[sea] bottom", "covers x in [0.2, 1] m", "span the basin [0, 1] m"});
  refused(bem + "bottom = [[0.0, -0.1], [0.5, -0.1], [0.5, -0.2], [1.0, -0.1]]\n", {"x must increase", "point 2 at x = 0.5 m"});
  refused(bem + "bottom = [[0.0, -0.1]]\n", {"at least 2 points", "got 1 point(s)"});
  refused("[sea]\nmodel = \"spectral\"\nbottom = [[0.0, -0.1], [1.0, -0.1]]\n", {"[sea] bottom", "needs model = \"bem\""});
  CHECK(parse(bem + "bottom = [[0.0, -0.1], [1.2, -0.1]]\n").sea.bottom.size() == 2);
  // Tank zones: the spectral sea, a regular wave (checked here only: fluid/sea.hpp asserts them).
  refused(bem + "[sea.tank]\nenabled = true\n", {"[sea.tank] enabled", "need model = \"spectral\""});
  refused("[sea]\nmodel = \"spectral\"\n[sea.tank]\nenabled = true\n", {"[sea.tank] enabled", "kind = \"regular\""});
  refused("[sea.waves]\nkind = \"regular\"\n", {"[sea.waves] kind", "wavelength or a period"});
  refused("[run\n", {"case.toml:1", "not valid TOML"});
  // At most kMaxRecords records: output_interval = 1e-320 would write records without end.
  refused("[run]\nt_end = 10\noutput_interval = 1e-320\n", {"case.toml:3", "[run] output_interval", ">= 1e-06 s",
                                                                "at most 10000000 records"});
  refused("[run]\nt_end = 1e9\noutput_interval = 1\n", {"case.toml:3", "[run] output_interval", "1000000002 records"});
}

TEST_CASE("a configuration that never ends (/dev/zero) is refused at a bound and not read into memory") {
  CHECK_THROWS_WITH_AS(load_config("/dev/zero"), doctest::Contains("/dev/zero: larger than 64 MiB"), InputError);
  // The same device as a forcing series (tests/data/fuzz/config/series_dev_zero.toml,
  // found by fuzz/fuzz_config): named by the key.
  CHECK_THROWS_WITH_AS(parse("[forcing]\nseries = \"/dev/zero\"\n"),
                       doctest::Contains("key '[forcing] series': /dev/zero: the forcing series is not a regular file"),
                       InputError);
}

TEST_CASE("the bound on records: kMaxRecords records up to t_end") {
  CHECK(record_count_problem(1e7 - 2, 1.0).empty());  // t = 0, 1, ..., 1e7 - 2 and t_end: kMaxRecords
  CHECK(!record_count_problem(1e7 - 1, 1.0).empty());
  CHECK(record_count_problem(1e7 - 1, 1.0).find("got 1 s: 10000001 records") != std::string::npos);
  CHECK(record_count_problem(0, 1e-300).empty());     // t_end = 0: two records
  CHECK(parse("[run]\nt_end = 3600\noutput_interval = 0.001\n").run.output_interval == 0.001);
}

TEST_CASE("the resolved configuration parses back to the same values") {
  const Config c = parse("[run]\nt_end = 3\n[[floes.floe]]\nvertices = [[0,0],[1,0],[1,1]]\n"
                         "[coupling]\nlaw = \"blend\"\nrestitution = 0.3\n");
  const std::string text = resolved_toml(c);
  const Config d = parse(text);
  CHECK(d.run.t_end == 3.0);
  CHECK(d.floes.floes.size() == 1);
  CHECK(d.coupling.restitution == 0.3);
  CHECK(resolved_toml(d) == text);
}

TEST_SUITE_END();
