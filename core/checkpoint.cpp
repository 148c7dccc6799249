#include "core/checkpoint.hpp"

#include <cmath>
#include <cstring>

#include "core/detail/checkpoint_io.hpp"
#include "core/error.hpp"
#include "core/run_file.hpp"

namespace floesim {

namespace {

void doubles(hid_t g, const std::string& name, const std::vector<double>& v, hsize_t columns = 1) {
  std::vector<hsize_t> d{columns > 1 ? v.size() / columns : v.size()};
  if (columns > 1) d.push_back(columns);
  h5::write_doubles(g, name, d, v.empty() ? nullptr : v.data());
}
void ints(hid_t g, const std::string& name, const std::vector<long long>& v) {
  h5::write_ints(g, name, {v.size()}, v.empty() ? nullptr : v.data());
}

void write_modal(hid_t parent, const std::string& name, const ModalState& m) {
  h5::Handle g = h5::create_group(parent, name);
  h5::set_attr(g, "time", m.time);
  doubles(g, "q", m.q);
  doubles(g, "v", m.v);
  if (!m.held_pressure.empty()) doubles(g, "held_pressure", m.held_pressure);
}

void write_floes(hid_t parent, const Floes& f) {
  h5::Handle g = h5::create_group(parent, "floes");
  std::vector<long long> offsets(f.offsets.begin(), f.offsets.end()), id(f.id.begin(), f.id.end());
  ints(g, "offsets", offsets);
  std::vector<double> body;
  body.reserve(2 * f.body.size());
  for (const Vec2& p : f.body) { body.push_back(p.x()); body.push_back(p.y()); }
  doubles(g, "body", body, 2);
  doubles(g, "thickness", f.thickness);
  doubles(g, "density", f.density);
  doubles(g, "area", f.area);
  doubles(g, "mass", f.mass);
  doubles(g, "inertia_z", f.inertia_z);
  doubles(g, "inertia_x", f.inertia_x);
  doubles(g, "inertia_y", f.inertia_y);
  doubles(g, "ocean_drag", f.ocean_drag);
  h5::write_bytes(g, "static", {f.is_static.size()}, f.is_static.empty() ? nullptr : f.is_static.data());
  std::vector<double> state(f.state.size() * kStateColumns);
  if (!f.state.empty()) std::memcpy(state.data(), static_cast<const void*>(f.state.data()), state.size() * sizeof(double));
  doubles(g, "state", state, kStateColumns);
  ints(g, "id", id);
  h5::set_attr(g, "ids_issued", static_cast<double>(f.ids_issued));
}

}  // namespace

void write_checkpoint_group(hid_t file, const std::string& name, const Checkpoint& c) {
  h5::Handle g = h5::create_group(file, name);
  h5::set_attr(g, "version", static_cast<double>(kCheckpointVersion));
  h5::set_attr(g, "time", c.time);
  h5::set_attr(g, "steps", static_cast<double>(c.steps));
  h5::set_attr(g, "equal_dt", c.equal_dt);
  h5::set_attr(g, "next_record", static_cast<double>(c.next_record));
  h5::set_attr(g, "records", static_cast<double>(c.records));
  h5::set_attr(g, "fracture_events", static_cast<double>(c.fracture_events));
  h5::set_attr(g, "collision_events", static_cast<double>(c.collision_events));
  h5::set_attr(g, "floor_pair", c.floor_pair);
  write_floes(g, c.floes);
  if (c.sea.present) write_modal(g, "sea", c.sea);
  if (c.incident.present) {
    const IncidentState& s = c.incident;
    write_modal(g, "incident", s.sea);
    h5::Handle i = h5::open_group(g, "incident", "");
    h5::set_attr(i, "t0", s.t0);
    h5::set_attr(i, "t1", s.t1);
    doubles(i, "u0", s.u0);
    doubles(i, "v0", s.v0);
    doubles(i, "u1", s.u1);
    doubles(i, "v1", s.v1);
  }
  if (c.floe_sea.present) {
    h5::Handle s = h5::create_group(g, "floe_sea");
    doubles(s, "bottom0", c.floe_sea.bottom0);
    h5::set_attr(s, "loads_h", c.floe_sea.loads_h);
    h5::set_attr(s, "penalty_energy", c.floe_sea.penalty_energy);
    if (!c.floe_sea.footprint_reference.empty()) {
      std::vector<double> flat;
      for (const auto& p : c.floe_sea.footprint_reference) flat.insert(flat.end(), p.begin(), p.end());
      doubles(s, "footprint_reference", flat, 3);
    }
    if (!c.floe_sea.mean_horizontal.empty()) {
      std::vector<double> flat;
      for (const auto& p : c.floe_sea.mean_horizontal) flat.insert(flat.end(), p.begin(), p.end());
      doubles(s, "mean_horizontal", flat, 3);
    }
  }
  {
    const WarmStartState& w = c.warm;
    h5::Handle s = h5::create_group(g, "warm_start");
    h5::set_attr(s, "clock", static_cast<double>(w.clock));
    std::vector<long long> keys(w.keys.size());
    for (std::size_t k = 0; k < keys.size(); ++k) std::memcpy(&keys[k], &w.keys[k], sizeof(long long));
    ints(s, "keys", keys);
    ints(s, "stored", w.stored);
    ints(s, "offsets", w.offsets);
    doubles(s, "entries", w.entries, WarmStartState::kWidth);
  }
  doubles(g, "counters", c.counters);
  h5::Handle counters = h5::open_dataset(g, "counters", "");
  h5::set_attr(counters, "columns", c.counter_names);
  ints(g, "record_floes", c.record_floes);
}

// ---------------------------------------------------------------- reading

namespace {

struct Reader {
  std::string path;
  std::string sub;  // the group read, for messages ("floes/")
  std::vector<double> doubles(hid_t g, const std::string& name, std::size_t expected = SIZE_MAX) const {
    const std::string what = path + ": /checkpoint/" + sub + name;
    std::vector<double> v = h5::read_doubles(h5::open_dataset(g, name, path), what);
    if (expected != SIZE_MAX && v.size() != expected)
      throw InputError(what + ": expected " + std::to_string(expected) + " numbers, got " + std::to_string(v.size()));
    return v;
  }
  std::vector<long long> ints(hid_t g, const std::string& name) const {
    return h5::read_ints(h5::open_dataset(g, name, path), path + ": /checkpoint/" + sub + name);
  }
  double attr(hid_t g, const std::string& name) const {
    if (!h5::has_attr(g, name)) throw InputError(path + ": /checkpoint: attribute '" + name + "' is missing");
    return h5::get_attr_double(g, name);
  }
  long long count(hid_t g, const std::string& name) const {
    const double v = attr(g, name);
    if (!(v >= 0.0 && v < 9.0e15 && v == std::floor(v)))
      throw InputError(path + ": /checkpoint: attribute '" + name + "' is not a count");
    return static_cast<long long>(v);
  }
  ModalState modal(hid_t parent, const std::string& name) const {
    ModalState m;
    if (!h5::exists(parent, name)) return m;
    h5::Handle g = h5::open_group(parent, name, path);
    m.present = true;
    m.time = attr(g, "time");
    m.q = doubles(g, "q");
    m.v = doubles(g, "v", m.q.size());
    if (h5::exists(g, "held_pressure")) m.held_pressure = doubles(g, "held_pressure");
    return m;
  }
  void fail(const std::string& what) const { throw InputError(path + ": /checkpoint: " + what); }
};

Floes read_floes(Reader r, hid_t parent) {
  h5::Handle g = h5::open_group(parent, "floes", r.path);
  r.sub = "floes/";
  Floes f;
  const std::vector<long long> offsets = r.ints(g, "offsets");
  if (offsets.empty() || offsets.front() != 0) r.fail("floes/offsets: expected n + 1 offsets starting at 0");
  for (std::size_t i = 1; i < offsets.size(); ++i)
    if (offsets[i] < offsets[i - 1] + 3) r.fail("floes/offsets: expected at least 3 vertices per floe");
  const std::size_t n = offsets.size() - 1;
  f.offsets.assign(offsets.begin(), offsets.end());
  const std::vector<double> body = r.doubles(g, "body", 2 * static_cast<std::size_t>(offsets.back()));
  f.body.resize(body.size() / 2);
  for (std::size_t k = 0; k < f.body.size(); ++k) f.body[k] = Vec2{body[2 * k], body[2 * k + 1]};
  f.thickness = r.doubles(g, "thickness", n);
  f.density = r.doubles(g, "density", n);
  f.area = r.doubles(g, "area", n);
  f.mass = r.doubles(g, "mass", n);
  f.inertia_z = r.doubles(g, "inertia_z", n);
  f.inertia_x = r.doubles(g, "inertia_x", n);
  f.inertia_y = r.doubles(g, "inertia_y", n);
  f.ocean_drag = r.doubles(g, "ocean_drag", n);
  const std::vector<long long> is_static = r.ints(g, "static");
  if (is_static.size() != n) r.fail("floes/static: expected one flag per floe");
  f.is_static.assign(is_static.begin(), is_static.end());
  const std::vector<double> state = r.doubles(g, "state", n * kStateColumns);
  f.state.resize(n);
  if (n) std::memcpy(static_cast<void*>(f.state.data()), state.data(), state.size() * sizeof(double));
  for (double x : state)
    if (!std::isfinite(x)) r.fail("floes/state: expected finite numbers");
  const std::vector<long long> id = r.ints(g, "id");
  if (id.size() != n) r.fail("floes/id: expected one number per floe");
  f.ids_issued = static_cast<std::uint32_t>(r.count(g, "ids_issued"));
  for (long long x : id) {
    if (x < 0 || x >= static_cast<long long>(f.ids_issued)) r.fail("floes/id: a number outside [0, ids_issued)");
    f.id.push_back(static_cast<std::uint32_t>(x));
  }
  return f;
}

}  // namespace

Checkpoint read_checkpoint(const std::string& path) {
  h5::Handle file = h5::open_file(path);
  if (!h5::has_attr(file, "format") || h5::get_attr_string(file, "format") != std::string(kRunFormat))
    throw InputError(path + ": not a floesim run file (attribute 'format' is not '" + std::string(kRunFormat) + "')");
  if (!h5::exists(file, "/checkpoint"))
    throw InputError(path + ": the run has no checkpoint (/checkpoint): it was written before checkpoints "
                            "existed, or the process was killed before its first checkpoint "
                            "(set [run] checkpoint_interval to write them during a run)");
  const Reader r{path, ""};
  h5::Handle g = h5::open_group(file, "/checkpoint", path);
  const double version = r.attr(g, "version");
  if (version != static_cast<double>(kCheckpointVersion))
    r.fail("version " + (version == std::floor(version) && std::abs(version) < 1e15
                              ? std::to_string(static_cast<long long>(version)) : std::to_string(version)) +
           ", this floesim reads version " + std::to_string(kCheckpointVersion));
  Checkpoint c;
  c.time = r.attr(g, "time");
  if (!(std::isfinite(c.time) && c.time >= 0.0)) r.fail("time: expected a finite time >= 0");
  c.steps = r.count(g, "steps");
  c.equal_dt = r.attr(g, "equal_dt");
  c.next_record = r.count(g, "next_record");
  c.records = r.count(g, "records");
  c.fracture_events = r.count(g, "fracture_events");
  // Absent from checkpoints written before /events/collisions existed.
  c.collision_events = h5::has_attr(g, "collision_events") ? r.count(g, "collision_events") : 0;
  c.floor_pair = h5::has_attr(g, "floor_pair") ? h5::get_attr_string(g, "floor_pair") : "";
  c.floes = read_floes(r, g);
  c.sea = r.modal(g, "sea");
  if (h5::exists(g, "incident")) {
    c.incident.sea = r.modal(g, "incident");
    c.incident.present = true;
    h5::Handle i = h5::open_group(g, "incident", path);
    c.incident.t0 = r.attr(i, "t0");
    c.incident.t1 = r.attr(i, "t1");
    c.incident.u0 = r.doubles(i, "u0");
    c.incident.v0 = r.doubles(i, "v0", c.incident.u0.size());
    c.incident.u1 = r.doubles(i, "u1", c.incident.u0.size());
    c.incident.v1 = r.doubles(i, "v1", c.incident.u0.size());
  }
  if (h5::exists(g, "floe_sea")) {
    h5::Handle s = h5::open_group(g, "floe_sea", path);
    c.floe_sea.present = true;
    c.floe_sea.bottom0 = r.doubles(s, "bottom0", c.floes.size());
    c.floe_sea.loads_h = r.attr(s, "loads_h");
    c.floe_sea.penalty_energy = r.attr(s, "penalty_energy");
    if (h5::exists(s, "footprint_reference")) {
      const std::vector<double> flat = r.doubles(s, "footprint_reference", 3 * c.floes.size());
      for (std::size_t k = 0; k + 2 < flat.size(); k += 3) c.floe_sea.footprint_reference.push_back({flat[k], flat[k + 1], flat[k + 2]});
    }
    if (h5::exists(s, "mean_horizontal")) {
      const std::vector<double> flat = r.doubles(s, "mean_horizontal", 3 * c.floes.size());
      for (std::size_t k = 0; k + 2 < flat.size(); k += 3) c.floe_sea.mean_horizontal.push_back({flat[k], flat[k + 1], flat[k + 2]});
    }
  }
  {
    h5::Handle s = h5::open_group(g, "warm_start", path);
    WarmStartState& w = c.warm;
    w.clock = r.count(s, "clock");
    const std::vector<long long> keys = r.ints(s, "keys");
    w.keys.resize(keys.size());
    for (std::size_t k = 0; k < keys.size(); ++k) std::memcpy(&w.keys[k], &keys[k], sizeof(long long));
    w.stored = r.ints(s, "stored");
    w.offsets = r.ints(s, "offsets");
    w.entries = r.doubles(s, "entries");
    // Files written before the vertex_of_b column (8 numbers an entry) get
    // it as 0; their points were contact mid-points, so those warm starts
    // mostly find nothing and the LCPs start from scratch.
    if (!w.offsets.empty() && w.offsets.back() > 0 &&
        static_cast<std::size_t>(w.offsets.back()) * 8 == w.entries.size()) {
      std::vector<double> wide;
      for (std::size_t e = 0; e < w.entries.size(); e += 8) {
        wide.insert(wide.end(), w.entries.begin() + static_cast<std::ptrdiff_t>(e),
                    w.entries.begin() + static_cast<std::ptrdiff_t>(e + 8));
        wide.push_back(0.0);
      }
      w.entries = std::move(wide);
    }
    if (w.stored.size() != keys.size() || w.offsets.size() != keys.size() + 1 || w.offsets.front() != 0 ||
        static_cast<std::size_t>(w.offsets.back()) * WarmStartState::kWidth != w.entries.size())
      r.fail("warm_start: keys, stored, offsets and entries do not agree");
    for (std::size_t k = 1; k < w.offsets.size(); ++k)
      if (w.offsets[k] < w.offsets[k - 1]) r.fail("warm_start/offsets: expected non-decreasing offsets");
  }
  c.counters = r.doubles(g, "counters");
  {
    h5::Handle d = h5::open_dataset(g, "counters", path);
    c.counter_names = h5::get_attr_strings(d, "columns");
    if (c.counter_names.size() != c.counters.size()) r.fail("counters: expected one name per counter");
  }
  c.record_floes = r.ints(g, "record_floes");
  if (static_cast<long long>(c.record_floes.size()) != c.records)
    r.fail("record_floes: expected one entry per record");
  return c;
}

void release_restored(Checkpoint& c) {
  c.sea = ModalState{};
  c.incident = IncidentState{};
  c.floe_sea = FloeSeaState{};
  c.warm = WarmStartState{};
}

}  // namespace floesim
