#include "apps/viz/colormap.hpp"

#include <algorithm>
#include <cmath>

#include "core/error.hpp"

namespace floesim::viz {

Range positive_range(const std::vector<double>& values) {
  double hi = 0.0;
  for (double v : values)
    if (std::isfinite(v)) hi = std::max(hi, v);
  return {0.0, hi > 0.0 ? hi : 1.0};
}

Range symmetric_range(const std::vector<double>& values) {
  double m = 0.0;
  for (double v : values)
    if (std::isfinite(v)) m = std::max(m, std::abs(v));
  if (!(m > 0.0)) m = 1.0;
  return {-m, m};
}

ColorMap::ColorMap(std::string name, std::vector<Rgb> anchors) : name_(std::move(name)), anchors_(std::move(anchors)) {
  FLOESIM_ASSERT(anchors_.size() >= 2);
}

Rgb ColorMap::operator()(double t) const {
  if (!std::isfinite(t)) return {0.5, 0.5, 0.5};
  const double s = std::clamp(t, 0.0, 1.0) * static_cast<double>(anchors_.size() - 1);
  const std::size_t k = std::min(static_cast<std::size_t>(s), anchors_.size() - 2);
  const double f = s - static_cast<double>(k);
  const Rgb& a = anchors_[k];
  const Rgb& b = anchors_[k + 1];
  return {a.r + f * (b.r - a.r), a.g + f * (b.g - a.g), a.b + f * (b.b - a.b)};
}

// Anchors chosen for this project: lightness runs one way along the sea map
// (so crests and troughs read without the legend), and the floe maps use hues
// that the sea map does not, so that floes stand out on any sea.
const ColorMap& sea_map() {
  static const ColorMap m("sea", {{0.03, 0.15, 0.36}, {0.13, 0.38, 0.64}, {0.42, 0.66, 0.84}, {0.88, 0.95, 0.98}});
  return m;
}
const ColorMap& speed_map() {
  static const ColorMap m("speed", {{1.00, 0.96, 0.70}, {0.99, 0.70, 0.30}, {0.89, 0.30, 0.13}, {0.55, 0.03, 0.12}});
  return m;
}
const ColorMap& heave_map() {
  static const ColorMap m("heave", {{0.05, 0.45, 0.25}, {0.94, 0.94, 0.94}, {0.50, 0.12, 0.55}});
  return m;
}

Rgb line_colour(std::size_t index) {
  static const Rgb palette[10] = {{0.12, 0.47, 0.71}, {0.90, 0.45, 0.05}, {0.17, 0.60, 0.17}, {0.80, 0.15, 0.15},
                                  {0.50, 0.35, 0.72}, {0.55, 0.34, 0.29}, {0.88, 0.40, 0.70}, {0.40, 0.40, 0.40},
                                  {0.65, 0.65, 0.10}, {0.08, 0.70, 0.78}};
  return palette[index % 10];
}

}  // namespace floesim::viz
