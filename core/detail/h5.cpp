#include "core/detail/h5.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <sys/wait.h>

#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <limits>
#include <mutex>

#include "core/detail/h5_published.hpp"
#include "core/error.hpp"

namespace floesim::h5 {

namespace {
[[noreturn]] void fail(const std::string& msg) { throw InputError(msg); }
// A file that cannot be created or written: not the input's fault (exit 1).
[[noreturn]] void fail_write(const std::string& msg) { throw RunError(msg); }
}  // namespace

void silence_errors() {
  static std::once_flag once;
  std::call_once(once, [] { H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr); });
}

bool is_hdf5(const std::string& path) {
  silence_errors();
  return H5Fis_hdf5(path.c_str()) > 0;
}

namespace {
// The file access list for writing `path` as `how` says: the publishing
// driver's, or the sec2 driver's (in place, also for a path that is not a
// regular file). In place, the helper copies of an earlier published writer
// go, so that no stale copy stays beside the file.
Handle write_fapl(const std::string& path, Writing how) {
  Handle fapl{how == Writing::published ? published_fapl(path) : hid_t{-1}, H5Pclose};
  if (!fapl.valid()) {
    fapl = Handle{H5Pcreate(H5P_FILE_ACCESS), H5Pclose};
    H5Pset_fapl_sec2(fapl);
  }
  if (how == Writing::in_place) {
    std::remove(working_path(path).c_str());
    std::remove(previous_path(path).c_str());
  }
  H5Pset_file_locking(fapl, false, true);
  return fapl;
}
}  // namespace

Handle open_file(const std::string& path, bool write, Writing how) {
  silence_errors();
  if (!is_hdf5(path)) fail(path + ": not an HDF5 file (or it cannot be read)");
  // A file continued (written) is written as one created.
  Handle fapl = write ? write_fapl(path, how) : Handle{H5Pcreate(H5P_FILE_ACCESS), H5Pclose};
  hid_t f = H5Fopen(path.c_str(), write ? H5F_ACC_RDWR : H5F_ACC_RDONLY, fapl);
  if (f < 0) fail(path + ": cannot open the HDF5 file" + (write ? " for writing" : ""));
  return {f, H5Fclose};
}

void check_global_heaps(const std::string& path) {
  // HDF5 File Format Specification, "Global Heap": "GCOL", version 1, 3
  // reserved bytes, the collection size (8 bytes, counting this header),
  // then objects: index (2), reference count (2), reserved (4), size (8) and
  // the data padded to 8 bytes; index 0 is the free space, whose size counts
  // its own header. HDF5 steps from one object to the next by that size and
  // never checks that it moves. Collections are found by their signature;
  // bytes of a dataset that happen to read "GCOL" are walked too, harmlessly:
  // only a step of 0 is refused.
  std::ifstream in(path, std::ios::binary);
  if (!in) return;  // open_file names the problem
  auto u16 = [](const unsigned char* b) { return static_cast<unsigned>(b[0] | (b[1] << 8)); };
  auto u64 = [](const unsigned char* b) {
    std::uint64_t v = 0;
    for (int k = 7; k >= 0; --k) v = (v << 8) | b[k];
    return v;
  };
  auto read_at = [&](std::uint64_t at, unsigned char* b, std::size_t n) {
    in.clear();
    in.seekg(static_cast<std::streamoff>(at));
    return static_cast<bool>(in.read(reinterpret_cast<char*>(b), static_cast<std::streamsize>(n)));
  };
  auto walk = [&](std::uint64_t at) {
    unsigned char h[16];
    if (!read_at(at, h, 16) || h[4] != 1) return;
    const std::uint64_t size = u64(h + 8);
    if (size < 16 || size > (std::uint64_t{1} << 40)) return;  // HDF5 refuses these itself
    for (std::uint64_t p = 16; p + 16 <= size;) {
      if (!read_at(at + p, h, 16)) return;
      const unsigned index = u16(h);
      const std::uint64_t obj = u64(h + 8);
      const std::uint64_t step = index > 0 ? 16 + ((obj + 7) / 8) * 8 : obj;
      if (step == 0)
        fail(path + ": corrupted HDF5 file: the global heap at byte " + std::to_string(at) +
             " holds an empty free-space object at byte " + std::to_string(at + p) +
             ", which HDF5 would read without end");
      // An object must lie inside its collection: HDF5 copies `obj` bytes
      // from it without checking (a read past the heap's memory).
      if (index > 0 && obj > size - p - 16)
        fail(path + ": corrupted HDF5 file: object " + std::to_string(index) + " of the global heap at byte " +
             std::to_string(at) + " claims " + std::to_string(obj) + " bytes, more than the " +
             std::to_string(size - p - 16) + " left in its collection");
      if (obj > size) return;  // the free space runs past the collection: HDF5 stops there
      p += step;
    }
  };
  std::vector<char> buf(std::size_t{1} << 20);
  std::vector<std::uint64_t> found;
  std::uint64_t base = 0;  // file offset of buf[0]
  std::size_t keep = 0;    // bytes carried over from the previous block
  while (true) {
    in.read(buf.data() + keep, static_cast<std::streamsize>(buf.size() - keep));
    const std::size_t n = keep + static_cast<std::size_t>(in.gcount());
    if (n < 4) break;
    for (std::size_t k = 0; k + 4 <= n; ++k)
      if (buf[k] == 'G' && buf[k + 1] == 'C' && buf[k + 2] == 'O' && buf[k + 3] == 'L') found.push_back(base + k);
    if (!in) break;
    std::copy(buf.begin() + static_cast<std::ptrdiff_t>(n - 3), buf.begin() + static_cast<std::ptrdiff_t>(n), buf.begin());
    base += n - 3;
    keep = 3;
  }
  for (std::uint64_t at : found) walk(at);
}

