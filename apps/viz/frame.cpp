#include "apps/viz/frame.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>

#include "apps/viz/plot.hpp"
#include "core/error.hpp"

namespace floesim::viz {

FloeField floe_field(const std::string& name) {
  if (name == "speed") return FloeField::speed;
  if (name == "heave") return FloeField::heave;
  throw InputError("--color: unknown field '" + name + "', expected speed or heave");
}

const char* field_name(FloeField f) { return f == FloeField::speed ? "speed" : "heave"; }

namespace {

// The floe field's value from one floe's 12 state columns.
double field_value(const double* s, FloeField f) {
  return f == FloeField::speed ? std::hypot(s[kVx], s[kVy]) : s[kHeave];
}
bool exists(const double* s) { return std::isfinite(s[kX]) && std::isfinite(s[kY]) && std::isfinite(s[kYaw]); }

// Sizes derived from the picture height, so that pictures of any size look alike.
double font_size(int height) { return std::clamp(height / 48.0, 9.0, 24.0); }
double legend_width(int height) { return 10.5 * font_size(height); }

// A round length for the scale bar: 1, 2 or 5 times a power of ten, about a
// fifth of the map width.
double scale_bar_length(double map_metres) {
  const double target = 0.2 * map_metres;
  const double p = std::pow(10.0, std::floor(std::log10(target)));
  const double m = target / p;
  return (m < 2 ? 1.0 : m < 5 ? 2.0 : 5.0) * p;
}

std::string metres(double L) {
  char buf[32];
  if (L >= 1000) std::snprintf(buf, sizeof buf, "%g km", L / 1000);
  else if (L >= 1) std::snprintf(buf, sizeof buf, "%g m", L);
  else if (L >= 0.01) std::snprintf(buf, sizeof buf, "%g cm", L * 100);
  else std::snprintf(buf, sizeof buf, "%g mm", L * 1000);
  return buf;
}

void colour_bar(Canvas& c, const Rect& bar, const ColorMap& map, const Range& range, const std::string& title,
                double fs) {
  c.text({bar.x, bar.y - 0.8 * fs}, title, fs, kInk);
  const int steps = std::max(2, static_cast<int>(bar.h));
  std::vector<std::uint32_t> px(static_cast<std::size_t>(steps));
  for (int k = 0; k < steps; ++k) px[static_cast<std::size_t>(k)] = pack(map(1.0 - (k + 0.5) / steps));
  c.image(px, 1, steps, bar, false);
  c.stroke_rect(bar, kInk, 1.0);
  // Ticks inside the range only (the nice ticks may reach past it).
  const auto ticks = nice_ticks(range.lo, range.hi, 4);
  const auto labels = tick_labels(ticks);
  const double slack = 1e-9 * (range.hi - range.lo);
  for (std::size_t k = 0; k < ticks.size(); ++k) {
    if (ticks[k] < range.lo - slack || ticks[k] > range.hi + slack) continue;
    const double y = bar.y + bar.h * (1.0 - range.normalise(ticks[k]));
    c.line({bar.x + bar.w, y}, {bar.x + bar.w + 0.4 * fs, y}, kInk, 1.0);
    c.text({bar.x + bar.w + 0.6 * fs, y + 0.35 * fs}, labels[k], 0.9 * fs, kInk);
  }
}

void draw_sea(Canvas& c, const RunView& run, std::size_t record, const FrameScales& sc, const FrameLayout& lay) {
  const SeaGrid& g = run.sea();
  const std::vector<double> eta = run.eta(record);
  const int nx = static_cast<int>(g.x.size());
  const int ny = g.dims == 2 ? static_cast<int>(g.y.size()) : 1;
  std::vector<std::uint32_t> px(eta.size());
  // Image rows go top down, the grid's y up.
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i)
      px[static_cast<std::size_t>((ny - 1 - j) * nx + i)] =
          pack(sea_map()(sc.sea.normalise(eta[static_cast<std::size_t>(j * nx + i)])));
  const Point a = lay.to_pixel(g.xmin(), g.ymax()), b = lay.to_pixel(g.xmax(), g.ymin());
  c.image(px, nx, ny, {a.x, a.y, b.x - a.x, b.y - a.y}, true);
}

void draw_floes(Canvas& c, const RunView& run, std::size_t record, FloeField field, const FrameScales& sc,
                const FrameLayout& lay) {
  const std::vector<double> state = run.state(record);
  const ColorMap& map = field == FloeField::speed ? speed_map() : heave_map();
  std::vector<Point> pts;
  for (std::size_t i = 0; i < run.floes(); ++i) {
    const double* s = state.data() + i * kStateWidth;
    if (!exists(s)) continue;  // the floe does not exist at this record
    const double cs = std::cos(s[kYaw]), sn = std::sin(s[kYaw]);
    pts.clear();
    for (std::size_t k = run.vertex_begin(i); k < run.vertex_end(i); ++k) {
      const double bx = run.body_x(k), by = run.body_y(k);
      pts.push_back(lay.to_pixel(s[kX] + cs * bx - sn * by, s[kY] + sn * bx + cs * by));
    }
    const Rgb fill = run.is_static(i) ? kStaticFloe : map(sc.floe.normalise(field_value(s, field)));
    // Outlines only where a floe is large enough on the picture to keep its colour visible.
    const double r_px = run.radius(i) * lay.s;
    c.polygon(pts, fill, kOutline, r_px > 4 ? std::min(1.0, 0.15 * r_px) : 0.0);
  }
}

void draw_scale_bar(Canvas& c, const FrameLayout& lay, double fs) {
  const double L = scale_bar_length(lay.map.w / lay.s);
  const double w = L * lay.s;
  const double x = lay.map.x, y = lay.map.y + lay.map.h + 1.0 * fs;
  c.fill_rect({x, y, w, 0.35 * fs}, kInk);
  c.line({x, y - 0.3 * fs}, {x, y + 0.65 * fs}, kInk, 1.0);
  c.line({x + w, y - 0.3 * fs}, {x + w, y + 0.65 * fs}, kInk, 1.0);
  c.text({x + w + 0.6 * fs, y + 0.55 * fs}, metres(L), fs, kInk);
}

}  // namespace

