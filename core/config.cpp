// The configuration file read into Config (core/config.hpp): one reader per
// table, each key checked once, here, by the Section reader
// (core/detail/toml_section.hpp); then the rules that tie tables together.
#include "core/config.hpp"

#include <toml++/toml.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <numbers>
#include <sstream>

#include "core/detail/config_names.hpp"
#include "core/detail/h5.hpp"
#include "core/detail/toml_section.hpp"
#include "core/error.hpp"
#include "core/forcing.hpp"

namespace floesim {

namespace {

namespace fs = std::filesystem;
using namespace detail;

// A path the system cannot look at (too long, say) does not exist: the
// error_code overloads answer false where the others would throw.
bool path_exists(const std::string& path) {
  std::error_code ec;
  return fs::exists(path, ec) && !ec;
}
bool is_folder(const std::string& path) {
  std::error_code ec;
  return fs::is_directory(path, ec) && !ec;
}


std::string resolve_path(const std::string& p, const std::string& base_dir) {
  if (p.empty()) return p;
  fs::path path(p);
  if (path.is_relative()) path = fs::path(base_dir) / path;
  return path.lexically_normal().string();
}

void read_run(Section s, RunParams& r) {
  r.t_end = s.number("t_end", r.t_end, non_negative, "a time >= 0 (s)");
  r.dt_max = s.number("dt_max", r.dt_max, positive, "a time step > 0 (s)");
  r.output_interval = s.number("output_interval", r.output_interval, positive, "an interval > 0 (s)");
  if (const std::string problem = record_count_problem(r.t_end, r.output_interval); !problem.empty())
    s.fail("output_interval", problem);
  if (const std::string problem = step_count_problem(r.t_end, r.dt_max); !problem.empty()) s.fail("dt_max", problem);
  r.seed = static_cast<unsigned long>(
      s.integer("seed", static_cast<long long>(r.seed), [](long long v) { return v >= 0; }, "a seed >= 0"));
  r.threads = static_cast<int>(s.integer("threads", r.threads, [](long long v) { return v >= 0 && v <= 1024; },
                                         "a thread count in [0, 1024] (0: OMP_NUM_THREADS if set, else one per core)"));
  r.checkpoint_interval = s.number("checkpoint_interval", r.checkpoint_interval,
                                   [](double v) { return std::isfinite(v) && v >= 0.0; },
                                   "an interval >= 0 (s; 0: a checkpoint only at the end)");
  r.record_collisions = s.boolean("record_collisions", r.record_collisions);
  r.advance_on_part = s.boolean("advance_on_part", r.advance_on_part);
  r.crash_safe_output = s.boolean("crash_safe_output", r.crash_safe_output);
  s.finish();
}

void read_waves(Section s, WaveParams& w) {
  w.kind = s.choice("kind", w.kind, kWaveKinds);
  w.amplitude = s.number("amplitude", w.amplitude, non_negative, "an amplitude >= 0 (m)");
  w.wavelength = s.number("wavelength", w.wavelength, non_negative, "a wavelength > 0 (m)");
  w.period = s.number("period", w.period, non_negative, "a period > 0 (s)");
  w.direction = s.number("direction", w.direction, finite, "an angle (degrees from +x)");
  w.hs = s.number("hs", w.hs, non_negative, "a significant wave height >= 0 (m)");
  w.tp = s.number("tp", w.tp, non_negative, "a peak period > 0 (s)");
  w.gamma = s.number("gamma", w.gamma, [](double v) { return v >= 1.0 && v < 100.0; },
                     "a peak enhancement factor in [1, 100)");
  w.spreading = s.number("spreading", w.spreading, non_negative, "a spreading exponent >= 0");
  if (s.has("wavelength") && s.has("period"))
    s.fail("period", "give wavelength or period, not both");
  if ((w.kind == WaveKind::regular || w.kind == WaveKind::standing) && w.wavelength <= 0.0 &&
      w.period <= 0.0)
    s.fail("kind", "regular and standing waves need a wavelength or a period > 0");
  if (w.kind == WaveKind::jonswap && (w.hs <= 0.0 || w.tp <= 0.0))
    s.fail("kind", "jonswap needs hs > 0 and tp > 0");
  s.finish();
}

// The bottom grid of [sea] bottom_file in HDF5: a dataset /z of shape
// (ny, nx), z[j][i] the bottom at (x[i], y[j]) (finite, < 0), with its grid:
// /x (nx values) and /y (ny values), evenly spaced from 0 to Lx and Ly (the
// grid spans the basin, as the CSV's does). Fails through `fail` naming the
// file and the dataset at fault.
template <class Fail>
void read_bottom_grid_h5(SeaParams& p, Fail&& fail) {
  const std::string& path = p.bottom_file;
  auto num = [](double v) { std::ostringstream o; o << v; return o.str(); };
  // In the read (which may run in a child process) failures are plain InputErrors;
  // they reach `fail` below.
  auto bad = [](const std::string& m) { throw InputError(m); };
  auto read = [&] {
    h5::Handle file = h5::open_file(path);
    h5::Handle z = h5::open_dataset(file, "/z", path);
    const std::vector<hsize_t> d = h5::dims(z);
    if (d.size() != 2 || d[0] < 2 || d[1] < 2)
      bad(path + ": dataset /z: expected a 2-D grid of at least 2 x 2 depths, shape (ny, nx), x fastest");
    // As for the CSV: no larger than any grid a dense 3D basin could use (16 MiB of doubles).
    if (static_cast<double>(d[0]) * static_cast<double>(d[1]) > static_cast<double>(std::size_t{1} << 21))
      bad(path + ": dataset /z: expected at most 2097152 depths, got " + num(static_cast<double>(d[0])) + " x " +
           num(static_cast<double>(d[1])));
    std::vector<double> grid = h5::read_doubles(z, path + ": dataset /z");
    const int ny = static_cast<int>(d[0]), nx = static_cast<int>(d[1]);
    for (std::size_t k = 0; k < grid.size(); ++k)
      if (!(std::isfinite(grid[k]) && grid[k] < 0.0))
        bad(path + ": dataset /z: every depth must be finite and below the surface (z < 0), got " + num(grid[k]) +
             " at [" + std::to_string(k / static_cast<std::size_t>(nx)) + ", " +
             std::to_string(k % static_cast<std::size_t>(nx)) + "]");
    auto axis = [&](const std::string& name, int count, double length) {
      h5::Handle a = h5::open_dataset(file, name, path);
      const std::vector<hsize_t> da = h5::dims(a);
      const std::string what = path + ": dataset " + name;
      if (da.size() != 1 || da[0] != static_cast<hsize_t>(count))
        bad(what + ": expected " + std::to_string(count) + " coordinates (a 1-D dataset, one per node of /z)");
      const std::vector<double> c = h5::read_doubles(a, what);
      for (int i = 0; i < count; ++i) {
        const double want = length * i / (count - 1);
        if (!(std::abs(c[static_cast<std::size_t>(i)] - want) <= 1e-6 * length))
          bad(what + ": expected " + std::to_string(count) + " coordinates evenly spaced from 0 to " + num(length) +
               " m (the grid spans the basin), got " + num(c[static_cast<std::size_t>(i)]) + " at " +
               std::to_string(i) + " instead of " + num(want));
      }
    };
    axis("/x", nx, p.size[0]);
    axis("/y", ny, p.size[1]);
    p.bottom_grid = std::move(grid);
    p.bottom_nx = nx;
    p.bottom_ny = ny;
  };
  try {
    // Read first in a child process: a file that crashes HDF5 is refused.
    h5::refuse_if_read_crashes(path, read);
    read();
  } catch (const InputError& e) {
    fail(e.what());
  }
}

// The bottom grid of [sea] bottom_file: one line per row of nodes (y from 0),
// comma-separated depths z < 0 (x from 0); blank lines and lines starting with
// '#' are skipped. Fails through `fail` with the line that is wrong.
template <class Fail>
void read_bottom_grid(SeaParams& p, Fail&& fail) {
  // A folder, a device or a pipe is refused (/dev/zero would be one endless line), and so is a
  // file larger than any grid a dense 3D basin could use.
  std::error_code ec;
  if (!fs::is_regular_file(p.bottom_file, ec))
    fail(p.bottom_file + ": not found or not a regular file; expected a CSV or HDF5 grid of depths");
  if (fs::file_size(p.bottom_file, ec) > (std::uintmax_t{16} << 20))
    fail(p.bottom_file + ": larger than 16 MiB; expected a CSV grid of depths");
  std::ifstream in(p.bottom_file);
  if (!in) fail("cannot read the file " + p.bottom_file);
  std::string line;
  int line_no = 0;
  p.bottom_grid.clear();
  p.bottom_nx = p.bottom_ny = 0;
  while (std::getline(in, line)) {
    ++line_no;
    const auto first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos || line[first] == '#') continue;
    int count = 0;
    std::size_t pos = 0;
    while (pos <= line.size()) {
      const std::size_t comma = std::min(line.find(',', pos), line.size());
      const std::string field = line.substr(pos, comma - pos);
      char* end = nullptr;
      const double z = std::strtod(field.c_str(), &end);
      if (end == field.c_str() || field.find_first_not_of(" \t\r", static_cast<std::size_t>(end - field.c_str())) != std::string::npos)
        fail(p.bottom_file + ":" + std::to_string(line_no) + ": expected comma-separated numbers, got \"" + field + "\"");
      if (!(std::isfinite(z) && z < 0.0))
        fail(p.bottom_file + ":" + std::to_string(line_no) + ": every depth must be finite and below the surface (z < 0), got " + field);
      p.bottom_grid.push_back(z);
      ++count;
      pos = comma + 1;
    }
    if (p.bottom_ny == 0) p.bottom_nx = count;
    if (count != p.bottom_nx)
      fail(p.bottom_file + ":" + std::to_string(line_no) + ": expected " + std::to_string(p.bottom_nx) +
           " values as on the first row, got " + std::to_string(count));
    ++p.bottom_ny;
  }
  if (p.bottom_nx < 2 || p.bottom_ny < 2)
    fail(p.bottom_file + ": expected a grid of at least 2 x 2 depths (rows along x, one row per y), got " +
         std::to_string(p.bottom_nx) + " x " + std::to_string(p.bottom_ny));
}

void read_sea(Section s, SeaParams& p, const std::string& file, const std::string& base_dir) {
  p.model = s.choice("model", p.model, kSeaModels);
  p.dims = static_cast<int>(s.integer("dims", p.dims, [](long long v) { return v == 1 || v == 2; }, "1 or 2"));
  p.size = s.pair("size", p.size, "[Lx, Ly], two sizes > 0 (m)");
  if (!(p.size[0] > 0.0 && p.size[1] > 0.0 && p.size[0] <= kMaxCoordinate && p.size[1] <= kMaxCoordinate)) {
    std::ostringstream m;
    m << "expected two sizes > 0 and <= " << kMaxCoordinate << " m, got [" << p.size[0] << ", " << p.size[1] << "]";
    s.fail("size", m.str());
  }
  if (s.has("cells")) {
    auto c = s.numbers("cells", 2, "[nx, ny], two cell counts >= 1");
    for (double v : c)
      if (!(v >= 1.0 && v == std::floor(v) && v < 1e6)) s.fail("cells", "expected two whole cell counts in [1, 1e6)");
    p.cells = {static_cast<int>(c[0]), static_cast<int>(c[1])};
    // The grid is allocated whole (some twenty numbers per cell): bounded here.
    const double total = p.dims == 2 ? c[0] * c[1] : c[0];
    if (total > kMaxSeaCells) {
      std::ostringstream m;
      m << "expected at most " << static_cast<long long>(kMaxSeaCells) << " cells in all (4096 x 4096), got "
        << total;
      s.fail("cells", m.str());
    }
  } else {
    s.node("cells");
  }
  p.bem_modes = static_cast<int>(s.integer("bem_modes", p.bem_modes, [](long long v) { return v >= 0 && v < 1000000; },
                                           "a number of modes >= 0 (0: all)"));
  if (p.model == SeaModel::bem && p.dims == 2) {
    // The 3D basin's set-up is a dense LU, then all modes (dense eigenproblem)
    // or the lowest (Lanczos): fluid/bem3d.hpp, cost in docs/sea.md.
    const double cells = static_cast<double>(p.cells[0]) * p.cells[1];
    const double most = p.bem_modes == 0 ? kMaxBem3dCells : kMaxBem3dLowestCells;
    if (cells > most) {
      std::ostringstream m;
      m << "model = \"bem\" with dims = 2 is a dense set-up: expected at most " << static_cast<long long>(most)
        << " surface cells in all" << (p.bem_modes == 0 ? " with all modes (bem_modes = 0)" : " with bem_modes > 0")
        << ", got " << cells << " (" << p.cells[0] << " x " << p.cells[1] << ")";
      if (p.bem_modes == 0) m << "; keep the lowest modes only with bem_modes = n (up to "
                              << static_cast<long long>(kMaxBem3dLowestCells) << " cells)";
      s.fail("cells", m.str());
    }
    if (p.bem_modes > 0 && p.bem_modes > cells - 2)
      s.fail("bem_modes", "expected at most " + std::to_string(static_cast<long long>(cells) - 2) +
                              " modes (surface cells - 2) on " + std::to_string(p.cells[0]) + " x " +
                              std::to_string(p.cells[1]) + " cells, got " + std::to_string(p.bem_modes));
  } else if (p.bem_modes != 0) {
    s.fail("bem_modes", "the lowest modes only apply to model = \"bem\" with dims = 2");
  }
  p.bem_static_correction = s.boolean("bem_static_correction", p.bem_static_correction);
  if (p.bem_static_correction && p.bem_modes == 0)
    s.fail("bem_static_correction",
           "corrects the lowest modes only (bem_modes = n > 0 on model = \"bem\" with dims = 2); with all modes "
           "there is nothing dropped to correct");
  p.depth = s.number("depth", p.depth, [](double v) { return v > 0.0; }, "a depth > 0 (m) or inf");
  p.rho = s.number("rho", p.rho, positive, "a density > 0 (kg/m^3)");
  p.g = s.number("g", p.g, positive, "a gravity > 0 (m/s^2)");
  p.sigma = s.number("sigma", p.sigma, non_negative, "a surface tension >= 0 (N/m)");
  p.bottom = s.points("bottom", "a polyline [[x, z], ...] (m)");
  if (!p.bottom.empty()) {
    // The basin's bottom (fluid/bem.hpp): below the surface, x increasing, spanning [0, Lx].
    if (p.model != SeaModel::bem) s.fail("bottom", "a bottom polyline needs model = \"bem\"");
    const auto& b = p.bottom;
    auto num = [](double v) { std::ostringstream o; o << v; return o.str(); };
    if (b.size() < 2)
      s.fail("bottom", "expected a polyline of at least 2 points [x, z] spanning the basin [0, " + num(p.size[0]) +
                           "] m, got " + std::to_string(b.size()) + " point(s)");
    for (std::size_t i = 0; i < b.size(); ++i) {
      if (!(std::isfinite(b[i][0]) && std::isfinite(b[i][1]) && b[i][1] < 0.0))
        s.fail("bottom", "every bottom point must be finite and below the surface (z < 0): point " +
                             std::to_string(i) + " is (" + num(b[i][0]) + ", " + num(b[i][1]) + ") m");
      if (i > 0 && !(b[i][0] > b[i - 1][0]))
        s.fail("bottom", "x must increase along the polyline (point " + std::to_string(i) + " at x = " +
                             num(b[i][0]) + " m)");
    }
    if (b.front()[0] > 0.0 || b.back()[0] < p.size[0])
      s.fail("bottom", "the polyline covers x in [" + num(b.front()[0]) + ", " + num(b.back()[0]) +
                           "] m but must span the basin [0, " + num(p.size[0]) + "] m");
  }
  p.bottom_file = resolve_path(s.string("bottom_file", ""), base_dir);
  if (!p.bottom_file.empty()) {
    if (!(p.model == SeaModel::bem && p.dims == 2))
      s.fail("bottom_file", "a bottom grid needs model = \"bem\" with dims = 2");
    if (!p.bottom.empty()) s.fail("bottom_file", "give bottom or bottom_file, not both");
    auto fail = [&](const std::string& m) { s.fail("bottom_file", m); };
    std::error_code ec;
    if (fs::is_regular_file(p.bottom_file, ec) && h5::is_hdf5(p.bottom_file))
      read_bottom_grid_h5(p, fail);
    else
      read_bottom_grid(p, fail);
  }
  read_waves(Section(s.table("waves"), "sea.waves", file), p.waves);
  {
    Section t(s.table("tank"), "sea.tank", file);
    TankConfig& k = p.tank;
    k.enabled = t.boolean("enabled", k.enabled);
    k.generation_length = t.number("generation_length", k.generation_length, non_negative, "a length >= 0 (m; 0: 3 wavelengths)");
    k.absorption_length = t.number("absorption_length", k.absorption_length, non_negative, "a length >= 0 (m; 0: 2 wavelengths)");
    k.rate = t.number("rate", k.rate, non_negative, "a rate >= 0 (1/s; 0: 4 omega)");
    k.ramp_periods = t.number("ramp_periods", k.ramp_periods, non_negative, "a number of periods >= 0");
    if (k.enabled && p.model != SeaModel::spectral && !(p.model == SeaModel::bem && p.dims == 2))
      t.fail("enabled", "tank zones need model = \"spectral\" (or \"bem\" with dims = 2)");
    if (k.enabled && p.waves.kind != WaveKind::regular)
      t.fail("enabled", "tank zones generate the regular wave of [sea.waves] (kind = \"regular\")");
    t.finish();
  }
  s.finish();
}

FloeInput read_floe(Section s, const PackDefaults& def, std::size_t index, const std::string& file) {
  FloeInput f;
  f.origin = where(file, s.line(), "", "") + "[[floes.floe]] " + std::to_string(index);
  auto pts = s.points("vertices", "an array of [x, y] vertices (m)");
  if (!s.has("vertices")) s.fail("vertices", "every [[floes.floe]] needs vertices = [[x, y], ...]");
  for (auto& p : pts) f.vertices.emplace_back(p[0], p[1]);
  auto v = s.pair("velocity", {0.0, 0.0});
  f.velocity = {v[0], v[1]};
  f.angular_velocity = s.number("angular_velocity", 0.0, finite, "an angular velocity (rad/s)");
  f.thickness = s.number("thickness", def.thickness, positive, "a thickness > 0 (m)");
  f.density = s.number("density", def.density, positive, "a density > 0 (kg/m^3)");
  f.is_static = s.boolean("static", false);
  f.heave = s.number("heave", 0.0, finite, "a heave (m, from floating equilibrium; with [coupling] start = \"given\")");
  f.heave_rate = s.number("heave_rate", 0.0, finite, "a heave rate (m/s; with [coupling] start = \"given\")");
  if (f.is_static && (f.heave != 0.0 || f.heave_rate != 0.0)) s.fail("static", "a static floe (obstacle) cannot heave");
  f.ocean_drag = s.number("ocean_drag", -1.0, non_negative, "a drag coefficient >= 0");
  f.mooring_period = s.number("mooring_period", 0.0, positive, "a mooring period > 0 (s)");
  f.mooring_damping = s.number("mooring_damping", 0.0, non_negative, "a damping ratio >= 0");
  if (s.has("mooring_damping") && !s.has("mooring_period"))
    s.fail("mooring_damping", "a mooring needs its mooring_period (s)");
  if (f.is_static && s.has("mooring_period")) s.fail("mooring_period", "a static floe (obstacle) cannot be moored");
  if (f.is_static && (s.has("velocity") || s.has("angular_velocity")) &&
      (f.velocity.norm() > 0.0 || f.angular_velocity != 0.0))
    s.fail("static", "a static floe (obstacle) cannot have a velocity");
  s.finish();
  return f;
}

void read_floes(Section s, FloesConfig& c, const std::string& file, const std::string& base_dir) {
  c.pack = resolve_path(s.string("pack", ""), base_dir);
  c.defaults.thickness = s.number("thickness", c.defaults.thickness, positive, "a thickness > 0 (m)");
  c.defaults.density = s.number("density", c.defaults.density, positive, "a density > 0 (kg/m^3)");
  if (!c.pack.empty() && !path_exists(c.pack)) s.fail("pack", "file not found: " + c.pack);
  if (const toml::array* a = s.table_array("floe")) {
    for (std::size_t i = 0; i < a->size(); ++i)
      c.floes.push_back(read_floe(Section((*a)[i].as_table(), "floes.floe", file), c.defaults, i, file));
  }
  s.finish();
}

void read_contact(Section s, ContactParams& c, const std::string& base_dir) {
  c.collision_distance = s.number("collision_distance", c.collision_distance, positive, "a distance > 0 (m)");
  c.restitution = s.number("restitution", c.restitution, unit_interval, "a restitution in [0, 1]");
  c.friction = s.number("friction", c.friction, non_negative, "a friction coefficient >= 0");
  c.rest_speed = s.number("rest_speed", c.rest_speed, non_negative, "a speed >= 0 (m/s)");
  c.periodic = s.choice("domain", c.periodic, kDomains);
  if (s.has("box")) {
    auto b = s.numbers("box", 4, "[xmin, xmax, ymin, ymax] (m)");
    if (!(b[1] > b[0] && b[3] > b[2])) s.fail("box", "expected xmin < xmax and ymin < ymax");
    c.box = {b[0], b[1], b[2], b[3]};
  } else {
    s.node("box");
  }
  c.dump_failed_lcps = resolve_path(s.string("dump_failed_lcps", ""), base_dir);
  if (s.has("dump_failed_lcps") && !is_folder(c.dump_failed_lcps))
    s.fail("dump_failed_lcps", "expected an existing folder, found none at " + c.dump_failed_lcps);
  s.finish();
}

void read_coupling(Section s, CouplingParams& c, SeaModel sea_model) {
  c.law = s.choice("law", c.law, kPenaltyLaws);
  c.stiffness = s.number("stiffness", c.stiffness, positive, "a relative stiffness K > 0");
  c.blend = s.number("blend", c.blend, unit_interval, "a blend s in [0, 1]");
  c.restitution = s.number("restitution", c.restitution, unit_interval, "a restitution in [0, 1]");
  if (s.has("blend") && s.has("restitution")) s.fail("restitution", "give blend or restitution, not both");
  if ((s.has("blend") || s.has("restitution")) && c.law != PenaltyLaw::blend)
    s.fail(s.has("blend") ? "blend" : "restitution", "only used with law = \"blend\"");
  if (!s.has("restitution")) c.restitution = -1.0;
  // "equilibrium": the floes at rest on the sea, then the waves; "given": the floes' heave as given.
  c.start_given = s.choice("start", c.start_given, kStarts);
  c.footprint = s.choice("footprint", c.footprint, kFootprints);
  if (c.footprint == FootprintChoice::tent && sea_model == SeaModel::bem)
    s.fail("footprint", "\"tent\" needs a periodic sea ([sea] model = \"spectral\"): a tent would reach past a bem "
                        "basin's walls; use \"cell\" or \"automatic\"");
  c.footprint_reach = s.number("footprint_reach", c.footprint_reach, [](double v) { return v >= 0.0 && v <= 0.5; },
                               "a fraction of a cell in [0, 0.5]");
  c.integrator = s.choice("integrator", c.integrator, kIntegrators);
  c.horizontal_loads = s.choice("horizontal_loads", c.horizontal_loads, kHorizontalLoads);
  c.newton_tolerance = s.number("newton_tolerance", c.newton_tolerance, positive, "a relative tolerance > 0");
  c.cg_tolerance = s.number("cg_tolerance", c.cg_tolerance, positive, "a relative tolerance > 0");
  c.cg_forcing = s.number("cg_forcing", c.cg_forcing, positive, "a relative tolerance > 0");
  s.finish();
}

void read_forcing(Section s, ForcingParams& f, const std::string& base_dir) {
  f.current = s.pair("current", f.current);
  f.wind = s.pair("wind", f.wind);
  f.series = resolve_path(s.string("series", ""), base_dir);
  if (!f.series.empty() && !path_exists(f.series)) s.fail("series", "file not found: " + f.series);
  f.series_interpolation = s.choice("series_interpolation", f.series_interpolation, kSeriesInterpolations);
  // The series is checked here, at load, by its reader (the one place of its rules), so that
  // a bad file is refused before any scenario is built; make_forcing reads it again.
  if (!f.series.empty()) {
    try {
      ForcingSeries::from_csv(f.series, f.series_interpolation);
    } catch (const InputError& e) {
      s.fail("series", e.what());
    }
  }
  f.coriolis = s.number("coriolis", f.coriolis, finite, "a Coriolis parameter f (1/s)");
  if (s.has("latitude")) {
    if (s.has("coriolis")) s.fail("latitude", "give coriolis (f) or latitude, not both");
    const double lat = s.number("latitude", 0.0, [](double v) { return v >= -90.0 && v <= 90.0; },
                                "a latitude in [-90, 90] degrees");
    // f = 2 Ω sin(latitude), Ω = 7.2921e-5 rad/s (sidereal rotation of the Earth).
    f.coriolis = 2.0 * 7.2921e-5 * std::sin(lat * std::numbers::pi / 180.0);
  } else {
    s.node("latitude");
  }
  f.ocean_drag = s.number("ocean_drag", f.ocean_drag, non_negative, "a drag coefficient >= 0");
  f.air_drag = s.number("air_drag", f.air_drag, non_negative, "a drag coefficient >= 0");
  f.air_density = s.number("air_density", f.air_density, non_negative, "a density >= 0 (kg/m^3)");
  s.finish();
}

void read_fracture(Section s, FractureParams& f, const std::string& file) {
  f.enabled = s.boolean("enabled", f.enabled);
  f.criterion = s.choice("criterion", f.criterion, kFractureCriteria);
  f.strength = s.number("strength", f.strength, positive, "a strength > 0 (Pa)");
  f.toughness = s.number("toughness", f.toughness, positive, "a toughness > 0 (J/m^2)");
  f.young = s.number("young", f.young, positive, "a Young's modulus > 0 (Pa)");
  f.poisson = s.number("poisson", f.poisson, [](double v) { return v > -1.0 && v < 0.5; },
                       "a Poisson ratio in (-1, 0.5)");
  f.split = s.boolean("split", f.split);
  f.mesh_size = s.number("mesh_size", f.mesh_size, positive, "a mesh size > 0 (m)");
  f.duration = s.number("duration", f.duration, positive, "a duration > 0 (s)");
  f.load_radius = s.number("load_radius", f.load_radius, non_negative, "a radius >= 0 (m; 0: the floe's thickness)");
  f.min_fragment_area = s.number("min_fragment_area", f.min_fragment_area, non_negative,
                                 "an area >= 0 (m^2; 0: mesh_size^2)");
  f.elements_across = s.number("elements_across", f.elements_across, non_negative,
                               "a number of elements >= 0 (0: mesh_size alone)");
  f.mesher = s.choice("mesher", f.mesher, kFractureMeshers);
  if (const toml::array* a = s.table_array("load")) {
    for (std::size_t i = 0; i < a->size(); ++i) {
      Section l((*a)[i].as_table(), "fracture.load", file);
      FractureLoad load;
      load.point = l.pair("point", load.point);
      if (!l.has("point")) l.fail("point", "every [[fracture.load]] needs a point = [x, y]");
      if (l.has("force") == l.has("impulse"))
        l.fail("force", "every [[fracture.load]] needs exactly one of force = [fx, fy] or impulse = [ix, iy]");
      load.force = l.pair("force", load.force);
      load.impulse = l.pair("impulse", load.impulse);
      load.is_impulse = l.has("impulse");
      l.finish();
      f.loads.push_back(load);
    }
  }
  s.finish();
}

}  // namespace

