// The run file's writer (core/run_file.hpp: RunWriter, its records, checkpoints,
// end mark and XDMF companion). Reading and comparing runs: run_file_read.cpp.
#include "core/run_file.hpp"

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>

#include "core/checkpoint.hpp"
#include "core/detail/checkpoint_io.hpp"
#include "core/detail/h5.hpp"
#include "core/error.hpp"
#include "core/floes.hpp"

namespace floesim {

namespace fs = std::filesystem;

struct RunWriter::Impl {
  std::string path;
  h5::Handle file, floes_group, xdmf_group, time, state, energy, lcp, substeps, verts, eta, events, collisions;
  std::size_t n = 0, nverts = 0, records = 0;  // floes (numbers) and vertices in the /floes tables
  std::size_t event_rows = 0;  // rows of /events/fracture
  std::size_t collision_rows = 0;  // rows of /events/collisions
  // The /floes tables, one row per floe number, and the XDMF topology.
  std::vector<long long> offsets{0}, topology;
  std::vector<double> vertices, thickness, mass, area;
  std::vector<unsigned char> is_static;
  std::vector<double> times;
  // Sizes of the tables at each record (the XDMF grid of a record uses those).
  std::vector<std::size_t> record_floes, record_vertices, record_topology;
  std::vector<std::string> energy_columns;
  SeaGridInfo sea;
  std::chrono::steady_clock::time_point last_xdmf = std::chrono::steady_clock::now();
  std::vector<double> scratch;
  // disk_full: a reservation was refused; the file is as last flushed (whole) and
  // only its end mark is still written. write_failed: a write itself failed (no
  // reservation on this file system); HDF5 cannot make such a file consistent,
  // so nothing more is written to it, it is only closed.
  bool disk_full = false, write_failed = false;
  // What one record may add to the file (reserve_for_writes), for n floes.
  hsize_t record_bytes = 0;
  std::size_t record_bytes_n = 0;

