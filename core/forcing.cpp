#include "core/forcing.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <fstream>

#include "core/error.hpp"

namespace floesim {

ForcingSeries::ForcingSeries(const ForcingParams& p) {
  t_ = {0.0};
  v_ = {ForcingSample{p.wind, p.current}};
}

namespace {
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
}  // namespace

ForcingSeries ForcingSeries::from_csv(const std::string& path, SeriesInterpolation interpolation) {
  std::ifstream in(path);
  if (!in) throw InputError(path + ": cannot open the forcing series");
  ForcingSeries s;
  s.interpolation_ = interpolation;
  std::string line;
  long lineno = 0;
  bool header_seen = false;
  auto bad = [&](const std::string& what) { throw InputError(where(path, lineno, "", what)); };
  while (std::getline(in, line)) {
    ++lineno;
    if (line.empty() || line.find_first_not_of(" \t\r") == std::string::npos || line[0] == '#') continue;
    const auto fields = split_csv(line);
    if (!header_seen) {
      header_seen = true;
      if (!fields.empty() && fields[0] == "t_s") {
        if (fields.size() != 5 || fields[1] != "wind_u" || fields[2] != "wind_v" ||
            fields[3] != "current_u" || fields[4] != "current_v")
          bad("expected the header t_s,wind_u,wind_v,current_u,current_v");
        continue;
      }
    }
    if (fields.size() != 5) bad("expected 5 columns (t_s,wind_u,wind_v,current_u,current_v), got " +
                                std::to_string(fields.size()));
    double v[5];
    for (int k = 0; k < 5; ++k) {
      const std::string& f = fields[static_cast<std::size_t>(k)];
      auto [p, ec] = std::from_chars(f.data(), f.data() + f.size(), v[k]);
      if (ec != std::errc{} || p != f.data() + f.size()) bad("column " + std::to_string(k + 1) + " is not a number: '" + f + "'");
      if (!std::isfinite(v[k])) bad("column " + std::to_string(k + 1) + " is not finite");
    }
    if (!s.t_.empty() && !(v[0] > s.t_.back())) bad("times must increase strictly");
    s.t_.push_back(v[0]);
    s.v_.push_back(ForcingSample{{v[1], v[2]}, {v[3], v[4]}});
  }
  if (s.t_.empty()) throw InputError(path + ": the forcing series has no data row");
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
