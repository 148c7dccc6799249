#pragma once
// Private to core: an HDF5 file driver that publishes a file whole at each
// flush, so that a writer killed at any instant (SIGKILL, no clean-up) leaves
// the file as it was at its last flush: readable, with every object whole.
//
// Why: HDF5 (1.10, our Debian's) updates a file in place, and a flush writes
// many pieces of metadata one after another (object headers, B-tree nodes,
// heaps, the superblock last). A writer stopped between two of those writes
// leaves a file whose metadata is half old, half new: a link may name an
// object header not yet written, a group's names may not match its entries.
// Such a file may not open at all. HDF5 offers no journal; SWMR orders its
// flushes for readers, but forbids new objects (our checkpoint groups) and
// leaves flags that plain readers refuse after a crash.
//
// How: two copies of the file, on two inodes. HDF5 writes to the working copy
// PATH.writing; the file named PATH is never written while it bears that name.
// At the end of each flush (HDF5 calls the driver's flush last, after the
// metadata and the superblock are written and the file cut to its end of
// allocation) the driver publishes the working copy by rename(2), which POSIX
// makes atomic: a reader (or a restart) opening PATH finds the previous whole
// file or the new one, never a mixture. It then brings the other copy (kept
// under PATH.previous while it is brought up to date) to the same bytes by
// copying the byte ranges written since the last flush, and makes it the
// working copy. A run killed leaves PATH whole, and possibly the two
// helper names, which the next writer of PATH removes.
//
// Cost: every byte is written twice (once in each copy), and the disk holds
// the file twice while it is written. A writer closing the file removes its
// working copy. Paths that are not regular files (/dev/full, a FIFO) are
// written in place (no copy can be renamed onto them).

#include <hdf5.h>

#include <string>

namespace floesim::h5 {

// A file access property list for a file written through the publishing
// driver, or -1 when `path` must be written in place (not a regular file).
hid_t published_fapl(const std::string& path);
// The names of the helper copies of `path`.
std::string working_path(const std::string& path);
std::string previous_path(const std::string& path);
// True if `file` is written through the publishing driver.
bool is_published(hid_t file);
// What the driver shares with h5::reserve: the working copy's and the other
// copy's POSIX descriptors (fd[1] is -1 before the first publication; a disk
// reservation applies to both, since both grow alike), and the end of
// allocation (H5Fget_eoa answers only for drivers that support SWMR).
struct PublishedHandle {
  int fd[2] = {-1, -1};
  haddr_t eoa = 0;
};
// The handle of a file written through the publishing driver, or nullptr.
const PublishedHandle* published_handle(hid_t file);

}  // namespace floesim::h5
