// The run loop and a comparison against FloeDyn on its own single-floe case.
#include <doctest/doctest.h>

#include <hdf5.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "core/error.hpp"
#include "core/run_file.hpp"
#include "coupling/run.hpp"

using namespace floesim;
namespace fs = std::filesystem;

TEST_SUITE_BEGIN("coupling");

namespace {
const std::string kData = FLOESIM_DATA_DIR;

std::vector<std::array<double, 6>> read_reference(const std::string& path) {
  std::ifstream in(path);
  std::string line;
  std::vector<std::array<double, 6>> rows;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#' || line[0] == 't') continue;
    std::array<double, 6> r{};
    std::stringstream ss(line);
    for (double& x : r) {
      std::string f;
      std::getline(ss, f, ',');
      x = std::stod(f);
    }
    rows.push_back(r);
  }
  return rows;
}
}  // namespace

TEST_CASE("single floe under FloeDyn's forcing follows FloeDyn's trajectory") {
  // Reference: data/floedyn/single_floe_check.csv, FloeDyn (forward Euler, dt = 10 s)
  // on floe 54 of its example, with its per-minute forcing (held constant over each minute),
  // rho_w = 1024.071, Coriolis at 80.207 N with Omega = 7.292e-5 (README of that folder).
  // Our scheme (linearised backward Euler for drag) differs from forward Euler by O(dt) in
  // transients, so the comparison is at the level of that discretisation difference.
  const double f = 2 * 7.292e-5 * std::sin(80.207 * M_PI / 180);
  std::ostringstream t;
  t.precision(17);
  t << "[run]\nt_end = 60000\ndt_max = 10\noutput_interval = 60\n[sea]\nrho = 1024.071\n"
    << "[floes]\npack = \"" << kData << "/floedyn/one_floe.h5\"\n"
    << "[forcing]\nseries = \"" << kData << "/floedyn/topaz_forcing_minutes_day1.csv\"\n"
    << "series_interpolation = \"previous\"\ncoriolis = " << f << "\nair_drag = 1.7e-3\nair_density = 1.341\n";
  Simulation sim(build_scenario(parse_config(t.str(), "floedyn_single.toml", ".")));
  const auto ref = read_reference(kData + "/floedyn/single_floe_check.csv");
  REQUIRE(ref.size() == 1001);  // t = 0, 60, ..., 60000 s
  double max_speed = 0, max_dv = 0, max_dx = 0, max_dist = 0;
  for (const auto& r : ref) {
    while (sim.time() < r[0]) sim.step(r[0]);
    const FloeState& s = sim.floes().state[0];
    max_speed = std::max(max_speed, std::hypot(r[3], r[4]));
    max_dv = std::max(max_dv, std::hypot(s.vx - r[3], s.vy - r[4]));
    max_dx = std::max(max_dx, std::hypot(s.x - r[1], s.y - r[2]));
    max_dist = std::max(max_dist, std::hypot(r[1], r[2]));
  }
  MESSAGE("max speed " << max_speed << " m/s, max |dv| " << max_dv << " m/s; distance " << max_dist
                       << " m, max |dx| " << max_dx << " m");
  CHECK(max_dv < 1e-3 * max_speed);  // measured: 2.0e-4 m/s of 0.283 m/s
  CHECK(max_dx < 1e-4 * max_dist);   // measured: 0.47 m over 7630 m
}