Handle create_file(const std::string& path, Writing how) {
  silence_errors();
  // No file lock: a run file is written by one process and may be read by
  // others (scripts, `floesim info`) while the run goes on. Published
  // (h5_published.hpp), the name `path` holds the file as of its last flush,
  // whole, whatever instant the writer is stopped at; in place (by choice,
  // or a path that is not a regular file such as /dev/full), on the sec2
  // driver. Both give reserve() a file descriptor.
  Handle fapl = write_fapl(path, how);
  errno = 0;
  hid_t f = H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, fapl);
  if (f < 0) {
    const int err = errno;
    const bool folder = err == ENOENT || err == EACCES || err == EROFS || err == ENOTDIR || err == 0;
    fail_write(path + ": cannot create the file (" + (err ? std::strerror(err) : "unknown reason") +
               (folder ? "; does its folder exist and is it writable?)" : ")"));
  }
  return {f, H5Fclose};
}

bool flush(hid_t file) { return H5Fflush(file, H5F_SCOPE_GLOBAL) >= 0; }

namespace {
// The POSIX file descriptor under an HDF5 file on the sec2 driver, or -1.
int descriptor(hid_t file) {
  Handle fapl{H5Fget_access_plist(file), H5Pclose};
  if (!fapl.valid() || H5Pget_driver(fapl) != H5FD_SEC2) return -1;
  void* handle = nullptr;
  if (H5Fget_vfd_handle(file, fapl, &handle) < 0 || !handle) return -1;
  return *static_cast<int*>(handle);
}

// The descriptor of the file HDF5 writes and its end of allocation; for a
// published file, also the other copy's descriptor (else -1). False when none.
bool where_written(hid_t file, int& fd, int& other, haddr_t& eoa) {
  other = -1;
  if (const PublishedHandle* h = published_handle(file)) {
    fd = h->fd[0];
    other = h->fd[1];
    eoa = h->eoa;
    return fd >= 0;
  }
  fd = descriptor(file);
  return fd >= 0 && H5Fget_eoa(file, &eoa) >= 0;
}
}  // namespace