  void write_tables();
  bool write_xdmf() const;
  // Disk space for what the next record (or the tables, or the end mark) may
  // add to the file, reserved before it is written (h5::reserve); throws
  // RunError when the disk is full or the file may not grow.
  void reserve_for_writes(hsize_t extra = 0);
  // Flushes the file to disk; throws RunError when a write failed.
  void flush();
  // Runs `write` (HDF5 writes); a failure sets write_failed and becomes a
  // RunError naming the file and the records it keeps.
  template <class F> void guarded(F&& write);
  std::string keeps() const {
    return records == 0 ? std::string("no record was written")
                        : "the run file keeps the " + std::to_string(records) + " records written before";
  }
};

namespace {
// Room for the end mark (status and record-count attributes) and the
// metadata HDF5 rewrites at a flush (object headers, B-tree nodes, heap).
constexpr hsize_t kMetadataMargin = hsize_t{1} << 18;
}  // namespace

void RunWriter::Impl::reserve_for_writes(hsize_t extra) {
  if (record_bytes == 0 || record_bytes_n != n) {  // the datasets' extents change only with n
    record_bytes = 0;
    for (hid_t d : {time.get(), state.get(), energy.get(), lcp.get(), substeps.get(), verts.get(), eta.get(),
                    events.get()})
      if (d >= 0) record_bytes += h5::append_bytes(d);
    // The tables are rewritten whole when floes appear.
    record_bytes += 8 * (offsets.size() + vertices.size() + 4 * thickness.size() + topology.size());
    record_bytes_n = n;
  }
  const hsize_t bytes = kMetadataMargin + record_bytes + extra;
  const int err = h5::reserve(file, bytes);
  if (err != 0) {
    disk_full = true;  // nothing written since the last flush: the file on disk is whole
    throw RunError(path + ": cannot reserve " + std::to_string(bytes) + " bytes of disk space for the next record (" +
                   std::strerror(err) + (err == ENOSPC ? ": the disk is full" : err == EFBIG ? ": the file may not grow" : "") +
                   "); " + keeps());
  }
}

void RunWriter::Impl::flush() {
  if (!h5::flush(file)) {
    write_failed = true;
    throw RunError(path + ": writing the run file to disk failed (is the disk full?); " + keeps() +
                   " unless the failed write damaged it");
  }
}

template <class F>
void RunWriter::Impl::guarded(F&& write) {
  if (disk_full || write_failed) throw RunError(path + ": an earlier write to the run file failed; " + keeps());
  try {
    write();
  } catch (const RunError& e) {
    if (disk_full || write_failed) throw;  // already says what the file keeps
    write_failed = true;
    throw RunError(path + ": " + e.what() + "; " + keeps() + " unless the failed write damaged it");
  }
}

namespace {
h5::Writing h5_writing(RunFileWriting w) {
  return w == RunFileWriting::crash_safe ? h5::Writing::published : h5::Writing::in_place;
}

std::uint32_t id_of(const Floes& floes, std::size_t i) {
  return i < floes.id.size() ? floes.id[i] : static_cast<std::uint32_t>(i);
}
}  // namespace

// (Re)writes the per-floe tables; they are small, and rewritten only when
// floes appear.
void RunWriter::Impl::write_tables() {
  for (const char* name : {"offsets", "vertices", "thickness", "mass", "area", "static"}) h5::remove(floes_group, name);
  h5::remove(xdmf_group, "topology");
  h5::write_ints(floes_group, "offsets", {n + 1}, offsets.data());
  h5::write_doubles(floes_group, "vertices", {nverts, 2}, nverts ? vertices.data() : nullptr);
  h5::write_doubles(floes_group, "thickness", {n}, thickness.data());
  h5::write_doubles(floes_group, "mass", {n}, mass.data());
  h5::write_doubles(floes_group, "area", {n}, area.data());
  h5::write_bytes(floes_group, "static", {n}, is_static.data());
  h5::write_ints(xdmf_group, "topology", {topology.size()}, topology.data());
}

RunWriter::RunWriter(const std::string& path, const Floes& floes, const std::string& config_toml,
                     std::vector<std::string> energy_columns, const SeaGridInfo& sea,
                     std::size_t expected_records, RunFileWriting writing)
    : impl_(std::make_unique<Impl>()) {
  Impl& w = *impl_;
  w.path = path;
  w.energy_columns = std::move(energy_columns);
  w.sea = sea;
  const hsize_t rows = expected_records;
  w.file = h5::create_file(path, h5_writing(writing));
  try {
    start(floes, config_toml, static_cast<unsigned long long>(rows));
  } catch (const RunError& e) {
    // Not one record: close and remove what there is rather than leave a
    // file that may not open.
    impl_.reset();
    std::error_code ec;
    fs::remove(path, ec);
    fs::remove(fs::path(path).replace_extension(".xmf"), ec);  // one left by an earlier run
    throw RunError(std::string(e.what()) + " (the run file could not be started: removed)");
  }
}

void RunWriter::start(const Floes& floes, const std::string& config_toml, unsigned long long rows) {
  Impl& w = *impl_;
  w.reserve_for_writes(8 * config_toml.size());
  h5::set_attr(w.file, "format", std::string(kRunFormat));
  h5::set_attr(w.file, "config", config_toml);
  h5::set_attr(w.file, "status", std::string("running"));

  w.time = h5::create_extendible(w.file, "time", {}, rows);
  h5::set_attr(w.time, "units", std::string("s"));

  w.floes_group = h5::create_group(w.file, "/floes");
  // ParaView helpers: mixed-polygon topology (type 3 = polygon, vertex count,
  // vertex indices) and per-record world vertices.
  w.xdmf_group = h5::create_group(w.file, "/xdmf");
  note_floes(floes);  // the tables (the growing datasets do not exist yet)
  w.write_tables();   // also when there is no floe
  // Chunks sized on the floes at the start (a row of 1 floe per chunk would
  // make every record touch n chunks).
  w.state = h5::create_growable(w.floes_group, "state", {w.n, kStateColumns}, rows);
  h5::set_attr(w.state, "columns", std::vector<std::string>(std::begin(kStateColumnNames), std::end(kStateColumnNames)));
  w.verts = h5::create_growable(w.xdmf_group, "vertices", {w.nverts, 3}, rows);

  h5::Handle d = h5::create_group(w.file, "/diagnostics");
  w.energy = h5::create_extendible(d, "energy", {w.energy_columns.size()}, rows);
  h5::set_attr(w.energy, "columns", w.energy_columns);
  h5::set_attr(w.energy, "units", std::string("J"));
  w.lcp = h5::create_extendible(d, "lcp", {4}, rows);
  h5::set_attr(w.lcp, "columns", std::vector<std::string>{"solves", "pivots", "failures", "fallbacks"});
  w.substeps = h5::create_extendible(d, "substeps", {kSubstepColumns}, rows);
  h5::set_attr(w.substeps, "columns",
               std::vector<std::string>(std::begin(kSubstepColumnNames), std::end(kSubstepColumnNames)));

  h5::Handle ev = h5::create_group(w.file, "/events");
  w.events = h5::create_extendible(ev, "fracture", {kFractureEventColumns});
  h5::set_attr(w.events, "columns",
               std::vector<std::string>(std::begin(kFractureEventColumnNames), std::end(kFractureEventColumnNames)));

  if (w.sea.dims > 0) {
    h5::Handle s = h5::create_group(w.file, "/sea");
    const int nx = w.sea.cells[0], ny = w.sea.dims == 2 ? w.sea.cells[1] : 1;
    std::vector<double> x(static_cast<std::size_t>(nx)), y(static_cast<std::size_t>(ny));
    for (int i = 0; i < nx; ++i) x[static_cast<std::size_t>(i)] = (i + 0.5) * w.sea.size[0] / nx;
    for (int j = 0; j < ny; ++j) y[static_cast<std::size_t>(j)] = (j + 0.5) * w.sea.size[1] / ny;
    h5::write_doubles(s, "x", {x.size()}, x.data());
    h5::write_doubles(s, "y", {y.size()}, y.data());
    std::vector<hsize_t> row = w.sea.dims == 2 ? std::vector<hsize_t>{hsize_t(ny), hsize_t(nx)}
                                               : std::vector<hsize_t>{hsize_t(nx)};
    w.eta = h5::create_extendible(s, "eta", row, rows);
    h5::set_attr(w.eta, "units", std::string("m"));
  }
  w.record_bytes = 0;  // measured again on the datasets now made
  w.flush();
}

RunWriter::~RunWriter() {
  if (impl_ && impl_->file.valid()) {
    try { impl_->write_xdmf(); } catch (...) {}
  }
}

void RunWriter::note_floes(const Floes& floes) {
  Impl& w = *impl_;
  if (floes.ids_issued <= w.n && floes.size() <= w.n) return;  // nothing new (the usual step)
  std::size_t issued = floes.ids_issued;
  for (std::size_t i = 0; i < floes.size(); ++i) issued = std::max<std::size_t>(issued, id_of(floes, i) + 1);
  if (issued <= w.n) return;
  std::vector<long long> where(issued - w.n, -1);  // index in `floes` of each new number
  for (std::size_t i = 0; i < floes.size(); ++i)
    if (id_of(floes, i) >= w.n) where[id_of(floes, i) - w.n] = static_cast<long long>(i);
  for (std::size_t k = 0; k < where.size(); ++k) {
    // A number not present (made and ended between two notes) keeps an empty outline.
    const long long i = where[k];
    const std::size_t first = w.nverts;
    if (i >= 0) {
      const auto fi = static_cast<std::size_t>(i);
      for (const Vec2& p : floes.vertices(fi)) {
        w.vertices.push_back(p.x());
        w.vertices.push_back(p.y());
      }
      w.nverts += floes.vertices(fi).size();
    }
    w.offsets.push_back(static_cast<long long>(w.nverts));
    w.thickness.push_back(i >= 0 ? floes.thickness[static_cast<std::size_t>(i)] : std::nan(""));
    w.mass.push_back(i >= 0 ? floes.mass[static_cast<std::size_t>(i)] : std::nan(""));
    w.area.push_back(i >= 0 ? floes.area[static_cast<std::size_t>(i)] : std::nan(""));
    w.is_static.push_back(i >= 0 ? floes.is_static[static_cast<std::size_t>(i)] : 0);
    w.topology.push_back(3);
    w.topology.push_back(static_cast<long long>(w.nverts - first));
    for (std::size_t v = first; v < w.nverts; ++v) w.topology.push_back(static_cast<long long>(v));
  }
  w.n = issued;
  if (!w.file.valid()) return;
  w.guarded([&] {
    w.reserve_for_writes();  // counts the grown tables
    if (w.state.valid()) {
      // Earlier records read NaN for the new floes (the fill value).
      h5::set_extent(w.state, {w.records, w.n, kStateColumns});
      h5::set_extent(w.verts, {w.records, w.nverts, 3});
    }
    if (w.floes_group.valid() && h5::exists(w.floes_group, "offsets")) w.write_tables();
  });
}

void RunWriter::record(double t, const Floes& floes, std::span<const double> energy,
                       const LcpCounters& lcp, std::span<const double> eta) {
  record(t, floes, floes.state, energy, lcp, eta);
}

void RunWriter::record(double t, const Floes& floes, std::span<const FloeState> states,
                       std::span<const double> energy, const LcpCounters& lcp, std::span<const double> eta) {
  Impl& w = *impl_;
  FLOESIM_ASSERT(states.size() == floes.size());
  FLOESIM_ASSERT(energy.size() == w.energy_columns.size());
  if (w.eta.valid() && eta.empty()) throw RunError("run file: the sea elevation is missing from a record");
  note_floes(floes);
  // Reserve, write, flush: a refused reservation writes nothing (RunWriter's header).
  w.guarded([&] {
    w.reserve_for_writes();
    h5::append_row(w.time, &t);
    w.scratch.assign(w.n * kStateColumns, std::nan(""));
    for (std::size_t i = 0; i < floes.size(); ++i)
      std::copy_n(reinterpret_cast<const double*>(&states[i]), kStateColumns,
                  w.scratch.begin() + static_cast<std::ptrdiff_t>(id_of(floes, i) * kStateColumns));
    h5::append_row(w.state, w.scratch.data());
    h5::append_row(w.energy, energy.data());
    const double l[4] = {lcp.solves, lcp.pivots, lcp.failures, lcp.fallbacks};
    h5::append_row(w.lcp, l);
    h5::append_row(w.substeps, lcp.substeps.data());
    w.scratch.assign(3 * w.nverts, std::nan(""));
    for (std::size_t i = 0; i < floes.size(); ++i) {
      std::size_t k = static_cast<std::size_t>(w.offsets[id_of(floes, i)]);
      const FloeState& s = states[i];
      for (const Vec2& b : floes.vertices(i)) {
        const Vec2 p = Vec2{s.x, s.y} + rotate(b, s.yaw);  // Floes::to_world at this state
        w.scratch[3 * k] = p.x();
        w.scratch[3 * k + 1] = p.y();
        w.scratch[3 * k + 2] = s.heave;
        ++k;
      }
    }
    h5::append_row(w.verts, w.scratch.data());
    if (w.eta.valid()) h5::append_row(w.eta, eta.data());
    w.flush();
  });
  w.times.push_back(t);
  w.record_floes.push_back(w.n);
  w.record_vertices.push_back(w.nverts);
  w.record_topology.push_back(w.topology.size());
  ++w.records;
  // Keep the XDMF reasonably current without rewriting it at every record.
  const auto now = std::chrono::steady_clock::now();
  if (w.records == 1 || now - w.last_xdmf > std::chrono::seconds(5)) {
    w.write_xdmf();
    w.last_xdmf = now;
  }
}

void RunWriter::record_fracture(std::span<const FractureEventRow> events) {
  Impl& w = *impl_;
  if (events.empty()) return;
  w.guarded([&] {
    w.reserve_for_writes(8 * kFractureEventColumns * events.size());
    for (const FractureEventRow& e : events) h5::append_row(w.events, reinterpret_cast<const double*>(&e));
    w.event_rows += events.size();
    w.flush();
  });
}

void RunWriter::record_collisions(std::span<const CollisionEventRow> events) {
  Impl& w = *impl_;
  if (events.empty()) return;
  w.guarded([&] {
    w.reserve_for_writes(8 * kCollisionEventColumns * events.size());
    if (!w.collisions.valid()) {  // made by the first rows: a run that records none has no /events/collisions
      h5::Handle ev = h5::open_group(w.file, "/events", w.path);
      w.collisions = h5::create_extendible(ev, "collisions", {kCollisionEventColumns});
      h5::set_attr(w.collisions, "columns", std::vector<std::string>(std::begin(kCollisionEventColumnNames),
                                                                     std::end(kCollisionEventColumnNames)));
    }
    for (const CollisionEventRow& e : events) h5::append_row(w.collisions, reinterpret_cast<const double*>(&e));
    w.collision_rows += events.size();
  });
}

RunWriter::RunWriter(Resume, const std::string& path, const Checkpoint& c, const std::string& config_toml,
                     const std::vector<std::string>& energy_columns, const SeaGridInfo& sea,
                     RunFileWriting writing)
    : impl_(std::make_unique<Impl>()) {
  Impl& w = *impl_;
  w.path = path;
  w.energy_columns = energy_columns;
  w.sea = sea;
  w.file = h5::open_file(path, true, h5_writing(writing));
  auto fail = [&](const std::string& what) { throw InputError(path + ": cannot continue the run: " + what); };
  w.floes_group = h5::open_group(w.file, "/floes", path);
  w.xdmf_group = h5::open_group(w.file, "/xdmf", path);
  // The /floes tables as they were at the checkpoint: the first n numbers.
  const std::vector<long long> offsets = h5::read_ints(h5::open_dataset(w.floes_group, "offsets", path), path + ": /floes/offsets");
  std::size_t n = c.floes.ids_issued;
  for (std::uint32_t id : c.floes.id) n = std::max<std::size_t>(n, id + 1);
  if (offsets.size() < n + 1) fail("/floes/offsets has " + std::to_string(offsets.size()) + " entries, the checkpoint numbers " + std::to_string(n) + " floes");
  w.n = n;
  w.offsets.assign(offsets.begin(), offsets.begin() + static_cast<std::ptrdiff_t>(n + 1));
  w.nverts = static_cast<std::size_t>(w.offsets.back());
  auto table = [&](hid_t g, const char* name, std::size_t count) {
    std::vector<double> v = h5::read_doubles(h5::open_dataset(g, name, path), path + ": /floes/" + name);
    if (v.size() < count) fail(std::string("/floes/") + name + " is shorter than the checkpoint's floes");
    v.resize(count);
    return v;
  };
  w.vertices = table(w.floes_group, "vertices", 2 * w.nverts);
  w.thickness = table(w.floes_group, "thickness", n);
  w.mass = table(w.floes_group, "mass", n);
  w.area = table(w.floes_group, "area", n);
  for (double x : table(w.floes_group, "static", n)) w.is_static.push_back(x != 0.0 ? 1 : 0);
  const std::vector<long long> topology = h5::read_ints(h5::open_dataset(w.xdmf_group, "topology", path), path + ": /xdmf/topology");
  const std::size_t ntopo = 2 * n + w.nverts;  // per floe: type, count, its vertex indices
  if (topology.size() < ntopo) fail("/xdmf/topology is shorter than the checkpoint's floes");
  w.topology.assign(topology.begin(), topology.begin() + static_cast<std::ptrdiff_t>(ntopo));
  w.write_tables();

  const auto records = static_cast<std::size_t>(c.records);
  if (c.record_floes.size() != records) fail("the checkpoint's record_floes does not count its records");
  auto open_rows = [&](hid_t loc, const char* name, const std::string& full) {
    h5::Handle d = h5::open_dataset(loc, name, path);
    std::vector<hsize_t> dims = h5::dims(d);
    if (dims.empty() || dims[0] < records)
      fail(full + " has fewer rows than the checkpoint's " + std::to_string(records) + " records");
    dims[0] = records;
    h5::set_extent(d, dims);
    return d;
  };
  w.time = open_rows(w.file, "time", "/time");
  w.times = h5::read_doubles(w.time, path + ": /time");
  w.state = open_rows(w.floes_group, "state", "/floes/state");
  h5::set_extent(w.state, {records, w.n, kStateColumns});
  w.verts = open_rows(w.xdmf_group, "vertices", "/xdmf/vertices");
  h5::set_extent(w.verts, {records, w.nverts, 3});
  h5::Handle d = h5::open_group(w.file, "/diagnostics", path);
  w.energy = open_rows(d, "energy", "/diagnostics/energy");
  if (h5::get_attr_strings(w.energy, "columns") != w.energy_columns)
    fail("/diagnostics/energy has other columns than this run's energies (another configuration?)");
  w.lcp = open_rows(d, "lcp", "/diagnostics/lcp");
  w.substeps = open_rows(d, "substeps", "/diagnostics/substeps");
  h5::Handle ev = h5::open_group(w.file, "/events", path);
  {
    w.events = h5::open_dataset(ev, "fracture", path);
    const auto events = static_cast<std::size_t>(c.fracture_events);
    if (h5::dims(w.events).at(0) < events) fail("/events/fracture has fewer rows than the checkpoint counts");
    h5::set_extent(w.events, {events, kFractureEventColumns});
    w.event_rows = events;
  }
  {
    // Made by the first rows (record_collisions): absent until then.
    const auto rows = static_cast<std::size_t>(c.collision_events);
    if (h5::exists(ev, "collisions")) {
      w.collisions = h5::open_dataset(ev, "collisions", path);
      if (h5::dims(w.collisions).at(0) < rows) fail("/events/collisions has fewer rows than the checkpoint counts");
      h5::set_extent(w.collisions, {rows, kCollisionEventColumns});
    } else if (rows > 0) {
      fail("/events/collisions is missing, the checkpoint counts " + std::to_string(rows) + " rows");
    }
    w.collision_rows = rows;
  }
  if (sea.dims > 0) {
    h5::Handle s = h5::open_group(w.file, "/sea", path);
    w.eta = open_rows(s, "eta", "/sea/eta");
  }
  for (long long k : c.record_floes) {
    if (k < 0 || static_cast<std::size_t>(k) > n) fail("the checkpoint's record_floes exceed its floes");
    const auto nk = static_cast<std::size_t>(k);
    w.record_floes.push_back(nk);
    w.record_vertices.push_back(static_cast<std::size_t>(w.offsets[nk]));
    w.record_topology.push_back(2 * nk + static_cast<std::size_t>(w.offsets[nk]));
  }
  w.records = records;
  h5::set_attr(w.file, "config", config_toml);
  h5::set_attr(w.file, "status", std::string("running"));
  H5Fflush(w.file, H5F_SCOPE_GLOBAL);
}

void RunWriter::count_into(Checkpoint& c) const {
  const Impl& w = *impl_;
  c.records = static_cast<long long>(w.records);
  c.fracture_events = static_cast<long long>(w.event_rows);
  c.collision_events = static_cast<long long>(w.collision_rows);
  c.record_floes.assign(w.record_floes.begin(), w.record_floes.end());
}

void RunWriter::write_checkpoint(const Checkpoint& c) {
  Impl& w = *impl_;
  w.guarded([&] {
  try {
    // A new group, then the old one replaced by it: a write that fails
    // midway (a full disk) keeps the previous checkpoint. (A kill keeps the
    // file as of its last flush: h5_published.hpp.)
    h5::remove(w.file, "checkpoint_new");
    write_checkpoint_group(w.file, "checkpoint_new", c);
    h5::remove(w.file, "checkpoint");
    if (H5Lmove(w.file, "checkpoint_new", w.file, "checkpoint", H5P_DEFAULT, H5P_DEFAULT) < 0)
      throw InputError("cannot rename /checkpoint_new");
    H5Fflush(w.file, H5F_SCOPE_GLOBAL);
  } catch (const InputError& e) {
    throw RunError(std::string("cannot write the checkpoint: ") + e.what());
  }
  });
}

std::string RunWriter::finish(const std::string& status) {
  Impl& w = *impl_;
  if (!w.file.valid()) return {};
  std::string problem;
  if (w.write_failed) problem = "its status could not be written (a write failed)";
  if (w.disk_full) {
    // The refused reservation left the file as last flushed; the end mark
    // takes a little room (what the last flush trimmed off the reservation).
    if (h5::reserve(w.file, kMetadataMargin) == 0) w.disk_full = false;
    else problem = "its status could not be written (the disk is full)";
  }
  if (!w.disk_full && !w.write_failed) {
    try {
      w.guarded([&] {
        h5::set_attr(w.file, "status", status);
        h5::set_attr(w.file, "records", static_cast<long long>(w.records));
        w.flush();
      });
    } catch (const RunError&) {
      problem = "its status could not be written";
    }
  }
  // The XDMF describes exactly the records in the file, or is removed.
  if (!w.write_xdmf()) {
    std::error_code ec;
    fs::remove(xdmf_path(), ec);
    problem += std::string(problem.empty() ? "" : "; ") + "the XDMF file could not be written (removed)";
  }
  // Datasets and groups first, the file last (its close is then the real one).
  for (h5::Handle* h : {&w.time, &w.state, &w.energy, &w.lcp, &w.substeps, &w.verts, &w.eta, &w.events,
                        &w.floes_group, &w.xdmf_group})
    h->reset();
  if (!w.write_failed) h5::trim(w.file);  // the unused reservation
  w.file.reset();
  return problem;
}

std::size_t RunWriter::records() const { return impl_->records; }
bool RunWriter::failed() const { return impl_->disk_full || impl_->write_failed; }
const std::string& RunWriter::path() const { return impl_->path; }
std::string RunWriter::xdmf_path() const { return fs::path(impl_->path).replace_extension(".xmf").string(); }

bool RunWriter::Impl::write_xdmf() const {
  const std::string h5name = fs::path(path).filename().string();
  const std::string xmf = fs::path(path).replace_extension(".xmf").string();
  const std::string tmp = xmf + ".tmp";
  std::ofstream o(tmp);
  if (!o) return false;  // ParaView support is a convenience: never fail a run for it
  o.precision(15);  // times and grid spacings as written, not to 6 digits
  const std::size_t T = times.size();
  // A hyperslab of an HDF5 dataset in the Xdmf3 library's own notation
  // (file:path|start:stride:count:dataset dims), which ParaView's XDMF3 readers
  // read; they skip XDMF2-style ItemType="HyperSlab" items (tests/apps/paraview_check.py).
  auto slab = [&](const std::string& out, const std::string& start, const std::string& stride,
                  const std::string& count, const std::string& full, const std::string& set,
                  const std::string& type = "Float") {
    return "<DataItem Dimensions=\"" + out + "\" NumberType=\"" + type + "\" Precision=\"8\" Format=\"HDF\">" +
           h5name + ":" + set + "|" + start + ":" + stride + ":" + count + ":" + full + "</DataItem>";
  };
  // Each record shows the floes numbered so far (the tables' sizes then);
  // floes that ended have NaN coordinates.
  const std::string sn = std::to_string(n), sv = std::to_string(nverts), sT = std::to_string(T);
  const std::string stopo = std::to_string(topology.size());
  o << "<?xml version=\"1.0\" ?>\n<Xdmf Version=\"3.0\">\n<Domain>\n";
  o << "<Grid Name=\"floes\" GridType=\"Collection\" CollectionType=\"Temporal\">\n";
  for (std::size_t k = 0; k < T; ++k) {
    const std::size_t nk = record_floes[k];
    if (nk == 0) continue;
    const std::string sk = std::to_string(k), snk = std::to_string(nk), svk = std::to_string(record_vertices[k]);
    const std::string stk = std::to_string(record_topology[k]);
    o << "<Grid Name=\"floes_" << k << "\" GridType=\"Uniform\"><Time Value=\"" << times[k] << "\"/>\n";
    o << "<Topology TopologyType=\"Mixed\" NumberOfElements=\"" << nk << "\">"
      << slab(stk, "0", "1", stk, stopo, "/xdmf/topology", "Int") << "</Topology>\n";
    o << "<Geometry GeometryType=\"XYZ\">"
      << slab(svk + " 3", sk + " 0 0", "1 1 1", "1 " + svk + " 3", sT + " " + sv + " 3", "/xdmf/vertices")
      << "</Geometry>\n";
    for (int c = 0; c < kStateColumns; ++c)
      o << "<Attribute Name=\"" << kStateColumnNames[c] << "\" AttributeType=\"Scalar\" Center=\"Cell\">"
        << slab(snk, sk + " 0 " + std::to_string(c), "1 1 1", "1 " + snk + " 1",
                sT + " " + sn + " " + std::to_string(kStateColumns), "/floes/state")
        << "</Attribute>\n";
    o << "<Attribute Name=\"thickness\" AttributeType=\"Scalar\" Center=\"Cell\">"
      << slab(snk, "0", "1", snk, sn, "/floes/thickness") << "</Attribute>\n";
    o << "</Grid>\n";
  }
  o << "</Grid>\n";
  if (sea.dims > 0) {
    const int nx = sea.cells[0], ny = sea.dims == 2 ? sea.cells[1] : 1;
    const double dx = sea.size[0] / nx, dy = sea.dims == 2 ? sea.size[1] / ny : sea.size[1];
    const std::string dims = std::to_string(ny) + " " + std::to_string(nx);
    o << "<Grid Name=\"sea\" GridType=\"Collection\" CollectionType=\"Temporal\">\n";
    for (std::size_t k = 0; k < T; ++k) {
      // A flat 3D grid (z slowest, one layer): ParaView's XDMF3 reader puts a
      // 2DCoRectMesh in the y-z plane, this one in the x-y plane.
      o << "<Grid Name=\"sea_" << k << "\" GridType=\"Uniform\"><Time Value=\"" << times[k] << "\"/>\n";
      o << "<Topology TopologyType=\"3DCoRectMesh\" Dimensions=\"1 " << dims << "\"/>\n";
      o << "<Geometry GeometryType=\"ORIGIN_DXDYDZ\"><DataItem Dimensions=\"3\" Format=\"XML\">0 " << 0.5 * dy
        << " " << 0.5 * dx << "</DataItem><DataItem Dimensions=\"3\" Format=\"XML\">1 " << dy << " " << dx
        << "</DataItem></Geometry>\n";
      const std::string sk = std::to_string(k);
      o << "<Attribute Name=\"eta\" AttributeType=\"Scalar\" Center=\"Node\">"
        << (sea.dims == 2 ? slab("1 " + dims, sk + " 0 0", "1 1 1", "1 " + dims, sT + " " + dims, "/sea/eta")
                          : slab("1 " + dims, sk + " 0", "1 1", "1 " + std::to_string(nx), sT + " " + std::to_string(nx),
                                 "/sea/eta"))
        << "</Attribute>\n";
      o << "</Grid>\n";
    }
    o << "</Grid>\n";
  }
  o << "</Domain>\n</Xdmf>\n";
  o.close();
  std::error_code ec;
  if (!o) {  // a full disk: keep the previous XDMF rather than a truncated one
    fs::remove(tmp, ec);
    return false;
  }
  fs::rename(tmp, xmf, ec);
  return !ec;
}

}  // namespace floesim