TEST_CASE("the run loop records on schedule and the file holds the state") {
  const std::string out = (fs::temp_directory_path() / "floesim_loop.h5").string();
  const std::string text =
      "[run]\nt_end = 10\ndt_max = 0.3\noutput_interval = 2.5\n"
      "[[floes.floe]]\nvertices = [[0,0],[4,0],[4,3],[0,3]]\nvelocity = [0.2, 0.1]\n"
      "[forcing]\ncurrent = [0.1, 0]\n";
  Simulation sim(build_scenario(parse_config(text, "loop.toml", ".")));
  std::size_t calls = 0;
  const RunSummary s = run_simulation(sim, {out, -1.0, [&](const RunProgress&) { ++calls; }, {}});
  CHECK(s.status == "complete");
  CHECK(s.records == 5);  // t = 0, 2.5, 5, 7.5, 10
  CHECK(calls == s.steps);
  CHECK(sim.time() == 10.0);
  const RunInfo info = read_run_info(out);
  CHECK(info.status == "complete");
  CHECK(info.records == 5);
  CHECK(info.t_last == 10.0);
  CHECK(info.config.find("output_interval = 2.5") != std::string::npos);

  // The last record of /floes/state is the final state.
  hid_t f = H5Fopen(out.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  hid_t d = H5Dopen2(f, "/floes/state", H5P_DEFAULT);
  std::vector<double> st(5 * 12);
  H5Dread(d, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, st.data());
  H5Dclose(d);
  H5Fclose(f);
  CHECK(st[4 * 12 + 0] == sim.floes().state[0].x);
  CHECK(st[4 * 12 + 3] == sim.floes().state[0].vx);
  CHECK(st[0 * 12 + 0] == doctest::Approx(2.0));  // centroid at t = 0

  // An interrupted run ends with the last state recorded and says so.
  Simulation again(build_scenario(parse_config(text, "loop.toml", ".")));
  std::size_t n = 0;
  const RunSummary i = run_simulation(again, {out, -1.0, {}, [&] { return ++n == 7; }});
  CHECK(i.status == "interrupted");
  const RunInfo ii = read_run_info(out);
  CHECK(ii.status.rfind("interrupted", 0) == 0);
  CHECK(ii.t_last == doctest::Approx(again.time()));
}

TEST_CASE("a numerical failure marks the run file failed and keeps the records") {
  const std::string out = (fs::temp_directory_path() / "floesim_fail.h5").string();
  // Valid input whose numerics overflow: a 1e200 m/s wind (finite, so accepted; floes faster
  // than 1000 m/s are refused at load) has an air drag |U| U that overflows, which gives a
  // non-finite velocity in the first step, which the step's state check turns into a RunError.
  const std::string text =
      "[run]\nt_end = 10\ndt_max = 1\noutput_interval = 1\n"
      "[[floes.floe]]\nvertices = [[0,0],[1,0],[1,1],[0,1]]\n"
      "[forcing]\nwind = [1e200, 0]\n";
  Simulation sim(build_scenario(parse_config(text, "fail.toml", ".")));
  CHECK_THROWS_AS(run_simulation(sim, {out, -1.0, {}, {}}), RunError);
  const RunInfo info = read_run_info(out);
  CHECK(info.status.rfind("failed:", 0) == 0);
  CHECK(info.records == 1);
}

TEST_CASE("a wave-only run writes the sea elevation and keeps the sea's energy") {
  // Free linear waves: the modal flow is exact, so the sea energy is conserved to round-off;
  // a progressive wave has equal kinetic and potential energy, each rho g a^2 / 4 per unit area.
  const std::string out = (fs::temp_directory_path() / "floesim_waves.h5").string();
  const std::string text =
      "[run]\nt_end = 20\ndt_max = 0.1\noutput_interval = 1\n"
      "[sea]\nmodel = \"spectral\"\ndims = 2\nsize = [200.0, 100.0]\ncells = [64, 32]\ndepth = 40.0\n"
      "[sea.waves]\nkind = \"regular\"\namplitude = 0.25\nwavelength = 20.0\n";
  Simulation sim(build_scenario(parse_config(text, "waves.toml", ".")));
  REQUIRE(sim.has_sea());
  const RunSummary s = run_simulation(sim, {out, -1.0, {}, {}});
  CHECK(s.steps == 200);
  const Energies& a = s.energy_first;
  const Energies& b = s.energy_last;
  REQUIRE(a.names == std::vector<std::string>{"floes_horizontal_kinetic", "sea_kinetic", "sea_potential", "total"});
  const double per_part = 1025.0 * 9.81 * 0.25 * 0.25 / 4.0 * 200.0 * 100.0;
  CHECK(a.values[2] == doctest::Approx(per_part).epsilon(1e-3));
  CHECK(a.values[1] == doctest::Approx(a.values[2]).epsilon(1e-3));
  CHECK(b.values[3] == doctest::Approx(a.values[3]).epsilon(1e-10));
  const RunInfo info = read_run_info(out);
  bool has_eta = false;
  for (const auto& [path, shape] : info.datasets)
    if (path == "/sea/eta") has_eta = shape == std::vector<unsigned long long>{21, 32, 64};
  CHECK(has_eta);
}

TEST_SUITE_END();

TEST_CASE("the run file and floesim info hold the collision sub-stepper's counts") {
  // Two 10 m squares close at 1 m/s across a 5 m gap and meet within the first 10 s step (the
  // multirate case of test_collisions.cpp): one cluster of 2 floes, sub-stepped up to the impact
  // and on to the end of the step; the second step has no collision. /diagnostics/substeps must
  // hold, at each record, the counts Simulation::substep_report() had then.
  const std::string out = (fs::temp_directory_path() / "floesim_substeps.h5").string();
  const std::string text =
      "[run]\nt_end = 20\ndt_max = 10\noutput_interval = 10\n"
      "[contact]\nrestitution = 0.4\nfriction = 0.7\ncollision_distance = 0.01\n"
      "[forcing]\nocean_drag = 0\nair_drag = 0\n"
      "[[floes.floe]]\nvertices = [[-5.0, -5.0], [5.0, -5.0], [5.0, 5.0], [-5.0, 5.0]]\nvelocity = [0.5, 0.0]\n"
      "[[floes.floe]]\nvertices = [[10.0, -5.0], [20.0, -5.0], [20.0, 5.0], [10.0, 5.0]]\nvelocity = [-0.5, 0.0]\n";
  Simulation sim(build_scenario(parse_config(text, "substeps.toml", ".")));
  const RunSummary s = run_simulation(sim, {out, -1.0, {}, {}});
  REQUIRE(s.status == "complete");
  const contact::SubstepReport& r = sim.substep_report();
  REQUIRE(r.clusters == 1);
  REQUIRE(r.substeps >= 2);

  const RunDataset d = read_run_dataset(out, "/diagnostics/substeps");
  REQUIRE(d.shape == std::vector<unsigned long long>{3, kSubstepColumns});  // t = 0, 10, 20
  REQUIRE(d.columns == std::vector<std::string>(std::begin(kSubstepColumnNames), std::end(kSubstepColumnNames)));
  auto at = [&](std::size_t record, const std::string& column) {
    const auto c = std::find(d.columns.begin(), d.columns.end(), column) - d.columns.begin();
    return d.values[record * kSubstepColumns + static_cast<std::size_t>(c)];
  };
  for (const std::string& c : d.columns) CHECK(at(0, c) == 0.0);  // nothing before the first step
  CHECK(at(1, "clusters") == 1.0);
  CHECK(at(1, "largest_cluster") == 2.0);
  CHECK(at(1, "substeps") == static_cast<double>(r.substeps));
  CHECK(at(2, "clusters") == static_cast<double>(r.clusters));  // the second step added none
  CHECK(at(2, "substeps") == static_cast<double>(r.substeps));
  CHECK(at(2, "time_steps") == static_cast<double>(r.time_steps));
  CHECK(at(2, "merges") == static_cast<double>(r.merges));
  CHECK(at(2, "floor_steps") == 0.0);

  // floesim info reads the last record.
  const RunInfo info = read_run_info(out);
  CHECK(info.substeps_last[0] == 1.0);
  CHECK(info.substeps_last[1] == static_cast<double>(r.substeps));
  CHECK(info.substeps_last[3] == 2.0);
}
