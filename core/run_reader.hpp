#pragma once
// Reading a run file (format "floesim-1", docs/formats.md) dataset by
// dataset, for the commands that look at runs (render, plot) and for scripts
// bindings. Whole datasets or slabs of rows along the first dimension (one
// record of /floes/state or /sea/eta), so that a frame of a long run is read
// without loading the run. Every failure is an InputError naming the file and
// the dataset.

#include <cstddef>
#include <memory>
#include <string>
#include <vector>

namespace floesim {

class RunReader {
public:
  // Opens the file read-only; InputError if it is missing, not HDF5, or its
  // root attribute `format` is not "floesim-1".
  explicit RunReader(const std::string& path);
  ~RunReader();
  RunReader(RunReader&&) noexcept;
  RunReader& operator=(RunReader&&) noexcept;

  const std::string& path() const;
  bool has(const std::string& dataset) const;                    // e.g. "/sea/eta"
  std::vector<std::size_t> shape(const std::string& dataset) const;

  // The whole dataset, converted to double (integers too), row-major.
  std::vector<double> read(const std::string& dataset) const;
  // Rows [first, first + count) along the first dimension, row-major.
  std::vector<double> read_rows(const std::string& dataset, std::size_t first, std::size_t count) const;
  // Every row, but only columns [first_col, first_col + cols) of the last
  // dimension (e.g. x and y of /floes/state over all records).
  std::vector<double> read_columns(const std::string& dataset, std::size_t first_col, std::size_t cols) const;

  // A string-list attribute of a dataset (e.g. `columns`); empty if absent.
  std::vector<std::string> strings(const std::string& dataset, const std::string& attribute) const;
  // A string attribute of the file root (e.g. `status`); empty if absent.
  std::string root_string(const std::string& attribute) const;

private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace floesim
