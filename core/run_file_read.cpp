// Reading a run file's summary and datasets, and comparing two runs
// (core/run_file.hpp: read_run_info, read_run_dataset, compare_runs): what
// `floesim info`, `compare` and `regress` use. The writer is run_file.cpp.
#include <algorithm>
#include <cmath>
#include <sstream>

#include "core/detail/h5.hpp"
#include "core/error.hpp"
#include "core/run_file.hpp"

namespace floesim {

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
  // Read first in a child process: a file that crashes HDF5 is refused.
  h5::refuse_if_read_crashes(path, [&] { read_run_info_in_process(path); });
  return read_run_info_in_process(path);
}

RunInfo read_run_info_in_process(const std::string& path) {
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
  if (h5::exists(f, "/checkpoint")) {
    h5::Handle c = h5::open_group(f, "/checkpoint", path);
    if (h5::has_attr(c, "time")) r.checkpoint_time = h5::get_attr_double(c, "time");
  }
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
  if (h5::exists(f, "/diagnostics/substeps")) {  // absent in files written before it existed
    const auto sv = h5::read_doubles(h5::open_dataset(f, "/diagnostics/substeps", path), path + ": /diagnostics/substeps");
    if (sv.size() >= kSubstepColumns)
      std::copy(sv.end() - kSubstepColumns, sv.end(), r.substeps_last.begin());
  }
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

void validate(const CompareOptions& o) {
  for (auto [name, v] : {std::pair{"rtol", o.rtol}, std::pair{"atol", o.atol}})
    if (!(std::isfinite(v) && v >= 0.0)) {
      std::ostringstream m;
      m << "compare: " << name << " (tolerance): expected a finite number >= 0, got " << v;
      throw InputError(m.str());
    }
}

CompareResult compare_runs(const std::string& a, const std::string& b, const CompareOptions& opt) {
  validate(opt);
  h5::Handle fa = h5::open_file(a), fb = h5::open_file(b);
  for (auto [f, p] : {std::pair{fa.get(), a}, std::pair{fb.get(), b}})
    if (!h5::has_attr(f, "format") || h5::get_attr_string(f, "format") != kRunFormat)
      throw InputError(p + ": not a floesim run file (attribute 'format' is not '" + std::string(kRunFormat) + "')");
  CompareResult r;
  // /checkpoint is the means to continue a run, not one of its results.
  auto result = [](const std::string& p) { return p.rfind("/checkpoint", 0) != 0; };
  for (const std::string& p : dataset_paths(fa)) {
    if (!result(p)) continue;
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
    if (result(p) && !h5::exists(fa, p)) r.differences.push_back({p, "missing in A"});
  return r;
}

}  // namespace floesim
