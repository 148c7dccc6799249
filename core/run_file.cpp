#include "core/run_file.hpp"

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>

#include "core/detail/h5.hpp"
#include "core/error.hpp"
#include "core/floes.hpp"

namespace floesim {

namespace fs = std::filesystem;

struct RunWriter::Impl {
  std::string path;
  h5::Handle file, time, state, energy, lcp, verts, eta;
  std::size_t n = 0, nverts = 0, records = 0;
  std::size_t topology_size = 0;
  std::vector<double> times;
  std::vector<std::string> energy_columns;
  SeaGridInfo sea;
  std::chrono::steady_clock::time_point last_xdmf = std::chrono::steady_clock::now();
  std::vector<double> scratch;

  void write_xdmf() const;
};

RunWriter::RunWriter(const std::string& path, const Floes& floes, const std::string& config_toml,
                     std::vector<std::string> energy_columns, const SeaGridInfo& sea,
                     std::size_t expected_records)
    : impl_(std::make_unique<Impl>()) {
  Impl& w = *impl_;
  w.path = path;
  w.n = floes.size();
  w.nverts = floes.body.size();
  w.energy_columns = std::move(energy_columns);
  w.sea = sea;
  const hsize_t rows = expected_records;
  w.file = h5::create_file(path);
  h5::set_attr(w.file, "format", std::string(kRunFormat));
  h5::set_attr(w.file, "config", config_toml);
  h5::set_attr(w.file, "status", std::string("running"));

  w.time = h5::create_extendible(w.file, "time", {}, rows);
  h5::set_attr(w.time, "units", std::string("s"));

  h5::Handle g = h5::create_group(w.file, "/floes");
  std::vector<long long> off(floes.offsets.begin(), floes.offsets.end());
  h5::write_ints(g, "offsets", {w.n + 1}, off.data());
  h5::write_doubles(g, "vertices", {w.nverts, 2}, w.nverts ? floes.body[0].data() : nullptr);
  h5::write_doubles(g, "thickness", {w.n}, floes.thickness.data());
  h5::write_doubles(g, "mass", {w.n}, floes.mass.data());
  h5::write_doubles(g, "area", {w.n}, floes.area.data());
  std::vector<unsigned char> stat(floes.is_static.begin(), floes.is_static.end());
  h5::write_bytes(g, "static", {w.n}, stat.data());
  w.state = h5::create_extendible(g, "state", {w.n, kStateColumns}, rows);
  h5::set_attr(w.state, "columns", std::vector<std::string>(std::begin(kStateColumnNames), std::end(kStateColumnNames)));

  h5::Handle d = h5::create_group(w.file, "/diagnostics");
  w.energy = h5::create_extendible(d, "energy", {w.energy_columns.size()}, rows);
  h5::set_attr(w.energy, "columns", w.energy_columns);
  h5::set_attr(w.energy, "units", std::string("J"));
  w.lcp = h5::create_extendible(d, "lcp", {4}, rows);
  h5::set_attr(w.lcp, "columns", std::vector<std::string>{"solves", "pivots", "failures", "fallbacks"});

  if (sea.dims > 0) {
    h5::Handle s = h5::create_group(w.file, "/sea");
    const int nx = sea.cells[0], ny = sea.dims == 2 ? sea.cells[1] : 1;
    std::vector<double> x(static_cast<std::size_t>(nx)), y(static_cast<std::size_t>(ny));
    for (int i = 0; i < nx; ++i) x[static_cast<std::size_t>(i)] = (i + 0.5) * sea.size[0] / nx;
    for (int j = 0; j < ny; ++j) y[static_cast<std::size_t>(j)] = (j + 0.5) * sea.size[1] / ny;
    h5::write_doubles(s, "x", {x.size()}, x.data());
    h5::write_doubles(s, "y", {y.size()}, y.data());
    std::vector<hsize_t> row = sea.dims == 2 ? std::vector<hsize_t>{hsize_t(ny), hsize_t(nx)}
                                             : std::vector<hsize_t>{hsize_t(nx)};
    w.eta = h5::create_extendible(s, "eta", row, rows);
    h5::set_attr(w.eta, "units", std::string("m"));
  }

  // ParaView helpers: mixed-polygon topology (type 3 = polygon, vertex count,
  // vertex indices) and per-record world vertices.
  h5::Handle x = h5::create_group(w.file, "/xdmf");
  std::vector<long long> topo;
  for (std::size_t i = 0; i < w.n; ++i) {
    topo.push_back(3);
    topo.push_back(static_cast<long long>(floes.offsets[i + 1] - floes.offsets[i]));
    for (std::size_t k = floes.offsets[i]; k < floes.offsets[i + 1]; ++k) topo.push_back(static_cast<long long>(k));
  }
  w.topology_size = topo.size();
  h5::write_ints(x, "topology", {topo.size()}, topo.data());
  w.verts = h5::create_extendible(x, "vertices", {w.nverts, 3}, rows);
  H5Fflush(w.file, H5F_SCOPE_GLOBAL);
}

RunWriter::~RunWriter() {
  if (impl_ && impl_->file.valid()) {
    try { impl_->write_xdmf(); } catch (...) {}
  }
}

void RunWriter::record(double t, const Floes& floes, std::span<const double> energy,
                       const LcpCounters& lcp, std::span<const double> eta) {
  Impl& w = *impl_;
  FLOESIM_ASSERT(floes.size() == w.n && energy.size() == w.energy_columns.size());
  h5::append_row(w.time, &t);
  h5::append_row(w.state, reinterpret_cast<const double*>(floes.state.data()));
  h5::append_row(w.energy, energy.data());
  const double l[4] = {lcp.solves, lcp.pivots, lcp.failures, lcp.fallbacks};
  h5::append_row(w.lcp, l);
  w.scratch.resize(3 * w.nverts);
  for (std::size_t i = 0; i < w.n; ++i) {
    for (std::size_t k = floes.offsets[i]; k < floes.offsets[i + 1]; ++k) {
      const Vec2 p = floes.to_world(i, floes.body[k]);
      w.scratch[3 * k] = p.x();
      w.scratch[3 * k + 1] = p.y();
      w.scratch[3 * k + 2] = floes.state[i].heave;
    }
  }
  h5::append_row(w.verts, w.scratch.data());
  if (w.eta.valid()) {
    if (eta.empty()) throw RunError("run file: the sea elevation is missing from a record");
    h5::append_row(w.eta, eta.data());
  }
  w.times.push_back(t);
  ++w.records;
  H5Fflush(w.file, H5F_SCOPE_GLOBAL);
  // Keep the XDMF reasonably current without rewriting it at every record.
  const auto now = std::chrono::steady_clock::now();
  if (w.records == 1 || now - w.last_xdmf > std::chrono::seconds(5)) {
    w.write_xdmf();
    w.last_xdmf = now;
  }
}

void RunWriter::finish(const std::string& status) {
  Impl& w = *impl_;
  h5::set_attr(w.file, "status", status);
  h5::set_attr(w.file, "records", static_cast<long long>(w.records));
  H5Fflush(w.file, H5F_SCOPE_GLOBAL);
  w.write_xdmf();
  w.file.reset();
}

std::size_t RunWriter::records() const { return impl_->records; }
const std::string& RunWriter::path() const { return impl_->path; }
std::string RunWriter::xdmf_path() const { return fs::path(impl_->path).replace_extension(".xmf").string(); }

void RunWriter::Impl::write_xdmf() const {
  const std::string h5name = fs::path(path).filename().string();
  const std::string xmf = fs::path(path).replace_extension(".xmf").string();
  const std::string tmp = xmf + ".tmp";
  std::ofstream o(tmp);
  if (!o) return;  // ParaView support is a convenience: never fail a run for it
  const std::size_t T = times.size();
  auto hdf = [&](const std::string& dims, const std::string& type, const std::string& set) {
    return "<DataItem Dimensions=\"" + dims + "\" NumberType=\"" + type + "\" Precision=\"8\" Format=\"HDF\">" +
           h5name + ":" + set + "</DataItem>";
  };
  auto slab = [&](const std::string& out, const std::string& sel, int rank, const std::string& full,
                  const std::string& set) {
    return "<DataItem ItemType=\"HyperSlab\" Dimensions=\"" + out + "\" Type=\"HyperSlab\">"
           "<DataItem Dimensions=\"3 " + std::to_string(rank) + "\" Format=\"XML\">" + sel + "</DataItem>" +
           hdf(full, "Float", set) + "</DataItem>";
  };
  const std::string sn = std::to_string(n), sv = std::to_string(nverts), sT = std::to_string(T);
  o << "<?xml version=\"1.0\" ?>\n<Xdmf Version=\"3.0\">\n<Domain>\n";
  o << "<Grid Name=\"floes\" GridType=\"Collection\" CollectionType=\"Temporal\">\n";
  for (std::size_t k = 0; k < T && n > 0; ++k) {
    const std::string sk = std::to_string(k);
    o << "<Grid Name=\"floes_" << k << "\" GridType=\"Uniform\"><Time Value=\"" << times[k] << "\"/>\n";
    o << "<Topology TopologyType=\"Mixed\" NumberOfElements=\"" << n << "\">"
      << hdf(std::to_string(topology_size), "Int", "/xdmf/topology") << "</Topology>\n";
    o << "<Geometry GeometryType=\"XYZ\">"
      << slab(sv + " 3", sk + " 0 0 1 1 1 1 " + sv + " 3", 3, sT + " " + sv + " 3", "/xdmf/vertices")
      << "</Geometry>\n";
    for (int c = 0; c < kStateColumns; ++c)
      o << "<Attribute Name=\"" << kStateColumnNames[c] << "\" AttributeType=\"Scalar\" Center=\"Cell\">"
        << slab(sn, sk + " 0 " + std::to_string(c) + " 1 1 1 1 " + sn + " 1", 3,
                sT + " " + sn + " " + std::to_string(kStateColumns), "/floes/state")
        << "</Attribute>\n";
    o << "<Attribute Name=\"thickness\" AttributeType=\"Scalar\" Center=\"Cell\">"
      << hdf(sn, "Float", "/floes/thickness") << "</Attribute>\n";
    o << "</Grid>\n";
  }
  o << "</Grid>\n";
  if (sea.dims > 0) {
    const int nx = sea.cells[0], ny = sea.dims == 2 ? sea.cells[1] : 1;
    const double dx = sea.size[0] / nx, dy = sea.dims == 2 ? sea.size[1] / ny : sea.size[1];
    const std::string dims = std::to_string(ny) + " " + std::to_string(nx);
    o << "<Grid Name=\"sea\" GridType=\"Collection\" CollectionType=\"Temporal\">\n";
    for (std::size_t k = 0; k < T; ++k) {
      o << "<Grid Name=\"sea_" << k << "\" GridType=\"Uniform\"><Time Value=\"" << times[k] << "\"/>\n";
      o << "<Topology TopologyType=\"2DCoRectMesh\" Dimensions=\"" << dims << "\"/>\n";
      o << "<Geometry GeometryType=\"ORIGIN_DXDY\"><DataItem Dimensions=\"2\" Format=\"XML\">" << 0.5 * dy
        << " " << 0.5 * dx << "</DataItem><DataItem Dimensions=\"2\" Format=\"XML\">" << dy << " " << dx
        << "</DataItem></Geometry>\n";
      const std::string full = sea.dims == 2 ? sT + " " + dims : sT + " " + std::to_string(nx);
      const std::string sel = sea.dims == 2 ? std::to_string(k) + " 0 0 1 1 1 1 " + dims
                                            : std::to_string(k) + " 0 1 1 1 " + std::to_string(nx);
      o << "<Attribute Name=\"eta\" AttributeType=\"Scalar\" Center=\"Node\">"
        << slab(dims, sel, sea.dims == 2 ? 3 : 2, full, "/sea/eta") << "</Attribute>\n";
      o << "</Grid>\n";
    }
    o << "</Grid>\n";
  }
  o << "</Domain>\n</Xdmf>\n";
  o.close();
  std::error_code ec;
  fs::rename(tmp, xmf, ec);
}

// ---------------------------------------------------------------- reading

namespace {
std::vector<std::string> dataset_paths(hid_t file) {
  std::vector<std::string> out;
  auto visit = [](hid_t, const char* name, const H5O_info_t* info, void* data) -> herr_t {
    if (info->type == H5O_TYPE_DATASET)
      static_cast<std::vector<std::string>*>(data)->push_back(std::string("/") + name);
    return 0;
  };
  H5Ovisit2(file, H5_INDEX_NAME, H5_ITER_INC, visit, &out, H5O_INFO_BASIC);
  return out;
}
}  // namespace

RunInfo read_run_info(const std::string& path) {
  h5::Handle f = h5::open_file(path);
  RunInfo r;
  if (!h5::has_attr(f, "format"))
    throw InputError(path + ": not a floesim run file (root attribute 'format' is missing)");
  r.format = h5::get_attr_string(f, "format");
  if (r.format != kRunFormat)
    throw InputError(path + ": attribute 'format' is '" + r.format + "', expected '" + kRunFormat + "'");
  r.status = h5::has_attr(f, "status") ? h5::get_attr_string(f, "status") : "unknown";
  r.config = h5::has_attr(f, "config") ? h5::get_attr_string(f, "config") : "";
  const auto t = h5::read_doubles(h5::open_dataset(f, "/time", path), path + ": /time");
  r.records = t.size();
  if (!t.empty()) { r.t_first = t.front(); r.t_last = t.back(); }
  {
    h5::Handle th = h5::open_dataset(f, "/floes/thickness", path);
    r.floes = h5::dims(th).at(0);
    r.vertices = h5::dims(h5::open_dataset(f, "/floes/vertices", path)).at(0);
  }
  h5::Handle e = h5::open_dataset(f, "/diagnostics/energy", path);
  r.energy_columns = h5::get_attr_strings(e, "columns");
  const auto ev = h5::read_doubles(e, path + ": /diagnostics/energy");
  const std::size_t k = r.energy_columns.size();
  if (r.records && k && ev.size() >= k) r.energy_last.assign(ev.end() - static_cast<long>(k), ev.end());
  const auto lv = h5::read_doubles(h5::open_dataset(f, "/diagnostics/lcp", path), path + ": /diagnostics/lcp");
  if (lv.size() >= 4) for (int c = 0; c < 4; ++c) r.lcp_last[static_cast<std::size_t>(c)] = lv[lv.size() - 4 + static_cast<std::size_t>(c)];
  for (const std::string& p : dataset_paths(f)) {
    auto d = h5::dims(h5::open_dataset(f, p, path));
    r.datasets.emplace_back(p, std::vector<unsigned long long>(d.begin(), d.end()));
  }
  return r;
}

RunDataset read_run_dataset(const std::string& path, const std::string& dataset) {
  h5::Handle f = h5::open_file(path);
  if (!h5::has_attr(f, "format") || h5::get_attr_string(f, "format") != kRunFormat)
    throw InputError(path + ": not a floesim run file (attribute 'format' is not '" + std::string(kRunFormat) + "')");
  if (dataset.empty() || !h5::exists(f, dataset)) throw InputError(path + ": no dataset '" + dataset + "'");
  h5::Handle d = h5::open_dataset(f, dataset, path);
  RunDataset r;
  const auto dims = h5::dims(d);
  r.shape.assign(dims.begin(), dims.end());
  r.values = h5::read_doubles(d, path + ": " + dataset);
  if (h5::has_attr(d, "columns")) r.columns = h5::get_attr_strings(d, "columns");
  return r;
}

CompareResult compare_runs(const std::string& a, const std::string& b, const CompareOptions& opt) {
  h5::Handle fa = h5::open_file(a), fb = h5::open_file(b);
  for (auto [f, p] : {std::pair{fa.get(), a}, std::pair{fb.get(), b}})
    if (!h5::has_attr(f, "format") || h5::get_attr_string(f, "format") != kRunFormat)
      throw InputError(p + ": not a floesim run file (attribute 'format' is not '" + std::string(kRunFormat) + "')");
  CompareResult r;
  for (const std::string& p : dataset_paths(fa)) {
    if (!h5::exists(fb, p)) { r.differences.push_back({p, "missing in B"}); continue; }
    h5::Handle da = h5::open_dataset(fa, p, a), db = h5::open_dataset(fb, p, b);
    if (h5::dims(da) != h5::dims(db)) { r.differences.push_back({p, "shape"}); continue; }
    const auto va = h5::read_doubles(da, a + ": " + p), vb = h5::read_doubles(db, b + ": " + p);
    ++r.datasets_compared;
    DatasetDifference d{p, "values"};
    for (std::size_t i = 0; i < va.size(); ++i) {
      const double x = va[i], y = vb[i];
      if (std::isnan(x) && std::isnan(y)) continue;
      const double diff = std::abs(x - y);
      if (!(diff <= opt.atol + opt.rtol * std::abs(y))) {
        ++d.count;
        if (!(diff <= d.max_abs)) { d.max_abs = diff; d.at = i; }
      }
    }
    if (d.count) r.differences.push_back(d);
  }
  for (const std::string& p : dataset_paths(fb))
    if (!h5::exists(fa, p)) r.differences.push_back({p, "missing in A"});
  return r;
}

}  // namespace floesim
