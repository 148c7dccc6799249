// floesim_bench_render [REPEATS]: time one frame of `floesim render` (apps/viz)
// on named scenarios: packs of 1000 and 10000 floes (core/pack_generator.hpp,
// box side 100 sqrt(N) m, concentration 0.6) moving at random speeds over a
// 256 x 256 sea with a regular wave, at 1280x720 and 1920x1080. Prints CSV:
// per phase (open the run file, scales, draw, write the PNG) and in total, the
// minimum and the median over REPEATS after a warm-up (the machine is shared;
// the minimum is the figure least disturbed by others).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include "apps/viz/frame.hpp"
#include "core/floes.hpp"
#include "core/pack_generator.hpp"
#include "core/run_file.hpp"

using namespace floesim;
namespace fs = std::filesystem;

namespace {

struct Scenario {
  const char* name;
  std::size_t floes;
  int sea_cells;  // per side; 0: no sea
  int width, height;
};

// A run file of two records: the pack at rest, then moving with a wave.
void write_run(const std::string& path, std::size_t n, int cells) {
  PackOptions o;
  o.floes = n;
  o.concentration = 0.6;
  o.width = o.height = 100.0 * std::sqrt(static_cast<double>(n));
  Floes floes = generate_pack(o).floes;
  SeaGridInfo sea;
  if (cells > 0) sea = {2, {cells, cells}, {o.width, o.height}};
  RunWriter w(path, floes, "", {"total"}, sea);
  std::vector<double> eta(static_cast<std::size_t>(cells) * static_cast<std::size_t>(cells));
  const double e[1] = {0.0};
  std::mt19937_64 rng(1);
  std::uniform_real_distribution<double> u(-0.5, 0.5);
  for (int k = 0; k < 2; ++k) {
    for (int j = 0; j < cells; ++j)
      for (int i = 0; i < cells; ++i)
        eta[static_cast<std::size_t>(j * cells + i)] = k * 0.5 * std::sin(2 * M_PI * (i + 0.5) / 32.0);
    w.record(k, floes, e, {}, cells > 0 ? std::span<const double>(eta) : std::span<const double>());
    for (FloeState& s : floes.state) s.vx = u(rng), s.vy = u(rng), s.yaw += u(rng), s.heave = 0.1 * u(rng);
  }
  w.finish("complete");
}

double ms_since(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t).count();
}

}  // namespace

int main(int argc, char** argv) {
  const int repeats = argc > 1 ? std::max(1, std::atoi(argv[1])) : 5;
  const std::vector<Scenario> scenarios = {
      {"floes1000_sea256_720p", 1000, 256, 1280, 720},
      {"floes1000_nosea_720p", 1000, 0, 1280, 720},
      {"floes1000_sea256_1080p", 1000, 256, 1920, 1080},
      {"floes10000_sea256_1080p", 10000, 256, 1920, 1080},
  };
  const fs::path dir = fs::temp_directory_path() / "floesim_bench_render";
  fs::create_directories(dir);
  std::printf("scenario,floes,sea_cells,width,height,repeats,open_ms_min,scales_ms_min,draw_ms_min,png_ms_min,"
              "total_ms_min,total_ms_median,png_bytes\n");
  for (const Scenario& sc : scenarios) {
    const std::string run = (dir / (std::string(sc.name) + ".h5")).string();
    const std::string png = (dir / (std::string(sc.name) + ".png")).string();
    write_run(run, sc.floes, sc.sea_cells);
    std::vector<double> open, scales, draw, save, total;
    for (int r = 0; r <= repeats; ++r) {  // r = 0: warm-up
      const auto t0 = std::chrono::steady_clock::now();
      const viz::RunView view(run);
      const double t_open = ms_since(t0);
      auto t = std::chrono::steady_clock::now();
      const viz::FrameScales s = viz::frame_scales(view, {1}, viz::FloeField::speed);
      const double t_scales = ms_since(t);
      t = std::chrono::steady_clock::now();
      viz::Canvas canvas(sc.width, sc.height);
      viz::draw_frame(canvas, view, 1, viz::FloeField::speed, s);
      const double t_draw = ms_since(t);
      t = std::chrono::steady_clock::now();
      canvas.save_png(png);
      const double t_png = ms_since(t);
      if (r == 0) continue;
      open.push_back(t_open), scales.push_back(t_scales), draw.push_back(t_draw), save.push_back(t_png);
      total.push_back(ms_since(t0));
    }
    for (auto* v : {&open, &scales, &draw, &save, &total}) std::sort(v->begin(), v->end());
    std::printf("%s,%zu,%d,%d,%d,%d,%.1f,%.1f,%.1f,%.1f,%.1f,%.1f,%ju\n", sc.name, sc.floes, sc.sea_cells, sc.width,
                sc.height, repeats, open[0], scales[0], draw[0], save[0], total[0], total[total.size() / 2],
                static_cast<std::uintmax_t>(fs::file_size(png)));
    std::fflush(stdout);
  }
  fs::remove_all(dir);
  return 0;
}
