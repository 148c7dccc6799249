// The publishing file driver (core/detail/h5_published.hpp): HDF5 writes to a
// working copy; each flush publishes it by rename(2) and brings the other copy
// up to date, so that the name PATH always holds a whole file.
#include "core/detail/h5_published.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <memory>
#include <mutex>
#include <utility>
#include <vector>

namespace floesim::h5 {

namespace {

struct Published {
  H5FD_t pub{};  // first: HDF5 sees a pointer to this
  std::string path, work, previous;
  bool writable = false;
  // The driver's handle (H5Fget_vfd_handle) points at `handle`.
  PublishedHandle handle;
  haddr_t eof = 0;
  // Byte ranges [first, second) written to the working copy since the last
  // publication: what the other copy lacks.
  std::vector<std::pair<haddr_t, haddr_t>> written;
  bool dirty = false;
  // A write to the working copy failed (a full disk): HDF5 cannot make that
  // copy whole again, so it is never published; the file under `path` stays
  // the last whole one. (HDF5 still flushes, hence calls publish, at close.)
  bool broken = false;
};

Published* of(H5FD_t* f) { return reinterpret_cast<Published*>(f); }
const Published* of(const H5FD_t* f) { return reinterpret_cast<const Published*>(f); }

constexpr haddr_t kMaxAddr = (haddr_t{1} << (8 * sizeof(off_t) - 1)) - 1;

bool write_all(int fd, const void* data, size_t size, off_t at) {
  const auto* p = static_cast<const unsigned char*>(data);
  while (size > 0) {
    const ssize_t n = pwrite(fd, p, size, at);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    p += n;
    size -= static_cast<size_t>(n);
    at += n;
  }
  return true;
}

// Copies bytes [from, to) of `src` to the same place in `dst`.
bool copy_range(int src, int dst, off_t from, off_t to) {
  std::vector<unsigned char> buf(std::size_t{1} << 20);
  while (from < to) {
    const auto want = static_cast<size_t>(std::min<off_t>(to - from, static_cast<off_t>(buf.size())));
    const ssize_t n = pread(src, buf.data(), want, from);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    if (!write_all(dst, buf.data(), static_cast<size_t>(n), from)) return false;
    from += n;
  }
  return true;
}

off_t size_of(int fd) {
  struct stat st {};
  return fstat(fd, &st) == 0 ? st.st_size : -1;
}

// Publishes the working copy (the file as HDF5's flush left it) under `path`,
// then makes the other copy equal to it and the working copy.
//   1. link(path, previous): the published inode gets a second name, so that
//      the rename below does not delete it;
//   2. rename(work, path): the atomic step; a kill before it leaves the old
//      file under `path`, after it the new one;
//   3. the ranges written since the last publication copied into the old
//      inode, cut to the same size: now equal to the published one;
//   4. rename(previous, work): it is the working copy.
// Before the first publication there is no other copy: the new one is a
// whole copy of the file.
bool publish(Published& f) {
  const off_t size = size_of(f.handle.fd[0]);
  if (size < 0) return false;
  if (f.handle.fd[1] < 0) {
    if (std::rename(f.work.c_str(), f.path.c_str()) != 0) return false;
    f.handle.fd[1] = open(f.previous.c_str(), O_RDWR | O_CREAT | O_TRUNC | O_CLOEXEC, 0666);
    if (f.handle.fd[1] < 0) return false;
    f.written.assign(1, {0, static_cast<haddr_t>(size)});
  } else {
    unlink(f.previous.c_str());
    if (link(f.path.c_str(), f.previous.c_str()) != 0) {
      // A file system without hard links (EPERM, EOPNOTSUPP, ...): the
      // published inode is renamed away first. A kill between the two
      // renames leaves no file under `path`, but the two whole copies under
      // the helper names (docs/formats.md).
      if (errno == EEXIST || std::rename(f.path.c_str(), f.previous.c_str()) != 0) return false;
    }
    if (std::rename(f.work.c_str(), f.path.c_str()) != 0) return false;
  }
  std::sort(f.written.begin(), f.written.end());
  haddr_t done = 0;  // ranges overlap often (a chunk rewritten at each record): copy each byte once
  for (auto [a, b] : f.written) {
    a = std::max(a, done);
    b = std::min<haddr_t>(b, static_cast<haddr_t>(size));
    if (a < b && !copy_range(f.handle.fd[0], f.handle.fd[1], static_cast<off_t>(a), static_cast<off_t>(b))) return false;
    done = std::max(done, b);
  }
  if (ftruncate(f.handle.fd[1], size) != 0) return false;
  if (std::rename(f.previous.c_str(), f.work.c_str()) != 0) return false;
  std::swap(f.handle.fd[0], f.handle.fd[1]);
  f.written.clear();
  f.dirty = false;
  return true;
}

void remove_helpers(const Published& f) {
  unlink(f.work.c_str());
  unlink(f.previous.c_str());
}

// The working copy of a file opened to be continued, made at the first
// write: a whole copy of the published file.
bool ensure_work(Published& f) {
  if (f.handle.fd[0] >= 0) return true;
  unlink(f.previous.c_str());
  f.handle.fd[0] = open(f.work.c_str(), O_RDWR | O_CREAT | O_TRUNC | O_CLOEXEC, 0666);
  const off_t size = f.handle.fd[0] >= 0 ? size_of(f.handle.fd[1]) : -1;
  return size >= 0 && copy_range(f.handle.fd[1], f.handle.fd[0], 0, size);
}

H5FD_t* open_published(const char* name, unsigned flags, hid_t, haddr_t maxaddr) {
  if (!name || !*name || maxaddr == 0 || maxaddr == HADDR_UNDEF || maxaddr > kMaxAddr) return nullptr;
  auto f = std::make_unique<Published>();
  f->path = name;
  f->work = working_path(name);
  f->previous = previous_path(name);
  f->writable = (flags & H5F_ACC_RDWR) != 0;
  if (!f->writable) {
    f->handle.fd[0] = open(name, O_RDONLY | O_CLOEXEC);
  } else if (flags & H5F_ACC_CREAT) {
    // A new file: what an earlier run left under these names goes (the file
    // is published at the first flush; a run killed before has no file).
    if ((flags & H5F_ACC_EXCL) && access(name, F_OK) == 0) return nullptr;
    f->handle.fd[0] = open(f->work.c_str(), O_RDWR | O_CREAT | O_TRUNC | O_CLOEXEC, 0666);
    if (f->handle.fd[0] >= 0) {
      unlink(name);
      unlink(f->previous.c_str());
    }
  } else {
    // An existing file continued (a restart in place): it stays published
    // as it is; the working copy is made, a whole copy of it, at the first
    // write (HDF5 also opens a file so to see whether it exists, before
    // creating it anew: that open copies nothing).
    f->handle.fd[1] = open(name, O_RDWR | O_CLOEXEC);
    if (f->handle.fd[1] < 0) return nullptr;
    const off_t size = size_of(f->handle.fd[1]);
    f->eof = size > 0 ? static_cast<haddr_t>(size) : 0;
    return &f.release()->pub;
  }
  if (f->handle.fd[0] < 0) {
    const int err = errno;
    if (f->handle.fd[1] >= 0) close(f->handle.fd[1]);
    errno = err;
    return nullptr;
  }
  const off_t size = size_of(f->handle.fd[0]);
  f->eof = size > 0 ? static_cast<haddr_t>(size) : 0;
  return &f.release()->pub;
}

herr_t close_published(H5FD_t* file) {
  Published* f = of(file);
  // HDF5 flushed (and so published) the file before closing it; the working
  // copy, equal to it, goes. After a failed publication it may be torn: it
  // goes too, the published file being the last whole one.
  if (f->handle.fd[0] >= 0) close(f->handle.fd[0]);
  if (f->handle.fd[1] >= 0) close(f->handle.fd[1]);
  if (f->writable) remove_helpers(*f);
  delete f;
  return 0;
}

int cmp_published(const H5FD_t* a, const H5FD_t* b) { return of(a)->path.compare(of(b)->path); }

herr_t query_published(const H5FD_t*, unsigned long* flags) {
  // As the sec2 driver: HDF5 may aggregate metadata and small raw data, and
  // sieve. Not H5FD_FEAT_POSIX_COMPAT_HANDLE: HDF5 would then stat(2) the
  // file's name on creation, which exists only from the first publication.
  if (flags)
    *flags = H5FD_FEAT_AGGREGATE_METADATA | H5FD_FEAT_ACCUMULATE_METADATA | H5FD_FEAT_DATA_SIEVE |
             H5FD_FEAT_AGGREGATE_SMALLDATA | H5FD_FEAT_DEFAULT_VFD_COMPATIBLE;
  return 0;
}

haddr_t get_eoa_published(const H5FD_t* file, H5FD_mem_t) { return of(file)->handle.eoa; }
herr_t set_eoa_published(H5FD_t* file, H5FD_mem_t, haddr_t addr) {
  if (addr > kMaxAddr) return -1;
  of(file)->handle.eoa = addr;
  return 0;
}
haddr_t get_eof_published(const H5FD_t* file, H5FD_mem_t) { return of(file)->eof; }

herr_t get_handle_published(H5FD_t* file, hid_t, void** handle) {
  if (!handle || (of(file)->writable && !ensure_work(*of(file)))) return -1;
  *handle = &of(file)->handle;
  return 0;
}

herr_t read_published(H5FD_t* file, H5FD_mem_t, hid_t, haddr_t addr, size_t size, void* buffer) {
  Published* f = of(file);
  auto* p = static_cast<unsigned char*>(buffer);
  if (addr > kMaxAddr || size > kMaxAddr - addr) return -1;
  auto at = static_cast<off_t>(addr);
  while (size > 0) {
    const ssize_t n = pread(f->handle.fd[0] >= 0 ? f->handle.fd[0] : f->handle.fd[1], p, size, at);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) return -1;
    if (n == 0) {  // past the end of the file: zeros, as the sec2 driver reads
      std::memset(p, 0, size);
      break;
    }
    p += n;
    size -= static_cast<size_t>(n);
    at += n;
  }
  return 0;
}

herr_t write_published(H5FD_t* file, H5FD_mem_t, hid_t, haddr_t addr, size_t size, const void* buffer) {
  Published* f = of(file);
  if (!f->writable || addr > kMaxAddr || size > kMaxAddr - addr) return -1;
  if (!ensure_work(*f) || !write_all(f->handle.fd[0], buffer, size, static_cast<off_t>(addr))) {
    f->broken = true;
    return -1;
  }
  if (!f->written.empty() && f->written.back().second == addr) f->written.back().second = addr + size;
  else f->written.emplace_back(addr, addr + size);
  f->eof = std::max(f->eof, addr + size);
  f->dirty = true;
  return 0;
}

herr_t truncate_published(H5FD_t* file, hid_t, hbool_t) {
  Published* f = of(file);
  if (!f->writable || (f->handle.fd[0] < 0 && f->eof == f->handle.eoa)) return 0;  // nothing written yet
  if (!ensure_work(*f)) {
    f->broken = true;
    return -1;
  }
  // The file is cut (or extended) to its end of allocation, as by the sec2
  // driver; a disk reservation past it (h5::reserve) is cut here too.
  const off_t size = size_of(f->handle.fd[0]);
  if (size < 0) return -1;
  if (static_cast<haddr_t>(size) != f->handle.eoa) {
    if (ftruncate(f->handle.fd[0], static_cast<off_t>(f->handle.eoa)) != 0) {
      f->broken = true;
      return -1;
    }
    f->dirty = true;
  }
  f->eof = f->handle.eoa;
  return 0;
}

herr_t flush_published(H5FD_t* file, hid_t, hbool_t) {
  Published* f = of(file);
  // HDF5 calls this last in a flush: the working copy is a whole file.
  if (f->broken) return -1;
  if (!f->writable || !f->dirty) return 0;
  // A publication that fails midway leaves `path` whole (the previous or
  // the new file) but the copies unequal: nothing more is published.
  if (!publish(*f)) f->broken = true;
  return f->broken ? -1 : 0;
}

hid_t driver_id() {
  static hid_t id = -1;
  static std::once_flag once;
  std::call_once(once, [] {
    static H5FD_class_t cls{};
    cls.name = "floesim_published";
    cls.maxaddr = kMaxAddr;
    cls.fc_degree = H5F_CLOSE_WEAK;
    cls.open = open_published;
    cls.close = close_published;
    cls.cmp = cmp_published;
    cls.query = query_published;
    cls.get_eoa = get_eoa_published;
    cls.set_eoa = set_eoa_published;
    cls.get_eof = get_eof_published;
    cls.get_handle = get_handle_published;
    cls.read = read_published;
    cls.write = write_published;
    cls.flush = flush_published;
    cls.truncate = truncate_published;
    const H5FD_mem_t map[] = H5FD_FLMAP_DICHOTOMY;
    std::copy(std::begin(map), std::end(map), cls.fl_map);
    id = H5FDregister(&cls);
  });
  return id;
}

}  // namespace

