// Pack files (ours and FloeDyn's) and run files.
#include <doctest/doctest.h>

#include <hdf5.h>

#include <cmath>
#include <filesystem>

#include "core/error.hpp"
#include "core/floes.hpp"
#include "core/pack.hpp"
#include "core/run_file.hpp"

using namespace floesim;
namespace fs = std::filesystem;

TEST_SUITE_BEGIN("core");

namespace {
const std::string kShared = FLOESIM_SHARED_DIR;

Floes load(const Pack& p) {
  Floes f;
  for (const FloeInput& in : p.floes) f.add(make_floe_shape(in), in);
  return f;
}
std::string tmp(const std::string& name) { return (fs::temp_directory_path() / name).string(); }
}  // namespace

TEST_CASE("FloeDyn's 100-floe example loads with masses 917 h A") {
  const Pack p = read_pack(kShared + "/data/floedyn/in_example_100_floes.h5");
  CHECK(p.format == "floedyn");
  REQUIRE(p.floes.size() == 100);
  REQUIRE(p.window.has_value());
  const Floes f = load(p);
  double amin = 1e300, amax = 0;
  for (std::size_t i = 0; i < f.size(); ++i) {
    CHECK(f.vertices(i).size() == 25);
    CHECK(f.mass[i] == doctest::Approx(917.0 * f.thickness[i] * f.area[i]).epsilon(1e-14));
    // C_w attribute: the floe's own ocean drag coefficient (0.00490–0.00513 in this file).
    CHECK(f.ocean_drag[i] >= 0.00490);
    CHECK(f.ocean_drag[i] <= 0.00514);  // the README rounds 0.0051348 to 0.00513
    amin = std::min(amin, f.area[i]);
    amax = std::max(amax, f.area[i]);
  }
  // README: areas 207–98,043 m^2.
  CHECK(amin == doctest::Approx(207).epsilon(0.01));
  CHECK(amax == doctest::Approx(98043).epsilon(0.01));
}

TEST_CASE("FloeDyn single floe: floe 54's area and thickness as the README states") {
  const Floes f = load(read_pack(kShared + "/data/floedyn/one_floe.h5"));
  REQUIRE(f.size() == 1);
  CHECK(f.area[0] == doctest::Approx(595.1301036).epsilon(1e-9));
  CHECK(f.thickness[0] == doctest::Approx(0.9822713709408214).epsilon(1e-12));
  CHECK(f.ocean_drag[0] == doctest::Approx(0.004911356854704107).epsilon(1e-12));
}

TEST_CASE("our pack format round-trips") {
  Floes a;
  FloeInput in;
  in.vertices = {{0, 0}, {3, 0}, {3, 2}, {1, 3}, {0, 2}};
  in.velocity = {0.1, -0.2};
  in.angular_velocity = 0.01;
  in.thickness = 1.5;
  in.ocean_drag = 0.004;
  a.add(make_floe_shape(in), in);
  in.is_static = true;
  in.velocity = {0, 0};
  in.angular_velocity = 0;
  in.vertices = {{10, 0}, {12, 0}, {12, 1}};
  a.add(make_floe_shape(in), in);
  a.state[0].yaw = 0.3;
  const std::string p = tmp("floesim_roundtrip_pack.h5");
  write_pack(p, a, std::array<double, 4>{0, 20, 0, 10});
  const Pack pk = read_pack(p);
  CHECK(pk.format == "floesim-pack-1");
  const Floes b = load(pk);
  REQUIRE(b.size() == 2);
  for (std::size_t i = 0; i < 2; ++i) {
    CHECK(b.state[i].x == doctest::Approx(a.state[i].x));
    CHECK(b.state[i].y == doctest::Approx(a.state[i].y));
    CHECK(b.state[i].yaw == doctest::Approx(a.state[i].yaw));
    CHECK(b.mass[i] == doctest::Approx(a.mass[i]));
    CHECK(b.is_static[i] == a.is_static[i]);
  }
  CHECK(b.state[0].vy == doctest::Approx(-0.2));
  CHECK(b.ocean_drag[0] == doctest::Approx(0.004));
  CHECK((*pk.window)[1] == 20.0);
}

TEST_CASE("a file that is not a pack is refused by name") {
  const std::string p = tmp("floesim_not_a_pack.h5");
  {
    hid_t f = H5Fcreate(p.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
    H5Fclose(f);
  }
  CHECK_THROWS_WITH_AS(read_pack(p), doctest::Contains("not a floe pack"), InputError);
  const std::string txt = tmp("floesim_text.h5");
  { std::FILE* f = std::fopen(txt.c_str(), "w"); std::fputs("hello", f); std::fclose(f); }
  CHECK_THROWS_WITH_AS(read_pack(txt), doctest::Contains("not an HDF5 file"), InputError);
}

TEST_CASE("run file: records are readable, compare detects differences") {
  Floes f;
  FloeInput in;
  in.vertices = {{0, 0}, {2, 0}, {2, 2}, {0, 2}};
  f.add(make_floe_shape(in), in);
  const std::string a = tmp("floesim_run_a.h5"), b = tmp("floesim_run_b.h5");
  for (const std::string& path : {a, b}) {
    RunWriter w(path, f, "[run]\n", {"floes_kinetic", "total"});
    for (int k = 0; k < 3; ++k) {
      Floes g = f;
      g.state[0].x += k * (path == b && k == 2 ? 1.001 : 1.0);
      const double e[2] = {double(k), double(k)};
      w.record(k * 0.5, g, e, {});
    }
    w.finish("complete");
  }
  const RunInfo info = read_run_info(a);
  CHECK(info.format == "floesim-1");
  CHECK(info.status == "complete");
  CHECK(info.records == 3);
  CHECK(info.t_last == 1.0);
  CHECK(info.floes == 1);
  CHECK(info.energy_columns.back() == "total");
  CHECK(info.energy_last.back() == 2.0);
  CHECK(fs::exists(fs::path(a).replace_extension(".xmf")));

  CHECK(compare_runs(a, a, {}).equal());
  const CompareResult r = compare_runs(a, b, {});
  CHECK_FALSE(r.equal());
  bool state_differs = false;
  for (const auto& d : r.differences) state_differs = state_differs || d.dataset == "/floes/state";
  CHECK(state_differs);
  CHECK(compare_runs(a, b, {.rtol = 1e-2, .atol = 1e-2}).equal());
}

TEST_SUITE_END();
