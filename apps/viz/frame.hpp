#pragma once
// One picture of a run at one record (for `floesim render`): the floes as
// polygons coloured by speed or heave over the sea elevation as a colour map,
// with a time stamp, a scale bar and a colour legend for each field.

#include <string>
#include <vector>

#include "apps/viz/canvas.hpp"
#include "apps/viz/colormap.hpp"
#include "apps/viz/run_view.hpp"

namespace floesim::viz {

enum class FloeField { speed, heave };
FloeField floe_field(const std::string& name);  // "speed" or "heave"; InputError otherwise
const char* field_name(FloeField f);

// The world window (m) and the colour ranges shared by every frame of a
// picture or a video, so that frames of a video compare.
struct FrameScales {
  double xmin = 0, xmax = 1, ymin = 0, ymax = 1;
  Range floe;  // of the floe field
  Range sea;   // of the sea elevation
};
// Scales covering the given records: the sea grid and every floe that exists
// at one of them (its centroid +- its radius); colour ranges over their values.
FrameScales frame_scales(const RunView& run, const std::vector<std::size_t>& records, FloeField field);

// Where the world went on the picture: pixel = (left + s (x - xmin), bottom - s (y - ymin)).
struct FrameLayout {
  Rect map;            // the pixels of the world window
  double s = 1.0;      // pixels per metre
  double xmin = 0, ymin = 0;
  Point to_pixel(double x, double y) const { return {map.x + s * (x - xmin), map.y + map.h - s * (y - ymin)}; }
};

// Computes where the map goes on a canvas of this size (no drawing).
FrameLayout frame_layout(int width, int height, const FrameScales& scales);

// Draws record `record` of the run onto the canvas (which it covers).
FrameLayout draw_frame(Canvas& canvas, const RunView& run, std::size_t record, FloeField field,
                       const FrameScales& scales);

}  // namespace floesim::viz
