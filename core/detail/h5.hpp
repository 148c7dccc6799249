#pragma once
// Private to core: a thin RAII layer over the HDF5 C API. A failure to read
// becomes an InputError naming the file and the object; a failure to create or
// write a file (a folder that is not writable, a full disk) a RunError. HDF5's
// own error stack printing is switched off so that users see one clear message.

#include <hdf5.h>

#include <functional>
#include <string>
#include <vector>

namespace floesim::h5 {

// Owns one hid_t and closes it with the right H5*close.
class Handle {
public:
  Handle() = default;
  Handle(hid_t id, herr_t (*close)(hid_t)) : id_(id), close_(close) {}
  Handle(const Handle&) = delete;
  Handle& operator=(const Handle&) = delete;
  Handle(Handle&& o) noexcept : id_(o.id_), close_(o.close_) { o.id_ = -1; }
  Handle& operator=(Handle&& o) noexcept {
    if (this != &o) { reset(); id_ = o.id_; close_ = o.close_; o.id_ = -1; }
    return *this;
  }
  ~Handle() { reset(); }
  void reset() { if (id_ >= 0 && close_) close_(id_); id_ = -1; }
  hid_t get() const { return id_; }
  operator hid_t() const { return id_; }
  bool valid() const { return id_ >= 0; }

private:
  hid_t id_ = -1;
  herr_t (*close_)(hid_t) = nullptr;
};

void silence_errors();  // once per process: no HDF5 error-stack dumps on stderr

bool is_hdf5(const std::string& path);
// How a file opened to write, or created, is written.
//   published: through the publishing driver (h5_published.hpp): `path`
//     holds the file as of its last flush, whole, whatever instant the
//     process is killed at; the disk holds it twice while it is written.
//   in_place: on the sec2 (POSIX) driver, as HDF5 writes by itself: half the
//     disk and the writes, but a process killed in a flush may leave a file
//     that no longer opens. Helper copies an earlier published writer of
//     `path` left (killed) are removed: they are copies of an older file.
// A path that is not a regular file is written in place either way.
enum class Writing { published, in_place };
// A file opened to write, and a file created (an earlier one of that name is
// removed), are written as `how` says.
Handle open_file(const std::string& path, bool write = false, Writing how = Writing::published);
Handle create_file(const std::string& path, Writing how = Writing::published);
// Writes every cached object of the file to disk (and publishes it); false
// when a write failed.
bool flush(hid_t file);
// Disk space for the writes to come. HDF5 writes a file in place and keeps its
// structure consistent only when every write lands: a write that fails for
// want of space (ENOSPC) or past the file-size limit (EFBIG) in the middle of a
// flush leaves a file that no longer opens. reserve() allocates `bytes` past the
// file's end of allocation (posix_fallocate, which extends the file) before
// they are needed, so that the writes which follow, up to that many bytes, cannot
// fail for want of space. Returns 0 or the errno of the refusal (ENOSPC,
// EFBIG, ...); a file system that cannot preallocate (EOPNOTSUPP, a device
// such as /dev/full) reserves nothing and returns 0: the writes then report
// their own failure. HDF5 trims the file back to its end of allocation at each
// flush, so a reservation holds until the next flush.
int reserve(hid_t file, hsize_t bytes);
// Cuts the file to its end of allocation (what a reservation added past it).
void trim(hid_t file);
// Refuses (InputError) a file holding a global heap collection (where HDF5
// keeps variable-length strings, such as our "format" attributes) that
// HDF5 1.10 would mishandle: an object of index 0 and size 0 makes its reader
// loop forever, an object larger than its collection makes it copy past the
// heap's memory (byte-flipped packs, tests/data/fuzz/pack). Reads the whole
// file once; for the files a user hands us (packs).
void check_global_heaps(const std::string& path);
// HDF5 1.10 trusts a file's metadata, and a few corrupt files crash it (a
// signal) before any check of ours can run (docs/reliability.md). `read` is
// run first in a child process (fork): a child that ends by a signal, or by
// a sanitizer's report, means the library cannot read `path`, which is then
// refused (InputError); a child that read it or threw lets the caller read it
// (the same read: deterministic). Where fork fails, nothing is tried.
void refuse_if_read_crashes(const std::string& path, const std::function<void()>& read);
bool exists(hid_t loc, const std::string& path);  // a link path like "/floes/state"
Handle open_dataset(hid_t loc, const std::string& path, const std::string& file);
Handle open_group(hid_t loc, const std::string& path, const std::string& file);
Handle create_group(hid_t loc, const std::string& path);

std::vector<hsize_t> dims(hid_t dataset);

// The most numbers one dataset may hold when read whole: 2^28 (2 GiB as
// doubles; a million floes of a hundred vertices is 2e8 numbers). A file's
// dataspace is only a claim (a corrupted or hostile file may claim 4e9
// entries), so every read checks it before allocating: the element count
// against this bound and, for contiguous or compact layouts, against the bytes
// the file really stores for the dataset. Failures are InputErrors that start
// with `what` (the file and the dataset).
inline constexpr std::size_t kMaxElements = std::size_t{1} << 28;

// Whole datasets. read_doubles takes integers or floats; read_ints takes
// integers only (a float-typed index array is refused, not truncated).
std::vector<double> read_doubles(hid_t dataset, const std::string& what);
std::vector<long long> read_ints(hid_t dataset, const std::string& what);
// The first entry along dimension 0 (one record of a [T, ...] dataset), read
// without allocating the other T - 1; the dataset must have rank >= 1 and T >= 1.
std::vector<double> read_first_record(hid_t dataset, const std::string& what);

// Whole fixed-size datasets.
void write_doubles(hid_t loc, const std::string& name, const std::vector<hsize_t>& dims,
                   const double* data);
void write_ints(hid_t loc, const std::string& name, const std::vector<hsize_t>& dims,
                const long long* data);
void write_bytes(hid_t loc, const std::string& name, const std::vector<hsize_t>& dims,
                 const unsigned char* data);

// Extendible datasets along the first dimension (chunked): created with 0
// rows, each append adds one row of the given row shape. rows_hint, when not
// 0, is the number of rows expected: chunks hold no more rows than that, so a
// short run does not carry a mostly empty 64 KiB chunk per dataset.
Handle create_extendible(hid_t loc, const std::string& name, const std::vector<hsize_t>& row,
                         hsize_t rows_hint = 0);
void append_row(hid_t dataset, const double* row);
// Like create_extendible, but every dimension may grow (set_extent), and
// elements never written read as NaN (the fill value).
Handle create_growable(hid_t loc, const std::string& name, const std::vector<hsize_t>& row,
                       hsize_t rows_hint = 0);
void set_extent(hid_t dataset, const std::vector<hsize_t>& dims);
// Bytes the file may grow by when one row is appended to a chunked dataset:
// a new chunk along the first dimension across its whole current extent.
hsize_t append_bytes(hid_t dataset);
// Deletes a link (a dataset written whole, before writing it again).
void remove(hid_t loc, const std::string& name);

// Attributes (on a file, group or dataset).
void set_attr(hid_t obj, const std::string& name, const std::string& value);
void set_attr(hid_t obj, const std::string& name, double value);
void set_attr(hid_t obj, const std::string& name, long long value);
void set_attr(hid_t obj, const std::string& name, const std::vector<std::string>& values);
bool has_attr(hid_t obj, const std::string& name);
std::string get_attr_string(hid_t obj, const std::string& name);
double get_attr_double(hid_t obj, const std::string& name);
std::vector<std::string> get_attr_strings(hid_t obj, const std::string& name);

}  // namespace floesim::h5