int reserve(hid_t file, hsize_t bytes) {
  int fd = -1, other = -1;
  haddr_t eoa = 0;
  if (!where_written(file, fd, other, eoa)) return 0;
  struct stat st {};
  if (fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) return 0;
  int err = posix_fallocate(fd, static_cast<off_t>(eoa), static_cast<off_t>(bytes));
  // A published file's other copy receives the same bytes at the next publication.
  if (err == 0 && other >= 0) err = posix_fallocate(other, static_cast<off_t>(eoa), static_cast<off_t>(bytes));
  return err == EOPNOTSUPP || err == ENODEV || err == ESPIPE ? 0 : err;
}

void trim(hid_t file) {
  int fd = -1, other = -1;
  haddr_t eoa = 0;
  struct stat st {};
  if (!where_written(file, fd, other, eoa) || fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) return;
  if (static_cast<haddr_t>(st.st_size) > eoa && ftruncate(fd, static_cast<off_t>(eoa)) != 0) return;
}

bool exists(hid_t loc, const std::string& path) {
  // Check each link along the path, as H5Lexists requires.
  std::size_t pos = path[0] == '/' ? 1 : 0;
  while (pos <= path.size()) {
    const std::size_t next = path.find('/', pos);
    const std::string prefix = path.substr(0, next);
    if (H5Lexists(loc, prefix.c_str(), H5P_DEFAULT) <= 0) return false;
    if (next == std::string::npos) break;
    pos = next + 1;
  }
  return true;
}

Handle open_dataset(hid_t loc, const std::string& path, const std::string& file) {
  if (!exists(loc, path)) fail(file + ": dataset '" + path + "' is missing");
  hid_t d = H5Dopen2(loc, path.c_str(), H5P_DEFAULT);
  if (d < 0) fail(file + ": '" + path + "' is not a readable dataset");
  return {d, H5Dclose};
}

Handle open_group(hid_t loc, const std::string& path, const std::string& file) {
  if (!exists(loc, path)) fail(file + ": group '" + path + "' is missing");
  hid_t g = H5Gopen2(loc, path.c_str(), H5P_DEFAULT);
  if (g < 0) fail(file + ": '" + path + "' is not a group");
  return {g, H5Gclose};
}

