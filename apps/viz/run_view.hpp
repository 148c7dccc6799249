#pragma once
// What the pictures need from a run file (docs/formats.md): the floe outlines
// in the body frame, the record times, the sea grid, and, one record at a
// time, the floe states and the sea elevation. Shapes are checked on opening
// so that drawing code can index freely; a mismatch is an InputError naming
// the file and the dataset.

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "core/run_reader.hpp"

namespace floesim::viz {

inline constexpr int kStateWidth = 12;  // columns of /floes/state
enum StateColumn : int { kX = 0, kY = 1, kYaw = 2, kVx = 3, kVy = 4, kHeave = 6 };

struct SeaGrid {
  int dims = 0;               // 0: the run has no sea; 1: eta [T, nx]; 2: eta [T, ny, nx]
  std::vector<double> x, y;   // m, cell centres (y has one entry for dims 1)
  // World extent of the cells (centres +- half a cell; a single cell spans
  // [0, 2 centre]).
  double xmin() const, xmax() const, ymin() const, ymax() const;
};

class RunView {
public:
  explicit RunView(const std::string& path);

  const std::string& path() const { return reader_.path(); }
  const RunReader& reader() const { return reader_; }
  std::size_t records() const { return times_.size(); }
  const std::vector<double>& times() const { return times_; }
  std::size_t floes() const { return is_static_.size(); }
  std::size_t vertex_begin(std::size_t floe) const { return offsets_[floe]; }
  std::size_t vertex_end(std::size_t floe) const { return offsets_[floe + 1]; }
  double body_x(std::size_t vertex) const { return body_[2 * vertex]; }
  double body_y(std::size_t vertex) const { return body_[2 * vertex + 1]; }
  bool is_static(std::size_t floe) const { return is_static_[floe] != 0; }
  double radius(std::size_t floe) const { return radius_[floe]; }  // m, farthest vertex from the centroid
  const SeaGrid& sea() const { return sea_; }

  // The record nearest to time t; InputError naming the file if t lies
  // outside [first time, last time] (by more than a millionth of the span).
  std::size_t record_at(double t) const;

  std::vector<double> state(std::size_t record) const;  // [n * 12]
  std::vector<double> eta(std::size_t record) const;    // [ny * nx], y slowest; empty without a sea
  // Columns [first, first + count) of every floe's state at every record:
  // [T * n * count].
  std::vector<double> state_columns(int first, int count) const;
  std::vector<double> all_eta() const;  // [T * ny * nx]

private:
  RunReader reader_;
  std::vector<double> times_;
  std::vector<std::size_t> offsets_;
  std::vector<double> body_;
  std::vector<std::uint8_t> is_static_;
  std::vector<double> radius_;
  SeaGrid sea_;
};

}  // namespace floesim::viz
