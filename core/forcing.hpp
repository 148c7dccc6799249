#pragma once
// Wind and ocean current as functions of time: constant, or a time series read
// from CSV with the columns t_s,wind_u,wind_v,current_u,current_v (s, m/s; lines
// starting with '#' and blank lines are skipped; the header line, if any, must be
// exactly those names). Uniform in space.

#include <array>
#include <string>
#include <vector>

#include "core/params.hpp"

namespace floesim {

struct ForcingSample {
  std::array<double, 2> wind{};     // m/s
  std::array<double, 2> current{};  // m/s
};

class ForcingSeries {
public:
  // Constant forcing from [forcing] current and wind.
  explicit ForcingSeries(const ForcingParams& p);
  // Time series; throws InputError naming the file, the line and what was expected
  // for a bad file: a folder, unreadable, a wrong header, a wrong column count, a
  // non-number or non-finite value, times not increasing strictly, no data row.
  static ForcingSeries from_csv(const std::string& path, SeriesInterpolation interpolation);

  // The forcing at time t: linear interpolation between rows, or the value of
  // the last row at or before t ("previous"); clamped to the first/last row.
  ForcingSample at(double t) const;

  std::size_t rows() const { return t_.size(); }

private:
  ForcingSeries() = default;
  std::vector<double> t_;
  std::vector<ForcingSample> v_;
  SeriesInterpolation interpolation_ = SeriesInterpolation::linear;
};

// The forcing of a run: the series if [forcing] series is set, else constant.
ForcingSeries make_forcing(const ForcingParams& p);

}  // namespace floesim
