#include "core/run_reader.hpp"

#include <filesystem>

#include "core/detail/h5.hpp"
#include "core/error.hpp"
#include "core/run_file.hpp"

namespace floesim {

struct RunReader::Impl {
  std::string path;
  h5::Handle file;

  h5::Handle open(const std::string& dataset) const { return h5::open_dataset(file, dataset, path); }
  std::string what(const std::string& dataset) const { return path + ": " + dataset; }

  // Reads the hyperslab [start, start + count) of `dataset` as doubles.
  std::vector<double> slab(const std::string& dataset, const std::vector<hsize_t>& start,
                           const std::vector<hsize_t>& count) const {
    h5::Handle d = open(dataset);
    h5::Handle type{H5Dget_type(d), H5Tclose};
    const H5T_class_t cls = H5Tget_class(type);
    if (cls != H5T_FLOAT && cls != H5T_INTEGER) throw InputError(what(dataset) + ": expected numbers");
    std::size_t n = 1;
    for (hsize_t c : count) n *= c;
    std::vector<double> v(n);
    if (n == 0) return v;
    h5::Handle space{H5Dget_space(d), H5Sclose};
    H5Sselect_hyperslab(space, H5S_SELECT_SET, start.data(), nullptr, count.data(), nullptr);
    h5::Handle mem{H5Screate_simple(static_cast<int>(count.size()), count.data(), nullptr), H5Sclose};
    if (H5Dread(d, H5T_NATIVE_DOUBLE, mem, space, H5P_DEFAULT, v.data()) < 0)
      throw InputError(what(dataset) + ": cannot read the dataset");
    return v;
  }
};

RunReader::RunReader(const std::string& path) : impl_(std::make_unique<Impl>()) {
  impl_->path = path;
  std::error_code ec;
  if (!std::filesystem::exists(path, ec) || ec) throw InputError(path + ": run file not found");
  impl_->file = h5::open_file(path);
  if (!h5::has_attr(impl_->file, "format"))
    throw InputError(path + ": not a floesim run file (root attribute 'format' is missing)");
  const std::string format = h5::get_attr_string(impl_->file, "format");
  if (format != kRunFormat)
    throw InputError(path + ": attribute 'format' is '" + format + "', expected '" + kRunFormat + "'");
}

RunReader::~RunReader() = default;
RunReader::RunReader(RunReader&&) noexcept = default;
RunReader& RunReader::operator=(RunReader&&) noexcept = default;

const std::string& RunReader::path() const { return impl_->path; }

bool RunReader::has(const std::string& dataset) const { return h5::exists(impl_->file, dataset); }

std::vector<std::size_t> RunReader::shape(const std::string& dataset) const {
  const auto d = h5::dims(impl_->open(dataset));
  return {d.begin(), d.end()};
}

std::vector<double> RunReader::read(const std::string& dataset) const {
  return h5::read_doubles(impl_->open(dataset), impl_->what(dataset));
}

std::vector<double> RunReader::read_rows(const std::string& dataset, std::size_t first, std::size_t count) const {
  const auto d = shape(dataset);
  if (d.empty() || first + count > d[0])
    throw InputError(impl_->what(dataset) + ": rows " + std::to_string(first) + ".." + std::to_string(first + count) +
                     " requested, the dataset has " + (d.empty() ? std::string("no rows") : std::to_string(d[0])));
  std::vector<hsize_t> start(d.size(), 0), cnt(d.begin(), d.end());
  start[0] = first;
  cnt[0] = count;
  return impl_->slab(dataset, start, cnt);
}

std::vector<double> RunReader::read_columns(const std::string& dataset, std::size_t first_col, std::size_t cols) const {
  const auto d = shape(dataset);
  if (d.size() < 2 || first_col + cols > d.back())
    throw InputError(impl_->what(dataset) + ": columns " + std::to_string(first_col) + ".." +
                     std::to_string(first_col + cols) + " requested, the last dimension has " +
                     (d.size() < 2 ? std::string("no columns") : std::to_string(d.back())));
  std::vector<hsize_t> start(d.size(), 0), cnt(d.begin(), d.end());
  start.back() = first_col;
  cnt.back() = cols;
  return impl_->slab(dataset, start, cnt);
}

std::vector<std::string> RunReader::strings(const std::string& dataset, const std::string& attribute) const {
  h5::Handle d = impl_->open(dataset);
  if (!h5::has_attr(d, attribute)) return {};
  return h5::get_attr_strings(d, attribute);
}

std::string RunReader::root_string(const std::string& attribute) const {
  if (!h5::has_attr(impl_->file, attribute)) return {};
  return h5::get_attr_string(impl_->file, attribute);
}

}  // namespace floesim
