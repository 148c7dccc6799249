#pragma once
// Colour maps of floesim's pictures (docs/render.md lists their anchor
// colours): a value is normalised on a range, then interpolated linearly in
// RGB between evenly spaced anchors.

#include <string>
#include <vector>

#include "apps/viz/canvas.hpp"

namespace floesim::viz {

// A closed value range [lo, hi] with lo < hi.
struct Range {
  double lo = 0.0, hi = 1.0;
  double normalise(double v) const { return (v - lo) / (hi - lo); }  // 0 at lo, 1 at hi
};
// [0, max v] (max 0: [0, 1]) and [-max |v|, max |v|] (max 0: [-1, 1]),
// ignoring non-finite values.
Range positive_range(const std::vector<double>& values);
Range symmetric_range(const std::vector<double>& values);

class ColorMap {
public:
  ColorMap(std::string name, std::vector<Rgb> anchors);
  // t in [0, 1] (clamped); a non-finite t gives mid grey.
  Rgb operator()(double t) const;
  const std::string& name() const { return name_; }
  const std::vector<Rgb>& anchors() const { return anchors_; }

private:
  std::string name_;
  std::vector<Rgb> anchors_;
};

const ColorMap& sea_map();    // sea elevation: trough dark blue, crest near white
const ColorMap& speed_map();  // floe speed: slow pale yellow to fast dark red
const ColorMap& heave_map();  // floe heave: down green, level light grey, up purple

// Ten distinct line colours for plots; index taken modulo 10.
Rgb line_colour(std::size_t index);

inline constexpr Rgb kStaticFloe{0.55, 0.55, 0.55};  // obstacles, whatever the field
inline constexpr Rgb kOutline{0.08, 0.08, 0.08};
inline constexpr Rgb kInk{0.1, 0.1, 0.1};            // text, axes

}  // namespace floesim::viz
