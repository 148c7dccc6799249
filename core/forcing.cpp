#include "core/forcing.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>

#include "core/error.hpp"

namespace floesim {

ForcingSeries::ForcingSeries(const ForcingParams& p) {
  t_ = {0.0};
  v_ = {ForcingSample{p.wind, p.current}};
}

namespace {

constexpr const char* kHeader = "t_s,wind_u,wind_v,current_u,current_v";
constexpr const char* kColumns[5] = {"t_s", "wind_u", "wind_v", "current_u", "current_v"};

std::vector<std::string> split_csv(const std::string& line) {
  std::vector<std::string> out;
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = line.find(',', start);
    std::string f = line.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
    const auto b = f.find_first_not_of(" \t\r"), e = f.find_last_not_of(" \t\r");
    out.push_back(b == std::string::npos ? std::string{} : f.substr(b, e - b + 1));
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  return out;
}

// A field as it can be shown in a message: binary bytes as '?', at most 40 characters.
std::string shown(const std::string& f) {
  std::string s;
  for (char c : f.substr(0, 40)) s += (c >= 0x20 && c < 0x7f) ? c : '?';
  return "'" + s + (f.size() > 40 ? "...'" : "'");
}

bool is_number(const std::string& f, double& v) {
  const auto [p, ec] = std::from_chars(f.data(), f.data() + f.size(), v);
  return ec == std::errc{} && p == f.data() + f.size() && !f.empty();
}

}  // namespace

// Every rule of the series file is here. The configuration loader calls this to
// check [forcing] series at load (core/config.cpp); make_forcing reads it again.
ForcingSeries ForcingSeries::from_csv(const std::string& path, SeriesInterpolation interpolation) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec))
    throw InputError(path + ": the forcing series is a folder; expected a CSV file (" + std::string(kHeader) + ")");
  // A device or a pipe is refused: /dev/zero would be read as one endless line,
  // and the series is read twice (checked at load, then by make_forcing).
  if (std::filesystem::exists(path, ec) && !std::filesystem::is_regular_file(path, ec))
    throw InputError(path + ": the forcing series is not a regular file (a device or a pipe?); expected a CSV file (" +
                     std::string(kHeader) + ")");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path + ": cannot open the forcing series");
  ForcingSeries s;
  s.interpolation_ = interpolation;
  std::string line;
  long lineno = 0;
  bool first = true;  // the first line that is not blank or a comment: the header, if it is not numeric
  std::string last_t;  // the previous row's time as written, and its line
  long last_line = 0;
  auto bad = [&](const std::string& what) { throw InputError(where(path, lineno, "", what)); };
  while (std::getline(in, line)) {
    ++lineno;
    if (line.find_first_not_of(" \t\r") == std::string::npos || line[0] == '#') continue;
    const auto fields = split_csv(line);
    double v[5];
    if (first) {
      first = false;
      // A header is a line whose first field is not a number; it must be exactly ours,
      // so that a file with other columns (or other units) is not read by position.
      if (!is_number(fields[0], v[0])) {
        std::string got;
        for (const std::string& f : fields) got += (got.empty() ? "" : ",") + f;
        if (!std::equal(fields.begin(), fields.end(), std::begin(kColumns), std::end(kColumns)))
          bad("expected the header " + std::string(kHeader) + ", got " + shown(got));
        continue;
      }
    }
    if (fields.size() != 5)
      bad("expected 5 columns (" + std::string(kHeader) + "), got " + std::to_string(fields.size()));
    for (std::size_t k = 0; k < 5; ++k) {
      const std::string& f = fields[k];
      const std::string column = "column " + std::to_string(k + 1) + " (" + kColumns[k] + ")";
      if (!is_number(f, v[k])) bad(column + ": expected a number, got " + shown(f));
      if (!std::isfinite(v[k])) bad(column + ": expected a finite number, got " + shown(f));
    }
    if (!s.t_.empty() && !(v[0] > s.t_.back()))
      bad("expected times increasing strictly, got t_s = " + fields[0] + " after " + last_t + " (line " +
          std::to_string(last_line) + ")");
    last_t = fields[0];
    last_line = lineno;
    s.t_.push_back(v[0]);
    s.v_.push_back(ForcingSample{{v[1], v[2]}, {v[3], v[4]}});
  }
  if (in.bad()) throw InputError(path + ": cannot read the forcing series");
  if (s.t_.empty())
    throw InputError(path + ": the forcing series has no data row (expected the header " + std::string(kHeader) +
                     " then one row per time)");
  return s;
}

ForcingSample ForcingSeries::at(double t) const {
  if (t <= t_.front()) return v_.front();
  if (t >= t_.back()) return v_.back();
  const auto it = std::upper_bound(t_.begin(), t_.end(), t);  // first row after t
  const std::size_t j = static_cast<std::size_t>(it - t_.begin()), i = j - 1;
  if (interpolation_ == SeriesInterpolation::previous) return v_[i];
  const double a = (t - t_[i]) / (t_[j] - t_[i]);
  ForcingSample r;
  for (int k = 0; k < 2; ++k) {
    r.wind[k] = (1 - a) * v_[i].wind[k] + a * v_[j].wind[k];
    r.current[k] = (1 - a) * v_[i].current[k] + a * v_[j].current[k];
  }
  return r;
}

ForcingSeries make_forcing(const ForcingParams& p) {
  if (p.series.empty()) return ForcingSeries(p);
  return ForcingSeries::from_csv(p.series, p.series_interpolation);
}

}  // namespace floesim
