#include "apps/viz/plot.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "apps/viz/colormap.hpp"

namespace floesim::viz {

std::vector<double> nice_ticks(double lo, double hi, int target) {
  if (!std::isfinite(lo) || !std::isfinite(hi)) lo = 0.0, hi = 1.0;
  if (hi < lo) std::swap(lo, hi);
  if (hi - lo <= 1e-12 * std::max(std::abs(lo), std::abs(hi))) {
    // A constant: [0, 1] for zero (counters, energies at rest), else a tenth of its size around it.
    if (lo == 0.0) hi = 1.0;
    else lo -= 0.1 * std::abs(lo), hi += 0.1 * std::abs(hi);
  }
  const double raw = (hi - lo) / std::max(target, 1);
  const double p = std::pow(10.0, std::floor(std::log10(raw)));
  const double m = raw / p;
  const double step = (m <= 1.0 ? 1.0 : m <= 2.0 ? 2.0 : m <= 5.0 ? 5.0 : 10.0) * p;
  const double first = std::floor(lo / step + 1e-9) * step;
  const double last = std::ceil(hi / step - 1e-9) * step;
  std::vector<double> t;
  for (double v = first; v <= last + 0.5 * step; v += step) t.push_back(std::abs(v) < 1e-9 * step ? 0.0 : v);
  return t;
}

std::vector<std::string> tick_labels(const std::vector<double>& ticks) {
  if (ticks.empty()) return {};
  const double step = ticks.size() > 1 ? std::abs(ticks[1] - ticks[0]) : std::max(std::abs(ticks[0]), 1.0);
  double big = 0.0;
  for (double v : ticks) big = std::max(big, std::abs(v));
  const int step_exp = static_cast<int>(std::floor(std::log10(step) + 1e-9));
  const bool scientific = big >= 1e5 || (big > 0.0 && big < 1e-3);
  const int digits = scientific ? std::clamp(static_cast<int>(std::floor(std::log10(big) + 1e-9)) - step_exp, 0, 6)
                                : std::clamp(-step_exp, 0, 9);
  std::vector<std::string> out;
  char buf[40];
  for (double v : ticks) {
    std::snprintf(buf, sizeof buf, scientific ? "%.*e" : "%.*f", digits, v);
    out.emplace_back(buf);
  }
  return out;
}

namespace {

// Finite extent of one coordinate over every series.
void extent(const std::vector<Series>& series, bool use_x, double& lo, double& hi) {
  lo = INFINITY;
  hi = -INFINITY;
  for (const Series& s : series)
    for (std::size_t k = 0; k < s.x.size() && k < s.y.size(); ++k) {
      if (!std::isfinite(s.x[k]) || !std::isfinite(s.y[k])) continue;
      const double v = use_x ? s.x[k] : s.y[k];
      lo = std::min(lo, v);
      hi = std::max(hi, v);
    }
  if (lo > hi) lo = 0.0, hi = 1.0;
}

}  // namespace

void line_plot(Canvas& c, const Rect& area, const PlotSpec& spec, const std::vector<Series>& series) {
  const double fs = std::clamp(area.h / 28.0, 9.0, 16.0);  // font size
  double x_lo, x_hi, y_lo, y_hi;
  extent(series, true, x_lo, x_hi);
  extent(series, false, y_lo, y_hi);
  // x (time) spans exactly the data, with the nice ticks inside it; y spans the nice ticks.
  std::vector<double> xt = nice_ticks(x_lo, x_hi, std::max(2, static_cast<int>(area.w / 110)));
  double x0 = xt.front(), x1 = xt.back();
  if (x_hi > x_lo) {
    x0 = x_lo, x1 = x_hi;
    const double slack = 1e-9 * (x_hi - x_lo);
    std::erase_if(xt, [&](double v) { return v < x_lo - slack || v > x_hi + slack; });
  }
  const std::vector<double> yt = nice_ticks(y_lo, y_hi, std::max(2, static_cast<int>(area.h / 70)));
  const std::vector<std::string> xl = tick_labels(xt), yl = tick_labels(yt);

  // Room for the labels: y tick labels on the left, legend on the right.
  double ylab_w = 0.0;
  for (const std::string& l : yl) ylab_w = std::max(ylab_w, c.text_width(l, fs));
  const bool legend = spec.legend && series.size() > 1;
  double legend_w = 0.0;
  if (legend)
    for (const Series& s : series) legend_w = std::max(legend_w, c.text_width(s.name, fs) + 3.2 * fs);
  const double left = area.x + ylab_w + 2.2 * fs, right = area.x + area.w - legend_w - 0.8 * fs;
  const double top = area.y + (spec.title.empty() ? 0.8 : 2.0) * fs, bottom = area.y + area.h - 3.0 * fs;
  const Rect box{left, top, std::max(right - left, 10.0), std::max(bottom - top, 10.0)};
  auto px = [&](double x) { return box.x + (x - x0) / (x1 - x0) * box.w; };
  auto py = [&](double y) { return box.y + box.h - (y - yt.front()) / (yt.back() - yt.front()) * box.h; };

  const Rgb grid{0.88, 0.88, 0.88};
  for (std::size_t k = 0; k < xt.size(); ++k) {
    const double x = px(xt[k]);
    c.line({x, box.y}, {x, box.y + box.h}, grid, 1.0);
    c.line({x, box.y + box.h}, {x, box.y + box.h + 0.35 * fs}, kInk, 1.0);
    c.text({x, box.y + box.h + 1.4 * fs}, xl[k], fs, kInk, Align::centre);
  }
  for (std::size_t k = 0; k < yt.size(); ++k) {
    const double y = py(yt[k]);
    c.line({box.x, y}, {box.x + box.w, y}, grid, 1.0);
    c.line({box.x - 0.35 * fs, y}, {box.x, y}, kInk, 1.0);
    c.text({box.x - 0.5 * fs, y + 0.35 * fs}, yl[k], fs, kInk, Align::right);
  }
  c.stroke_rect(box, kInk, 1.0);
  if (!spec.title.empty()) c.text({box.x + 0.5 * box.w, area.y + 1.3 * fs}, spec.title, 1.1 * fs, kInk, Align::centre);
  c.text({box.x + 0.5 * box.w, area.y + area.h - 0.5 * fs}, spec.xlabel, fs, kInk, Align::centre);
  c.text({area.x + 1.0 * fs, box.y + 0.5 * box.h}, spec.ylabel, fs, kInk, Align::centre, true);

  c.clip({box.x - 2, box.y - 2, box.w + 4, box.h + 4});  // a line along an axis stays visible
  std::vector<Point> pts;
  for (std::size_t k = 0; k < series.size(); ++k) {
    const Series& s = series[k];
    pts.clear();
    for (std::size_t i = 0; i < s.x.size() && i < s.y.size(); ++i)
      pts.push_back(std::isfinite(s.x[i]) && std::isfinite(s.y[i]) ? Point{px(s.x[i]), py(s.y[i])}
                                                                     : Point{NAN, NAN});
    c.polyline(pts, line_colour(k), 1.6);
    if (pts.size() == 1) c.fill_rect({pts[0].x - 2, pts[0].y - 2, 4, 4}, line_colour(k));
  }
  c.reset_clip();

  if (legend) {
    double y = box.y + fs;
    for (std::size_t k = 0; k < series.size(); ++k, y += 1.4 * fs) {
      const double x = box.x + box.w + 0.8 * fs;
      c.line({x, y - 0.35 * fs}, {x + 1.8 * fs, y - 0.35 * fs}, line_colour(k), 2.5);
      c.text({x + 2.3 * fs, y}, series[k].name, fs, kInk);
    }
  }
}

}  // namespace floesim::viz