std::string working_path(const std::string& path) { return path + ".writing"; }
std::string previous_path(const std::string& path) { return path + ".previous"; }

hid_t published_fapl(const std::string& path) {
  struct stat st {};
  if (lstat(path.c_str(), &st) == 0 && !S_ISREG(st.st_mode)) return -1;  // a device, a FIFO, a link: in place
  const hid_t id = driver_id();
  if (id < 0) return -1;
  const hid_t fapl = H5Pcreate(H5P_FILE_ACCESS);
  if (fapl < 0) return -1;
  if (H5Pset_driver(fapl, id, nullptr) < 0) {
    H5Pclose(fapl);
    return -1;
  }
  return fapl;
}

bool is_published(hid_t file) {
  const hid_t fapl = H5Fget_access_plist(file);
  if (fapl < 0) return false;
  const bool yes = H5Pget_driver(fapl) == driver_id();
  H5Pclose(fapl);
  return yes;
}

const PublishedHandle* published_handle(hid_t file) {
  if (!is_published(file)) return nullptr;
  const hid_t fapl = H5Fget_access_plist(file);
  void* handle = nullptr;
  const herr_t got = H5Fget_vfd_handle(file, fapl, &handle);
  H5Pclose(fapl);
  return got < 0 ? nullptr : static_cast<const PublishedHandle*>(handle);
}

}  // namespace floesim::h5