Handle create_group(hid_t loc, const std::string& path) {
  hid_t g = H5Gcreate2(loc, path.c_str(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  if (g < 0) fail_write("cannot create HDF5 group '" + path + "'");
  return {g, H5Gclose};
}

std::vector<hsize_t> dims(hid_t dataset) {
  Handle space{H5Dget_space(dataset), H5Sclose};
  const int rank = H5Sget_simple_extent_ndims(space);
  std::vector<hsize_t> d(static_cast<std::size_t>(rank > 0 ? rank : 0));
  if (rank > 0) H5Sget_simple_extent_dims(space, d.data(), nullptr);
  return d;
}

namespace {
const char* class_name(H5T_class_t cls) {
  switch (cls) {
    case H5T_INTEGER: return "integers";
    case H5T_FLOAT: return "floating-point numbers";
    case H5T_STRING: return "strings";
    case H5T_ENUM: return "an enumeration (h5py writes booleans so)";
    case H5T_COMPOUND: return "a compound type";
    default: return "a non-numeric type";
  }
}

std::string shape_text(const std::vector<hsize_t>& shape) {
  std::string t;
  for (hsize_t d : shape) t += (t.empty() ? "" : " x ") + std::to_string(d);
  return "[" + t + "]";
}

// Checks that the file really holds the elements `shape` claims: layouts that
// store every element (contiguous, compact) must have n * element size bytes
// (chunked datasets may leave chunks unwritten, read as the fill value, so
// their storage says nothing). Overflow-safe.
void check_stored(hid_t dataset, hid_t type, const std::vector<hsize_t>& shape, const std::string& what) {
  Handle plist{H5Dget_create_plist(dataset), H5Pclose};
  const H5D_layout_t layout = plist.valid() ? H5Pget_layout(plist) : H5D_LAYOUT_ERROR;
  if (layout != H5D_CONTIGUOUS && layout != H5D_COMPACT) return;
  const hsize_t stored = H5Dget_storage_size(dataset);
  hsize_t need = H5Tget_size(type);
  for (hsize_t d : shape) need = (d != 0 && need > stored / d) ? stored + 1 : need * d;
  if (need > stored)
    fail(what + ": the dataspace claims " + shape_text(shape) + " entries but the file stores " +
         std::to_string(stored) + " bytes for them (the file is truncated or corrupted)");
}

// Number of elements of `shape`, refused above kMaxElements (overflow-safe).
// Called before any allocation.
std::size_t bounded_count(const std::vector<hsize_t>& shape, const std::string& what) {
  std::size_t n = 1;
  for (hsize_t d : shape) n = (d != 0 && n > kMaxElements / d) ? kMaxElements + 1 : n * static_cast<std::size_t>(d);
  if (n > kMaxElements)
    fail(what + ": the dataspace claims " + shape_text(shape) + " entries, more than the " +
         std::to_string(kMaxElements) + " one dataset may hold (is the file corrupted?)");
  return n;
}

template <class T>
std::vector<T> read_as(hid_t dataset, hid_t mem_type, bool integers_only, const std::string& what) {
  Handle type{H5Dget_type(dataset), H5Tclose};
  const H5T_class_t cls = H5Tget_class(type);
  if (integers_only && cls != H5T_INTEGER)
    fail(what + ": expected integers, got " + class_name(cls));
  if (cls != H5T_FLOAT && cls != H5T_INTEGER)
    fail(what + ": expected numbers (integers or floats), got " + class_name(cls));
  const std::vector<hsize_t> d = dims(dataset);
  const std::size_t count = bounded_count(d, what);
  check_stored(dataset, type, d, what);  // before the allocation: a corrupt dataspace may claim 2^28 entries
  std::vector<T> v(count);
  if (!v.empty() && H5Dread(dataset, mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data()) < 0)
    fail(what + ": cannot read the dataset");
  return v;
}
}  // namespace

std::vector<double> read_doubles(hid_t dataset, const std::string& what) {
  return read_as<double>(dataset, H5T_NATIVE_DOUBLE, false, what);
}
std::vector<long long> read_ints(hid_t dataset, const std::string& what) {
  return read_as<long long>(dataset, H5T_NATIVE_LLONG, true, what);
}

std::vector<double> read_first_record(hid_t dataset, const std::string& what) {
  Handle type{H5Dget_type(dataset), H5Tclose};
  const H5T_class_t cls = H5Tget_class(type);
  if (cls != H5T_FLOAT && cls != H5T_INTEGER)
    fail(what + ": expected numbers (integers or floats), got " + class_name(cls));
  const std::vector<hsize_t> d = dims(dataset);
  if (d.empty() || d[0] == 0) fail(what + ": expected at least one record");
  // The whole dataset must be stored (a claim of 4e9 records in 100 bytes is a
  // corrupted file even if only record 0 is read); only record 0 is bounded.
  check_stored(dataset, type, d, what);
  std::vector<hsize_t> start(d.size(), 0), cnt = d;
  cnt[0] = 1;
  std::vector<double> v(bounded_count(cnt, what));
  if (v.empty()) return v;
  Handle space{H5Dget_space(dataset), H5Sclose};
  Handle mem{H5Screate_simple(static_cast<int>(cnt.size()), cnt.data(), nullptr), H5Sclose};
  if (H5Sselect_hyperslab(space, H5S_SELECT_SET, start.data(), nullptr, cnt.data(), nullptr) < 0 ||
      H5Dread(dataset, H5T_NATIVE_DOUBLE, mem, space, H5P_DEFAULT, v.data()) < 0)
    fail(what + ": cannot read the dataset");
  return v;
}

namespace {
void write_raw(hid_t loc, const std::string& name, const std::vector<hsize_t>& d, hid_t file_type,
               hid_t mem_type, const void* data) {
  Handle space{H5Screate_simple(static_cast<int>(d.size()), d.data(), nullptr), H5Sclose};
  Handle set{H5Dcreate2(loc, name.c_str(), file_type, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT),
             H5Dclose};
  if (!set.valid()) fail_write("cannot create dataset '" + name + "'");
  bool empty = false;
  for (hsize_t x : d) empty = empty || x == 0;
  if (!empty && H5Dwrite(set, mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data) < 0)
    fail_write("cannot write dataset '" + name + "'");
}
}  // namespace

void write_doubles(hid_t loc, const std::string& name, const std::vector<hsize_t>& d,
                   const double* data) {
  write_raw(loc, name, d, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, data);
}
void write_ints(hid_t loc, const std::string& name, const std::vector<hsize_t>& d,
                const long long* data) {
  write_raw(loc, name, d, H5T_STD_I64LE, H5T_NATIVE_LLONG, data);
}
void write_bytes(hid_t loc, const std::string& name, const std::vector<hsize_t>& d,
                 const unsigned char* data) {
  write_raw(loc, name, d, H5T_STD_U8LE, H5T_NATIVE_UCHAR, data);
}

Handle create_extendible(hid_t loc, const std::string& name, const std::vector<hsize_t>& row,
                         hsize_t rows_hint) {
  std::vector<hsize_t> d{0}, maxd{H5S_UNLIMITED}, chunk{1};
  std::size_t row_size = 1;
  for (hsize_t r : row) {
    // An empty dimension (a run without floes) cannot be chunked as fixed-size.
    d.push_back(r);
    maxd.push_back(r ? r : H5S_UNLIMITED);
    chunk.push_back(r ? r : 1);
    row_size *= r ? r : 1;
  }
  // Aim for chunks of about 64 KiB: several rows per chunk when rows are small.
  chunk[0] = std::max<hsize_t>(1, 8192 / std::max<std::size_t>(row_size, 1));
  if (rows_hint > 0) chunk[0] = std::min(chunk[0], rows_hint);
  Handle space{H5Screate_simple(static_cast<int>(d.size()), d.data(), maxd.data()), H5Sclose};
  Handle props{H5Pcreate(H5P_DATASET_CREATE), H5Pclose};
  H5Pset_chunk(props, static_cast<int>(chunk.size()), chunk.data());
  hid_t set = H5Dcreate2(loc, name.c_str(), H5T_IEEE_F64LE, space, H5P_DEFAULT, props, H5P_DEFAULT);
  if (set < 0) fail_write("cannot create dataset '" + name + "'");
  return {set, H5Dclose};
}

void append_row(hid_t dataset, const double* row) {
  std::vector<hsize_t> d = dims(dataset);
  const hsize_t t = d[0];
  d[0] = t + 1;
  if (H5Dset_extent(dataset, d.data()) < 0) fail_write("cannot extend a run-file dataset");
  Handle space{H5Dget_space(dataset), H5Sclose};
  std::vector<hsize_t> start(d.size(), 0), cnt = d;
  start[0] = t;
  cnt[0] = 1;
  H5Sselect_hyperslab(space, H5S_SELECT_SET, start.data(), nullptr, cnt.data(), nullptr);
  Handle mem{H5Screate_simple(static_cast<int>(cnt.size()), cnt.data(), nullptr), H5Sclose};
  if (H5Dwrite(dataset, H5T_NATIVE_DOUBLE, mem, space, H5P_DEFAULT, row) < 0)
    fail_write("cannot append to a run-file dataset");
}

Handle create_growable(hid_t loc, const std::string& name, const std::vector<hsize_t>& row,
                       hsize_t rows_hint) {
  std::vector<hsize_t> d{0}, maxd{H5S_UNLIMITED}, chunk{1};
  std::size_t row_size = 1;
  for (hsize_t r : row) {
    d.push_back(r);
    maxd.push_back(H5S_UNLIMITED);
    chunk.push_back(std::max<hsize_t>(r, 1));
    row_size *= std::max<hsize_t>(r, 1);
  }
  chunk[0] = std::max<hsize_t>(1, 8192 / std::max<std::size_t>(row_size, 1));
  if (rows_hint > 0) chunk[0] = std::min(chunk[0], rows_hint);
  Handle space{H5Screate_simple(static_cast<int>(d.size()), d.data(), maxd.data()), H5Sclose};
  Handle props{H5Pcreate(H5P_DATASET_CREATE), H5Pclose};
  H5Pset_chunk(props, static_cast<int>(chunk.size()), chunk.data());
  const double nan = std::numeric_limits<double>::quiet_NaN();
  H5Pset_fill_value(props, H5T_NATIVE_DOUBLE, &nan);
  hid_t set = H5Dcreate2(loc, name.c_str(), H5T_IEEE_F64LE, space, H5P_DEFAULT, props, H5P_DEFAULT);
  if (set < 0) fail_write("cannot create dataset '" + name + "'");
  return {set, H5Dclose};
}

void set_extent(hid_t dataset, const std::vector<hsize_t>& d) {
  if (H5Dset_extent(dataset, d.data()) < 0) fail_write("cannot resize a run-file dataset");
}

hsize_t append_bytes(hid_t dataset) {
  const std::vector<hsize_t> d = dims(dataset);
  Handle plist{H5Dget_create_plist(dataset), H5Pclose};
  std::vector<hsize_t> chunk(d.size(), 1);
  if (d.empty() || !plist.valid() || H5Pget_chunk(plist, static_cast<int>(chunk.size()), chunk.data()) < 0)
    return 0;
  hsize_t bytes = 8 * std::max<hsize_t>(chunk[0], 1);
  for (std::size_t i = 1; i < d.size(); ++i) {
    const hsize_t c = std::max<hsize_t>(chunk[i], 1);
    bytes *= (std::max<hsize_t>(d[i], 1) + c - 1) / c * c;
  }
  return bytes;
}

void remove(hid_t loc, const std::string& name) {
  if (H5Lexists(loc, name.c_str(), H5P_DEFAULT) > 0 && H5Ldelete(loc, name.c_str(), H5P_DEFAULT) < 0)
    fail_write("cannot replace dataset '" + name + "'");
}

namespace {
Handle string_type(std::size_t) {
  Handle t{H5Tcopy(H5T_C_S1), H5Tclose};
  H5Tset_size(t, H5T_VARIABLE);
  H5Tset_cset(t, H5T_CSET_UTF8);
  return t;
}
void replace_attr(hid_t obj, const std::string& name) {
  if (H5Aexists(obj, name.c_str()) > 0) H5Adelete(obj, name.c_str());
}
}  // namespace

void set_attr(hid_t obj, const std::string& name, const std::string& value) {
  replace_attr(obj, name);
  Handle type = string_type(value.size());
  Handle space{H5Screate(H5S_SCALAR), H5Sclose};
  Handle a{H5Acreate2(obj, name.c_str(), type, space, H5P_DEFAULT, H5P_DEFAULT), H5Aclose};
  const char* p = value.c_str();
  if (!a.valid() || H5Awrite(a, type, &p) < 0) fail_write("cannot write attribute '" + name + "'");
}

void set_attr(hid_t obj, const std::string& name, const std::vector<std::string>& values) {
  replace_attr(obj, name);
  Handle type = string_type(0);
  const hsize_t n = values.size();
  Handle space{H5Screate_simple(1, &n, nullptr), H5Sclose};
  Handle a{H5Acreate2(obj, name.c_str(), type, space, H5P_DEFAULT, H5P_DEFAULT), H5Aclose};
  std::vector<const char*> p;
  for (const auto& s : values) p.push_back(s.c_str());
  if (!a.valid() || H5Awrite(a, type, p.data()) < 0) fail_write("cannot write attribute '" + name + "'");
}

namespace {
template <class T>
void set_scalar(hid_t obj, const std::string& name, hid_t file_type, hid_t mem_type, T value) {
  replace_attr(obj, name);
  Handle space{H5Screate(H5S_SCALAR), H5Sclose};
  Handle a{H5Acreate2(obj, name.c_str(), file_type, space, H5P_DEFAULT, H5P_DEFAULT), H5Aclose};
  if (!a.valid() || H5Awrite(a, mem_type, &value) < 0) fail_write("cannot write attribute '" + name + "'");
}
}  // namespace

void set_attr(hid_t obj, const std::string& name, double value) {
  set_scalar(obj, name, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, value);
}
void set_attr(hid_t obj, const std::string& name, long long value) {
  set_scalar(obj, name, H5T_STD_I64LE, H5T_NATIVE_LLONG, value);
}

bool has_attr(hid_t obj, const std::string& name) { return H5Aexists(obj, name.c_str()) > 0; }

std::vector<std::string> get_attr_strings(hid_t obj, const std::string& name) {
  if (!has_attr(obj, name)) fail("attribute '" + name + "' is missing");
  Handle a{H5Aopen(obj, name.c_str(), H5P_DEFAULT), H5Aclose};
  Handle ftype{H5Aget_type(a), H5Tclose};
  if (H5Tget_class(ftype) != H5T_STRING) fail("attribute '" + name + "' is not a string");
  Handle space{H5Aget_space(a), H5Sclose};
  const hssize_t n = H5Sget_simple_extent_npoints(space);
  std::vector<std::string> out;
  if (H5Tis_variable_str(ftype) > 0) {
    // In memory with the file's character set: HDF5 converts no string
    // between ASCII and UTF-8, and C writers (FloeDyn) use ASCII.
    Handle mtype = string_type(0);
    H5Tset_cset(mtype, H5Tget_cset(ftype));
    std::vector<char*> p(static_cast<std::size_t>(n), nullptr);
    if (H5Aread(a, mtype, p.data()) < 0) fail("cannot read attribute '" + name + "'");
    for (char* s : p) out.emplace_back(s ? s : "");
    H5Dvlen_reclaim(mtype, space, H5P_DEFAULT, p.data());
  } else {
    const std::size_t len = H5Tget_size(ftype);
    std::vector<char> buf(len * static_cast<std::size_t>(n) + 1, '\0');
    if (H5Aread(a, ftype, buf.data()) < 0) fail("cannot read attribute '" + name + "'");
    for (hssize_t i = 0; i < n; ++i) {
      std::string s(buf.data() + static_cast<std::size_t>(i) * len, len);
      out.push_back(s.substr(0, s.find('\0')));
    }
  }
  return out;
}

std::string get_attr_string(hid_t obj, const std::string& name) {
  auto v = get_attr_strings(obj, name);
  return v.empty() ? std::string{} : v[0];
}

double get_attr_double(hid_t obj, const std::string& name) {
  if (!has_attr(obj, name)) fail("attribute '" + name + "' is missing");
  Handle a{H5Aopen(obj, name.c_str(), H5P_DEFAULT), H5Aclose};
  // H5Aread writes every element: an array attribute would overrun v.
  Handle space{H5Aget_space(a), H5Sclose};
  const hssize_t n = H5Sget_simple_extent_npoints(space);
  if (n != 1)
    fail("attribute '" + name + "' holds " + std::to_string(n) + " values, expected one number");
  double v = 0.0;
  if (H5Aread(a, H5T_NATIVE_DOUBLE, &v) < 0) fail("attribute '" + name + "' is not a number");
  return v;
}


void refuse_if_read_crashes(const std::string& path, const std::function<void()>& read) {
  std::fflush(nullptr);
  const pid_t child = fork();
  if (child < 0) return;
  if (child == 0) {
    int code = 0;
    try {
      read();
    } catch (...) {
      code = 2;
    }
    _exit(code);
  }
  int status = 0;
  while (waitpid(child, &status, 0) < 0 && errno == EINTR) {
  }
  // 0: read; 2: refused (the caller refuses it again, with the reason).
  if (WIFEXITED(status) && (WEXITSTATUS(status) == 0 || WEXITSTATUS(status) == 2)) return;
  throw InputError(path + ": not a readable HDF5 file: the HDF5 library crashed reading it (" +
                   (WIFSIGNALED(status) ? "signal " + std::to_string(WTERMSIG(status))
                                        : "exit " + std::to_string(WEXITSTATUS(status))) +
                   "); the file is corrupt");
}

}  // namespace floesim::h5