FrameScales frame_scales(const RunView& run, const std::vector<std::size_t>& records, FloeField field) {
  FrameScales sc;
  double xmin = INFINITY, xmax = -INFINITY, ymin = INFINITY, ymax = -INFINITY;
  if (run.sea().dims > 0) {
    const SeaGrid& g = run.sea();
    xmin = g.xmin(), xmax = g.xmax(), ymin = g.ymin(), ymax = g.ymax();
  }
  std::vector<double> values, sea_values;
  for (std::size_t k : records) {
    const std::vector<double> st = run.state(k);
    for (std::size_t i = 0; i < run.floes(); ++i) {
      const double* s = st.data() + i * kStateWidth;
      if (!exists(s)) continue;
      const double r = run.radius(i);
      xmin = std::min(xmin, s[kX] - r), xmax = std::max(xmax, s[kX] + r);
      ymin = std::min(ymin, s[kY] - r), ymax = std::max(ymax, s[kY] + r);
      if (!run.is_static(i)) values.push_back(field_value(s, field));
    }
    const std::vector<double> e = run.eta(k);
    sea_values.insert(sea_values.end(), e.begin(), e.end());
  }
  if (!(xmin <= xmax)) xmin = 0, xmax = 1, ymin = 0, ymax = 1;  // nothing to show
  // A margin of 2% of the larger side; a degenerate side gets that margin too.
  const double pad = 0.02 * std::max({xmax - xmin, ymax - ymin, 1e-6});
  sc.xmin = xmin - pad, sc.xmax = xmax + pad, sc.ymin = ymin - pad, sc.ymax = ymax + pad;
  sc.floe = field == FloeField::speed ? positive_range(values) : symmetric_range(values);
  sc.sea = symmetric_range(sea_values);
  return sc;
}

FrameLayout frame_layout(int width, int height, const FrameScales& sc) {
  const double fs = font_size(height);
  // Above the map: the time stamp; below it: the scale bar, so that neither covers the run.
  const Rect room{0.6 * fs, 2.2 * fs, width - legend_width(height) - 1.2 * fs, height - 5.2 * fs};
  const double vw = sc.xmax - sc.xmin, vh = sc.ymax - sc.ymin;
  FrameLayout lay;
  lay.s = std::max(std::min(room.w / vw, room.h / vh), 1e-12);
  lay.map = {room.x + 0.5 * (room.w - vw * lay.s), room.y + 0.5 * (room.h - vh * lay.s), vw * lay.s, vh * lay.s};
  lay.xmin = sc.xmin;
  lay.ymin = sc.ymin;
  return lay;
}

FrameLayout draw_frame(Canvas& c, const RunView& run, std::size_t record, FloeField field, const FrameScales& sc) {
  const FrameLayout lay = frame_layout(c.width(), c.height(), sc);
  const double fs = font_size(c.height());
  c.fill_rect({0, 0, double(c.width()), double(c.height())}, {1, 1, 1});
  c.fill_rect(lay.map, {0.80, 0.85, 0.89});  // open water where no sea is computed
  c.clip(lay.map);
  if (run.sea().dims > 0) draw_sea(c, run, record, sc, lay);
  draw_floes(c, run, record, field, sc, lay);
  c.reset_clip();
  c.stroke_rect(lay.map, kInk, 1.0);
  draw_scale_bar(c, lay, fs);

  char stamp[96];
  std::snprintf(stamp, sizeof stamp, "t = %.6g s   (record %zu of %zu)", run.times()[record], record + 1,
                run.records());
  c.text({lay.map.x, 1.5 * fs}, stamp, 1.1 * fs, kInk);
  c.text({lay.map.x + lay.map.w, 1.5 * fs}, std::filesystem::path(run.path()).filename().string(), 0.9 * fs,
         {0.4, 0.4, 0.4}, Align::right);

  // Legends, in the column right of the map: the floe field above the sea.
  const double lx = c.width() - legend_width(c.height()) + 0.6 * fs;
  const double bar_h = std::max(3.0 * fs, 0.3 * c.height());
  double y = 4.0 * fs;
  if (run.floes() > 0) {
    const bool speed = field == FloeField::speed;
    colour_bar(c, {lx, y, 1.4 * fs, bar_h}, speed ? speed_map() : heave_map(), sc.floe,
               speed ? "floe speed (m/s)" : "floe heave (m)", fs);
    y += bar_h + 3.0 * fs;
  }
  if (run.sea().dims > 0) colour_bar(c, {lx, y, 1.4 * fs, bar_h}, sea_map(), sc.sea, "sea elevation (m)", fs);
  return lay;
}

}  // namespace floesim::viz
