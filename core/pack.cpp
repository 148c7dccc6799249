#include "core/pack.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "core/detail/h5.hpp"
#include "core/error.hpp"
#include "core/floes.hpp"

namespace floesim {

namespace {

constexpr const char* kPackFormat = "floesim-pack-1";

// Checks a dataset's rank and shape (0 in `expect`: any extent) before
// reading it, so that no size claimed by the file is allocated unchecked.
h5::Handle open_shaped(hid_t file, const std::string& path, const std::string& name,
                       const std::vector<hsize_t>& expect, const char* type) {
  h5::Handle d = h5::open_dataset(file, name, path);
  const auto dims = h5::dims(d);
  bool ok = dims.size() == expect.size();
  for (std::size_t k = 0; ok && k < dims.size(); ++k) ok = expect[k] == 0 || dims[k] == expect[k];
  if (!ok) {
    std::string want, got;
    for (hsize_t e : expect) want += (want.empty() ? "" : " x ") + (e ? std::to_string(e) : std::string("any"));
    for (hsize_t e : dims) got += (got.empty() ? "" : " x ") + std::to_string(e);
    throw InputError(path + ": dataset '" + name + "' has shape [" + got + "], expected [" + want + "] " + type);
  }
  return d;
}

std::vector<double> read_checked(hid_t file, const std::string& path, const std::string& name,
                                 const std::vector<hsize_t>& expect) {
  return h5::read_doubles(open_shaped(file, path, name, expect, "numbers"), path + ": dataset '" + name + "'");
}

std::vector<long long> read_checked_ints(hid_t file, const std::string& path, const std::string& name,
                                         const std::vector<hsize_t>& expect) {
  return h5::read_ints(open_shaped(file, path, name, expect, "integers"), path + ": dataset '" + name + "'");
}

void require_finite(const std::vector<double>& v, const std::string& path, const std::string& name) {
  for (std::size_t k = 0; k < v.size(); ++k)
    if (!std::isfinite(v[k]))
      throw InputError(path + ": dataset '" + name + "' has a non-finite value at flat index " +
                       std::to_string(k));
}

// /window (xmin, xmax, ymin, ymax), optional in both formats.
std::optional<std::array<double, 4>> read_window(hid_t file, const std::string& path) {
  if (!h5::exists(file, "/window")) return std::nullopt;
  auto w = read_checked(file, path, "/window", {4});
  require_finite(w, path, "/window");
  return std::array<double, 4>{w[0], w[1], w[2], w[3]};
}

Pack read_floedyn(hid_t file, const std::string& path, const PackDefaults& def) {
  Pack pack;
  pack.format = "floedyn";
  h5::Handle shapes = h5::open_group(file, "/floe_shapes", path);
  H5G_info_t info;
  H5Gget_info(shapes, &info);
  const std::size_t n = info.nlinks;
  if (n == 0) throw InputError(path + ": group '/floe_shapes' holds no floe");

  h5::Handle states = h5::open_dataset(file, "/floe_states", path);
  const auto sd = h5::dims(states);
  if (sd.size() != 3 || sd[0] < 1 || sd[1] != n || (sd[2] != 9 && sd[2] != 11))
    throw InputError(path + ": dataset '/floe_states' must be [T, " + std::to_string(n) +
                     ", 9 or 11] (one row per floe in /floe_shapes)");
  // Only record 0 is used: read it alone (a file may hold a long history, or
  // claim one it does not store).
  const std::vector<double> all = h5::read_first_record(states, path + ": dataset '/floe_states'");
  const std::size_t cols = sd[2];

  for (std::size_t i = 0; i < n; ++i) {
    const std::string name = "/floe_shapes/" + std::to_string(i);
    const std::vector<double> v = read_checked(file, path, name, {0, 2});
    require_finite(v, path, name);
    h5::Handle d = h5::open_dataset(file, name, path);
    FloeInput f;
    f.origin = path + ": floe " + std::to_string(i) + " ('" + name + "')";
    for (std::size_t k = 0; k + 1 < v.size(); k += 2) f.vertices.emplace_back(v[k], v[k + 1]);
    const double* s = all.data() + i * cols;
    for (std::size_t c = 0; c < 6; ++c)
      if (!std::isfinite(s[c]))
        throw InputError(path + ": dataset '/floe_states' record 0, floe " + std::to_string(i) +
                         " has a non-finite value in column " + std::to_string(c));
    f.position = {s[0], s[1]};
    f.yaw = s[2];
    f.velocity = {s[3], s[4]};
    f.angular_velocity = s[5];
    f.density = def.density;
    // Thickness: column 10 if > 0, else the dataset's attribute, else 1 m.
    f.thickness = 1.0;
    auto attr = [&](const char* a) {
      try {
        return h5::get_attr_double(d, a);
      } catch (const InputError& e) {
        throw InputError(path + ": dataset '" + name + "': " + e.what());
      }
    };
    if (h5::has_attr(d, "thickness")) f.thickness = attr("thickness");
    if (cols == 11 && std::isfinite(s[10]) && s[10] > 0.0) f.thickness = s[10];
    if (h5::has_attr(d, "C_w")) f.ocean_drag = attr("C_w");
    if (h5::has_attr(d, "obstacle")) f.is_static = attr("obstacle") != 0.0;
    pack.floes.push_back(std::move(f));
  }
  pack.window = read_window(file, path);
  return pack;
}

Pack read_ours(hid_t file, const std::string& path, const PackDefaults& def) {
  Pack pack;
  pack.format = kPackFormat;
  // Vertices first: their real extent bounds the number of floes the offsets
  // may claim (a floe has at least 3 vertices; the bound allows 1 per floe so
  // that a floe with too few is named by the floe check, not here).
  const auto verts = read_checked(file, path, "/floes/vertices", {0, 2});
  require_finite(verts, path, "/floes/vertices");
  const std::size_t nv = verts.size() / 2;
  const std::string od = path + ": dataset '/floes/offsets'";
  {
    const auto d = h5::dims(open_shaped(file, path, "/floes/offsets", {0}, "integers"));
    if (d[0] < 2)
      throw InputError(od + " has " + std::to_string(d[0]) + " entries, expected n + 1 >= 2 for n floes");
    if (d[0] - 1 > std::max<std::size_t>(nv, 1))
      throw InputError(od + " has " + std::to_string(d[0]) + " entries (" + std::to_string(d[0] - 1) +
                       " floes) but '/floes/vertices' has only " + std::to_string(nv) +
                       " rows, expected at most one entry per vertex row plus one");
  }
  const auto offsets = read_checked_ints(file, path, "/floes/offsets", {0});
  const std::size_t n = offsets.size() - 1;
  // Floe i has vertex rows offsets[i] .. offsets[i+1] - 1: the offsets start
  // at 0, never decrease, and end at the number of vertex rows.
  if (offsets[0] != 0)
    throw InputError(od + " starts at " + std::to_string(offsets[0]) + ", expected 0");
  for (std::size_t i = 0; i < n; ++i) {
    if (offsets[i + 1] < offsets[i])
      throw InputError(od + " decreases at floe " + std::to_string(i) + " (entry " + std::to_string(i + 1) +
                       " = " + std::to_string(offsets[i + 1]) + " < entry " + std::to_string(i) + " = " +
                       std::to_string(offsets[i]) + "), expected non-decreasing offsets");
    if (static_cast<unsigned long long>(offsets[i + 1]) > nv)
      throw InputError(od + " entry " + std::to_string(i + 1) + " = " + std::to_string(offsets[i + 1]) +
                       " (floe " + std::to_string(i) + ") points past '/floes/vertices', which has " +
                       std::to_string(nv) + " rows");
  }
  if (static_cast<std::size_t>(offsets[n]) != nv)
    throw InputError(od + " ends at " + std::to_string(offsets[n]) + " but '/floes/vertices' has " +
                     std::to_string(nv) + " rows, expected them equal");
  const auto pose = read_checked(file, path, "/floes/pose", {n, 3});
  require_finite(pose, path, "/floes/pose");
  auto optional = [&](const std::string& name, std::vector<hsize_t> shape) {
    std::vector<double> v;
    if (h5::exists(file, name)) v = read_checked(file, path, name, shape);
    return v;
  };
  const auto vel = optional("/floes/velocity", {n, 3});
  require_finite(vel, path, "/floes/velocity");
  const auto thick = optional("/floes/thickness", {n});
  const auto dens = optional("/floes/density", {n});
  const auto drag = optional("/floes/ocean_drag", {n});
  std::vector<long long> stat;
  if (h5::exists(file, "/floes/static")) stat = read_checked_ints(file, path, "/floes/static", {n});
  for (std::size_t i = 0; i < n; ++i) {
    FloeInput f;
    f.origin = path + ": floe " + std::to_string(i);
    for (auto k = static_cast<std::size_t>(offsets[i]); k < static_cast<std::size_t>(offsets[i + 1]); ++k)
      f.vertices.emplace_back(verts[2 * k], verts[2 * k + 1]);
    f.position = {pose[3 * i], pose[3 * i + 1]};
    f.yaw = pose[3 * i + 2];
    if (!vel.empty()) {
      f.velocity = {vel[3 * i], vel[3 * i + 1]};
      f.angular_velocity = vel[3 * i + 2];
    }
    f.thickness = thick.empty() ? def.thickness : thick[i];
    f.density = dens.empty() ? def.density : dens[i];
    if (!drag.empty() && std::isfinite(drag[i]) && drag[i] >= 0.0) f.ocean_drag = drag[i];
    f.is_static = !stat.empty() && stat[i] != 0;
    pack.floes.push_back(std::move(f));
  }
  pack.window = read_window(file, path);
  return pack;
}

}  // namespace

Pack read_pack(const std::string& path, const PackDefaults& defaults) {
  // Read first in a child process: a file that crashes HDF5 is refused.
  h5::refuse_if_read_crashes(path, [&] { read_pack_in_process(path, defaults); });
  return read_pack_in_process(path, defaults);
}

Pack read_pack_in_process(const std::string& path, const PackDefaults& defaults) {
  h5::Handle file = h5::open_file(path);
  h5::check_global_heaps(path);  // before any variable-length string is read
  if (h5::has_attr(file, "format")) {
    const std::string fmt = h5::get_attr_string(file, "format");
    if (fmt == kPackFormat) return read_ours(file, path, defaults);
    throw InputError(path + ": attribute 'format' is '" + fmt + "', expected '" + kPackFormat +
                     "' (or a FloeDyn input file with /floe_shapes)");
  }
  if (h5::exists(file, "/floe_shapes")) return read_floedyn(file, path, defaults);
  throw InputError(path + ": not a floe pack: neither a root attribute format = '" +
                   std::string(kPackFormat) + "' nor a FloeDyn group /floe_shapes");
}

void write_pack(const std::string& path, const Floes& floes,
                const std::optional<std::array<double, 4>>& window) {
  h5::Handle file = h5::create_file(path);
  h5::set_attr(file, "format", std::string(kPackFormat));
  h5::Handle g = h5::create_group(file, "/floes");
  const std::size_t n = floes.size();
  std::vector<long long> off(floes.offsets.begin(), floes.offsets.end());
  h5::write_ints(g, "offsets", {n + 1}, off.data());
  h5::write_doubles(g, "vertices", {floes.body.size(), 2}, floes.body.empty() ? nullptr : floes.body[0].data());
  std::vector<double> pose, vel;
  std::vector<unsigned char> stat;
  for (std::size_t i = 0; i < n; ++i) {
    const FloeState& s = floes.state[i];
    pose.insert(pose.end(), {s.x, s.y, s.yaw});
    vel.insert(vel.end(), {s.vx, s.vy, s.yaw_rate});
    stat.push_back(floes.is_static[i]);
  }
  h5::write_doubles(g, "pose", {n, 3}, pose.data());
  h5::write_doubles(g, "velocity", {n, 3}, vel.data());
  h5::write_doubles(g, "thickness", {n}, floes.thickness.data());
  h5::write_doubles(g, "density", {n}, floes.density.data());
  h5::write_doubles(g, "ocean_drag", {n}, floes.ocean_drag.data());
  h5::write_bytes(g, "static", {n}, stat.data());
  if (window) h5::write_doubles(file, "window", {4}, window->data());
}

}  // namespace floesim
