#pragma once
// Line plots with axes, ticks, labels and a legend, drawn on a Canvas (for
// `floesim plot`), and the tick arithmetic shared with colour legends.

#include <string>
#include <vector>

#include "apps/viz/canvas.hpp"

namespace floesim::viz {

// "Nice" tick positions (1, 2 or 5 times a power of ten apart) covering
// [lo, hi] with about `target` intervals; the first tick is <= lo and the
// last >= hi, so the ticks also give the axis limits.
std::vector<double> nice_ticks(double lo, double hi, int target = 5);
// Labels for evenly spaced ticks, all in one notation with as few digits as
// tell them apart: "0.5", "1.0", ... or, for large or tiny values,
// "5.0e+05", "1.0e+06", ...
std::vector<std::string> tick_labels(const std::vector<double>& ticks);

struct Series {
  std::string name;
  std::vector<double> x, y;  // same length; non-finite values leave a gap
};

struct PlotSpec {
  std::string title, xlabel, ylabel;
  bool legend = true;  // a legend right of the axes when there are several series
};

// Draws the series in `area` (title, axes with ticks, labels, legend). The
// limits are the nice ticks around the finite data; data with no finite value
// draws empty axes on [0, 1].
void line_plot(Canvas& canvas, const Rect& area, const PlotSpec& spec, const std::vector<Series>& series);

}  // namespace floesim::viz
