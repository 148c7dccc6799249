// floesim plot OUT.h5 energy|lcp|heave|fracture [-o FILE.png]: diagnostics of
// a run as PNG line plots (apps/viz/plot.*), so that a run can be judged at a
// glance.
#include <cmath>
#include <filesystem>
#include <sstream>
#include <iostream>

#include "apps/commands.hpp"
#include "apps/viz/plot.hpp"
#include "apps/viz/run_view.hpp"
#include "apps/viz/size.hpp"
#include "core/error.hpp"
#include "core/run_reader.hpp"

namespace floesim::apps {

namespace {

namespace fs = std::filesystem;
using viz::Series;

// Column c of a [T, k] dataset against time.
std::vector<Series> columns_vs_time(const RunReader& r, const std::string& dataset,
                                    const std::vector<double>& t, std::vector<std::string> names) {
  const auto shape = r.shape(dataset);
  if (shape.size() != 2 || shape[0] != t.size())
    throw InputError(r.path() + ": " + dataset + ": expected [T, k] with T = " + std::to_string(t.size()) +
                     " records");
  const std::size_t k = shape[1];
  const std::vector<double> v = r.read(dataset);
  std::vector<Series> out(k);
  for (std::size_t c = 0; c < k; ++c) {
    out[c].name = c < names.size() ? names[c] : "column " + std::to_string(c);
    out[c].x = t;
    for (std::size_t i = 0; i < t.size(); ++i) out[c].y.push_back(v[i * k + c]);
  }
  return out;
}

// "0,3,7" -> indices, each below n; InputError naming --floes otherwise.
std::vector<std::size_t> parse_floes(const std::string& text, std::size_t n) {
  std::vector<std::size_t> out;
  std::size_t pos = 0;
  while (pos <= text.size()) {
    const std::size_t end = std::min(text.find(',', pos), text.size());
    const std::string item = text.substr(pos, end - pos);
    std::size_t used = 0;
    long long v = -1;
    try { v = std::stoll(item, &used); } catch (...) { used = 0; }
    if (used != item.size() || item.empty() || v < 0 || static_cast<std::size_t>(v) >= n)
      throw InputError("--floes: '" + item + "' is not a floe index (expected 0 to " + std::to_string(n) +
                       " - 1, comma-separated)");
    out.push_back(static_cast<std::size_t>(v));
    pos = end + 1;
  }
  return out;
}

// Default heave floes: the moving ones, at most eight, spread over the indices.
std::vector<std::size_t> default_floes(const viz::RunView& run) {
  std::vector<std::size_t> moving;
  for (std::size_t i = 0; i < run.floes(); ++i)
    if (!run.is_static(i)) moving.push_back(i);
  if (moving.size() <= 8) return moving;
  std::vector<std::size_t> out;
  for (std::size_t k = 0; k < 8; ++k) out.push_back(moving[k * (moving.size() - 1) / 7]);
  return out;
}

// Fracture: the number of (dynamic) floes, and of floes in each size class
// (equivalent diameter d = sqrt(4 A / pi), `classes` classes of equal width
// in log d over the run's floes), against time. A floe exists at a record
// where its state is not NaN (core/run_file.hpp).
struct FractureSeries {
  Series count;
  std::vector<Series> classes;
};
FractureSeries fracture_series(const viz::RunView& run, std::size_t classes) {
  const std::vector<double>& t = run.times();
  const std::vector<double> area = run.reader().read("/floes/area");
  const std::size_t n = run.floes();
  if (area.size() != n)
    throw InputError(run.path() + ": /floes/area: expected " + std::to_string(n) + " values, one per floe");
  const std::vector<double> x = run.state_columns(0, 1);  // [T, n]
  double lo = INFINITY, hi = 0.0;
  std::vector<double> d(n, 0.0);
  for (std::size_t i = 0; i < n; ++i) {
    if (run.is_static(i)) continue;
    d[i] = std::sqrt(4.0 * area[i] / M_PI);
    lo = std::min(lo, d[i]);
    hi = std::max(hi, d[i]);
  }
  FractureSeries out;
  out.count = {"all floes", t, {}};
  if (!(hi > 0.0)) return out;
  const double span = std::log(hi / lo) > 0.0 ? std::log(hi / lo) : 1.0;
  auto class_of = [&](double di) {
    return std::min(classes - 1, static_cast<std::size_t>(static_cast<double>(classes) * std::log(di / lo) / span));
  };
  for (std::size_t c = 0; c < classes; ++c) {
    std::ostringstream name;
    name.precision(3);
    name << "d " << lo * std::exp(span * static_cast<double>(c) / static_cast<double>(classes)) << "-"
         << lo * std::exp(span * static_cast<double>(c + 1) / static_cast<double>(classes)) << " m";
    out.classes.push_back({name.str(), t, std::vector<double>(t.size(), 0.0)});
  }
  for (std::size_t k = 0; k < t.size(); ++k) {
    double count = 0.0;
    for (std::size_t i = 0; i < n; ++i) {
      if (run.is_static(i) || std::isnan(x[k * n + i])) continue;
      count += 1.0;
      out.classes[class_of(d[i])].y[k] += 1.0;
    }
    out.count.y.push_back(count);
  }
  return out;
}

}  // namespace

void add_plot_command(CLI::App& app, Registry& registry) {
  struct Args { std::string file, what, output, size = "1200x700", floes; };
  auto args = std::make_shared<Args>();
  CLI::App* sub = app.add_subcommand("plot", "Plot a run's diagnostics as PNG: energy (every part), "
                                              "lcp (collision LCP counters), heave (floe heave time series) or "
                                              "fracture (floe count and size classes against time)");
  sub->add_option("FILE", args->file, "Run file (.h5)")->required();
  sub->add_option("WHAT", args->what, "energy, lcp, heave or fracture")->required();
  sub->add_option("-o,--output", args->output, "PNG to write (default: FILE's name with _WHAT.png, here)");
  sub->add_option("--size", args->size, "Picture size in pixels, WxH")->capture_default_str();
  sub->add_option("--floes", args->floes, "heave: floe indices, comma-separated (default: up to 8 moving floes)");
  registry[sub] = [args] {
    const std::string& what = args->what;
    if (what != "energy" && what != "lcp" && what != "heave" && what != "fracture")
      throw InputError("plot: unknown plot '" + what + "', expected energy, lcp, heave or fracture");
    const auto [width, height] = viz::parse_size(args->size, "--size");
    const viz::RunView run(args->file);
    const RunReader& reader = run.reader();
    if (run.records() == 0) throw InputError(args->file + ": the run has no records (/time is empty): nothing to plot");
    const std::vector<double>& t = run.times();
    const std::string name = fs::path(args->file).filename().string();
    const std::string out = args->output.empty() ? fs::path(args->file).stem().string() + "_" + what + ".png" : args->output;

    viz::Canvas canvas(width, height);
    const viz::Rect all{8, 8, width - 16.0, height - 16.0};
    std::size_t drawn = 0;
    std::string extra;  // more key: value lines
    if (what == "energy") {
      const std::string set = "/diagnostics/energy";
      auto series = columns_vs_time(reader, set, t, reader.strings(set, "columns"));
      viz::line_plot(canvas, all, {"energy by part: " + name, "time (s)", "energy (J)"}, series);
      drawn = series.size();
    } else if (what == "lcp") {
      const std::string set = "/diagnostics/lcp";
      std::vector<std::string> names = reader.strings(set, "columns");
      if (names.empty()) names = {"solves", "pivots", "failures", "fallbacks"};
      auto series = columns_vs_time(reader, set, t, names);
      // One panel per counter (their sizes differ by orders of magnitude), two columns.
      const std::size_t cols = 2, rows = (series.size() + 1) / 2;
      const double w = all.w / cols, h = all.h / static_cast<double>(std::max<std::size_t>(rows, 1));
      for (std::size_t k = 0; k < series.size(); ++k) {
        const viz::Rect cell{all.x + static_cast<double>(k % cols) * w, all.y + static_cast<double>(k / cols) * h, w, h};
        viz::line_plot(canvas, cell, {"LCP " + series[k].name + " (cumulative): " + name, "time (s)", series[k].name},
                       {series[k]});
      }
      drawn = series.size();
    } else if (what == "fracture") {
      const FractureSeries f = fracture_series(run, 5);
      // One panel: the count and its classes share the unit (floes) and the axis.
      std::vector<Series> series{f.count};
      series.insert(series.end(), f.classes.begin(), f.classes.end());
      viz::line_plot(canvas, all, {"floes, all and by equivalent diameter: " + name, "time (s)", "floes"}, series);
      drawn = series.size();
      if (!f.count.y.empty())
        extra = "floes: " + std::to_string(static_cast<long>(f.count.y.front())) + " -> " +
                std::to_string(static_cast<long>(f.count.y.back())) + "\n";
    } else {
      const std::vector<std::size_t> floes = args->floes.empty() ? default_floes(run) : parse_floes(args->floes, run.floes());
      const std::vector<double> heave = run.state_columns(viz::kHeave, 1);  // [T, n]
      std::vector<Series> series;
      for (std::size_t i : floes) {
        Series s{"floe " + std::to_string(i), t, {}};
        for (std::size_t k = 0; k < t.size(); ++k) s.y.push_back(heave[k * run.floes() + i]);
        series.push_back(std::move(s));
      }
      viz::line_plot(canvas, all, {"floe heave: " + name, "time (s)", "heave (m)"}, series);
      drawn = series.size();
    }
    canvas.save_png(out);
    std::cout << "output: " << fs::absolute(out).string() << "\nplot: " << what << "\nseries: " << drawn
              << "\nsize: " << width << "x" << height << "\n" << extra;
    return 0;
  };
}

}  // namespace floesim::apps
