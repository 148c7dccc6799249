#include "fuzz/h5_recipe.hpp"

#include <hdf5.h>

#include <cstdlib>
#include <cstring>
#include <sstream>
#include <vector>

#include "fuzz/fuzz_util.hpp"

namespace floesim::fuzz {

namespace {

constexpr std::size_t kMaxWritten = 65536;  // elements written per dataset
constexpr int kMaxCommands = 256;

hid_t type_of(const std::string& t) {
  if (t == "f64") return H5T_NATIVE_DOUBLE;
  if (t == "f32") return H5T_NATIVE_FLOAT;
  if (t == "i64") return H5T_NATIVE_LLONG;
  if (t == "i32") return H5T_NATIVE_INT;
  if (t == "u8") return H5T_NATIVE_UCHAR;
  return -1;
}

// "4,2" -> {4, 2}; "-" -> {} (scalar). False for anything else or rank > 4.
bool parse_dims(const std::string& s, std::vector<hsize_t>& dims) {
  dims.clear();
  if (s == "-") return true;
  std::stringstream in(s);
  std::string part;
  while (std::getline(in, part, ',')) {
    if (part.empty() || dims.size() == 4) return false;
    char* end = nullptr;
    const unsigned long long v = std::strtoull(part.c_str(), &end, 10);
    if (*end != '\0') return false;
    dims.push_back(v);
  }
  return !dims.empty();
}

// The element count, or kMaxWritten + 1 past it (overflow-safe).
std::size_t count(const std::vector<hsize_t>& dims) {
  std::size_t n = 1;
  for (hsize_t d : dims) {
    if (d != 0 && n > kMaxWritten / d) return kMaxWritten + 1;
    n *= static_cast<std::size_t>(d);
  }
  return n;
}

std::vector<double> numbers(std::istream& in) {
  std::vector<double> v;
  std::string tok;
  while (v.size() < kMaxWritten && in >> tok) v.push_back(std::strtod(tok.c_str(), nullptr));
  return v;
}

std::string rest_of_line(std::istream& in) {
  std::string s;
  std::getline(in, s);
  const auto b = s.find_first_not_of(' ');
  return b == std::string::npos ? std::string{} : s.substr(b);
}

// A fixed- or variable-length string datatype (caller closes it).
hid_t string_type(bool variable, std::size_t len) {
  hid_t t = H5Tcopy(H5T_C_S1);
  H5Tset_size(t, variable ? H5T_VARIABLE : (len ? len : 1));
  return t;
}

// Writes `values`, cycled to n elements, as doubles: HDF5 converts them to the
// stored type (integers saturate).
herr_t write_numbers(hid_t obj, std::size_t n, const std::vector<double>& values, bool attribute) {
  std::vector<double> buf(n, 0.0);
  for (std::size_t k = 0; k < n && !values.empty(); ++k) buf[k] = values[k % values.size()];
  return attribute ? H5Awrite(obj, H5T_NATIVE_DOUBLE, buf.data())
                   : H5Dwrite(obj, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, buf.data());
}

void dataset(hid_t file, hid_t lcpl, std::istream& in, bool chunked) {
  std::string path, type, dims_text;
  std::vector<hsize_t> dims;
  if (!(in >> path >> type >> dims_text) || !parse_dims(dims_text, dims)) return;
  const bool is_str = type == "str" || type == "vstr";
  const hid_t num = type_of(type);
  if (!is_str && num < 0) return;
  const std::size_t n = count(dims);
  const bool store = n <= kMaxWritten;
  hid_t space = dims.empty() ? H5Screate(H5S_SCALAR)
                             : H5Screate_simple(static_cast<int>(dims.size()), dims.data(), nullptr);
  if (space < 0) return;
  hid_t dcpl = H5Pcreate(H5P_DATASET_CREATE);
  H5Pset_alloc_time(dcpl, H5D_ALLOC_TIME_LATE);
  if (chunked && !dims.empty()) {
    std::vector<hsize_t> chunk(dims.size()), maxdims(dims.size(), H5S_UNLIMITED);
    for (std::size_t k = 0; k < dims.size(); ++k) chunk[k] = dims[k] == 0 ? 1 : (dims[k] < 64 ? dims[k] : 64);
    H5Sclose(space);
    space = H5Screate_simple(static_cast<int>(dims.size()), dims.data(), maxdims.data());
    H5Pset_chunk(dcpl, static_cast<int>(dims.size()), chunk.data());
  }
  if (is_str) {
    const std::string s = rest_of_line(in);
    const hid_t t = string_type(type == "vstr", s.size());
    const hid_t d = H5Dcreate2(file, path.c_str(), t, space, lcpl, dcpl, H5P_DEFAULT);
    if (d >= 0 && store && n > 0) {
      if (type == "vstr") {
        std::vector<const char*> p(n, s.c_str());
        H5Dwrite(d, t, H5S_ALL, H5S_ALL, H5P_DEFAULT, p.data());
      } else {
        std::string buf;
        for (std::size_t k = 0; k < n; ++k) buf += s.empty() ? std::string(1, '\0') : s;
        H5Dwrite(d, t, H5S_ALL, H5S_ALL, H5P_DEFAULT, buf.data());
      }
    }
    if (d >= 0) H5Dclose(d);
    H5Tclose(t);
  } else {
    const std::vector<double> v = numbers(in);
    const hid_t d = H5Dcreate2(file, path.c_str(), num, space, lcpl, dcpl, H5P_DEFAULT);
    if (d >= 0 && store && n > 0) write_numbers(d, n, v, false);
    if (d >= 0) H5Dclose(d);
  }
  H5Pclose(dcpl);
  H5Sclose(space);
}

void attribute(hid_t file, std::istream& in) {
  std::string obj, name, type;
  if (!(in >> obj >> name >> type)) return;
  const hid_t o = H5Oopen(file, obj.c_str(), H5P_DEFAULT);
  if (o < 0) return;
  if (type == "str" || type == "vstr") {
    const std::string s = rest_of_line(in);
    const hid_t t = string_type(type == "vstr", s.size());
    const hid_t space = H5Screate(H5S_SCALAR);
    const hid_t a = H5Acreate2(o, name.c_str(), t, space, H5P_DEFAULT, H5P_DEFAULT);
    if (a >= 0) {
      const char* p = s.c_str();
      if (type == "vstr") H5Awrite(a, t, &p);
      else H5Awrite(a, t, s.empty() ? "" : s.data());
      H5Aclose(a);
    }
    H5Sclose(space);
    H5Tclose(t);
  } else if (const hid_t num = type_of(type); num >= 0) {
    const std::vector<double> v = numbers(in);
    const hsize_t n = v.empty() ? 1 : v.size();
    const hid_t space = v.size() <= 1 ? H5Screate(H5S_SCALAR) : H5Screate_simple(1, &n, nullptr);
    const hid_t a = H5Acreate2(o, name.c_str(), num, space, H5P_DEFAULT, H5P_DEFAULT);
    if (a >= 0) {
      write_numbers(a, static_cast<std::size_t>(n), v, true);
      H5Aclose(a);
    }
    H5Sclose(space);
  }
  H5Oclose(o);
}

}  // namespace

bool build_h5(const std::string& path, const std::uint8_t* data, std::size_t size) {
  static const bool quiet = [] { return H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr) >= 0; }();
  (void)quiet;
  static const std::uint8_t kSignature[8] = {0x89, 'H', 'D', 'F', '\r', '\n', 0x1a, '\n'};
  if (size >= 8 && std::memcmp(data, kSignature, 8) == 0) {
    static const bool recipes_only = std::getenv("FLOESIM_FUZZ_RECIPES_ONLY") != nullptr;
    if (recipes_only) return false;
    write_file(path, data, size);
    return true;
  }
  const hid_t file = H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
  if (file < 0) return false;
  const hid_t lcpl = H5Pcreate(H5P_LINK_CREATE);
  H5Pset_create_intermediate_group(lcpl, 1);
  std::stringstream lines(std::string(reinterpret_cast<const char*>(data), size));
  std::string line;
  for (int k = 0; k < kMaxCommands && std::getline(lines, line);) {
    std::stringstream in(line);
    std::string cmd;
    if (!(in >> cmd)) continue;
    ++k;
    if (cmd == "group") {
      std::string p;
      if (in >> p) {
        const hid_t g = H5Gcreate2(file, p.c_str(), lcpl, H5P_DEFAULT, H5P_DEFAULT);
        if (g >= 0) H5Gclose(g);
      }
    } else if (cmd == "dset" || cmd == "cdset") {
      dataset(file, lcpl, in, cmd == "cdset");
    } else if (cmd == "attr") {
      attribute(file, in);
    } else if (cmd == "soft") {
      std::string p, target;
      if (in >> p >> target) H5Lcreate_soft(target.c_str(), file, p.c_str(), lcpl, H5P_DEFAULT);
    }
  }
  H5Pclose(lcpl);
  H5Fclose(file);
  return true;
}

}  // namespace floesim::fuzz