std::string record_count_problem(double t_end, double output_interval) {
  const double records = std::floor(t_end / output_interval) + 2.0;
  if (records <= kMaxRecords) return "";
  std::ostringstream m;
  m << "expected an output_interval >= " << t_end / (kMaxRecords - 2.0) << " s (at most "
    << static_cast<long>(kMaxRecords) << " records up to t_end = " << t_end << " s), got " << output_interval << " s: ";
  if (std::isfinite(records)) m << std::setprecision(15) << records << " records";
  else m << "more records than a double can count";
  return m.str();
}

std::string step_count_problem(double t_end, double dt_max) {
  const double steps = std::ceil(t_end / dt_max);
  if (steps <= kMaxSteps) return "";
  std::ostringstream m;
  m << "expected a dt_max >= " << t_end / kMaxSteps << " s (at most " << static_cast<long long>(kMaxSteps)
    << " steps up to t_end = " << t_end << " s), got " << dt_max << " s: ";
  if (std::isfinite(steps)) m << std::setprecision(15) << steps << " steps";
  else m << "more steps than a double can count";
  return m.str();
}

Config parse_config(std::string_view text, const std::string& name, const std::string& base_dir) {
  toml::table root;
  try {
    root = toml::parse(text, name);
  } catch (const toml::parse_error& e) {
    throw InputError(where(name, static_cast<long>(e.source().begin.line), "",
                           "not valid TOML: " + std::string(e.description())));
  }
  Config c;
  c.file = name;
  Section top(&root, "", name);
  read_run(Section(top.table("run"), "run", name), c.run);
  read_sea(Section(top.table("sea"), "sea", name), c.sea, name, base_dir);
  read_floes(Section(top.table("floes"), "floes", name), c.floes, name, base_dir);
  read_contact(Section(top.table("contact"), "contact", name), c.contact, base_dir);
  read_coupling(Section(top.table("coupling"), "coupling", name), c.coupling, c.sea.model);
  read_forcing(Section(top.table("forcing"), "forcing", name), c.forcing, base_dir);
  read_fracture(Section(top.table("fracture"), "fracture", name), c.fracture, name);
  top.finish();
  // The static correction acts through the pressure held over a step, which
  // only the implicit step has (fluid/sea.hpp, hold_pressure; docs/sea.md).
  if (c.sea.bem_static_correction && c.coupling.integrator != CouplingIntegrator::implicit &&
      (!c.floes.floes.empty() || !c.floes.pack.empty()))
    throw InputError(name + ": [sea] bem_static_correction: the floes on a corrected sea need [coupling] integrator = "
                     "\"implicit\" (the correction is the dropped modes' response to the pressure held over a step; "
                     "the explicit kicks are impulses and would not see it)");
  if (!c.coupling.start_given)
    for (const FloeInput& f : c.floes.floes)
      if (f.heave != 0.0 || f.heave_rate != 0.0)
        throw InputError(f.origin + ": heave and heave_rate are initial values for [coupling] start = \"given\"; "
                         "with start = \"equilibrium\" (the default) the floes start at rest on the sea");
  return c;
}

Config load_config(const std::string& path) {
  // A folder opens as an empty stream on Linux and would parse as the default scenario.
  std::error_code ec;
  if (fs::is_directory(path, ec))
    throw InputError(path + ": is a folder; expected a configuration file (.toml)");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path + ": cannot open the configuration file");
  // Read in pieces up to a bound: a device such as /dev/zero never ends.
  std::string text;
  char piece[65536];
  while (in.read(piece, sizeof piece) || in.gcount() > 0) {
    text.append(piece, static_cast<std::size_t>(in.gcount()));
    if (text.size() > kMaxConfigBytes)
      throw InputError(path + ": larger than " + std::to_string(kMaxConfigBytes >> 20) +
                       " MiB; expected a configuration file (.toml)");
  }
  if (in.bad()) throw InputError(path + ": cannot read the configuration file");
  const fs::path dir = fs::absolute(fs::path(path)).parent_path();
  return parse_config(text, path, dir.string());
}

}  // namespace floesim
