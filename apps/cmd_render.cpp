// floesim render OUT.h5 [--time T | --frames DIR] [--size WxH] [--color speed|heave] [--mp4]:
// PNG pictures of a run (floes over the sea elevation) and, with ffmpeg, a video.
// Drawing is in apps/viz/frame.*; this file chooses records, files and ffmpeg.
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <sstream>

#include "apps/commands.hpp"
#include "apps/viz/frame.hpp"
#include "apps/viz/size.hpp"
#include "core/error.hpp"

extern char** environ;

namespace floesim::apps {

namespace {

namespace fs = std::filesystem;

// The first executable `name` on PATH, or empty.
std::string find_on_path(const std::string& name) {
  const char* path = std::getenv("PATH");
  std::stringstream dirs(path ? path : "");
  std::string dir;
  while (std::getline(dirs, dir, ':')) {
    const fs::path p = fs::path(dir.empty() ? "." : dir) / name;
    if (access(p.c_str(), X_OK) == 0 && fs::is_regular_file(p)) return p.string();
  }
  return {};
}

// Runs a program with arguments (no shell) and returns its exit status (-1: it could not start).
int run_program(const std::vector<std::string>& args) {
  std::vector<char*> argv;
  for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  pid_t pid = 0;
  if (posix_spawn(&pid, args[0].c_str(), nullptr, nullptr, argv.data(), environ) != 0) return -1;
  int status = 0;
  if (waitpid(pid, &status, 0) < 0) return -1;
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

double elapsed_ms(std::chrono::steady_clock::time_point since) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - since).count();
}

}  // namespace

void add_render_command(CLI::App& app, Registry& registry) {
  struct Args {
    std::string file, output, frames, size = "1280x720", color = "speed";
    double time = 0.0;
    bool mp4 = false;
    std::size_t every = 1;
    double fps = 10.0;
  };
  auto args = std::make_shared<Args>();
  CLI::App* sub = app.add_subcommand("render", "Draw a run: floes coloured by speed or heave over the sea "
                                                "elevation, as PNG pictures or an MP4 video");
  sub->add_option("FILE", args->file, "Run file (.h5)")->required();
  CLI::Option* time = sub->add_option("--time", args->time, "Draw the record nearest to this time (s); default: the last");
  CLI::Option* frames = sub->add_option("--frames", args->frames, "Draw every record into this folder as frame_NNNNN.png");
  time->excludes(frames);
  sub->add_option("--size", args->size, "Picture size in pixels, WxH")->capture_default_str();
  sub->add_option("--color", args->color, "Floe colour: speed or heave")->capture_default_str();
  CLI::Option* mp4 = sub->add_flag("--mp4", args->mp4, "Also make an MP4 video of the frames (needs ffmpeg)");
  mp4->excludes(time);
  sub->add_option("--every", args->every, "With --frames or --mp4: draw every K-th record")
      ->capture_default_str()->check(CLI::PositiveNumber);
  sub->add_option("--fps", args->fps, "With --mp4: frames per second of the video")
      ->capture_default_str()->check(CLI::PositiveNumber);
  sub->add_option("-o,--output", args->output,
                  "Picture (default: FILE's name with .png, here) or, with --mp4, video (default: .mp4)");
  registry[sub] = [args, time] {
    const auto start = std::chrono::steady_clock::now();
    const viz::FloeField field = viz::floe_field(args->color);
    const auto [width, height] = viz::parse_size(args->size, "--size");
    const viz::RunView run(args->file);
    if (run.records() == 0) throw InputError(args->file + ": the run has no records (/time is empty): nothing to draw");
    const std::string stem = fs::path(args->file).stem().string();
    std::ostream& o = std::cout;

    if (args->frames.empty() && !args->mp4) {
      const std::size_t k = time->count() ? run.record_at(args->time) : run.records() - 1;
      const std::string out = args->output.empty() ? stem + ".png" : args->output;
      const viz::FrameScales sc = viz::frame_scales(run, {k}, field);
      viz::Canvas canvas(width, height);
      const viz::FrameLayout lay = viz::draw_frame(canvas, run, k, field, sc);
      canvas.save_png(out);
      o << std::setprecision(10) << "output: " << fs::absolute(out).string() << "\nrecord: " << k
        << "\ntime: " << run.times()[k] << "\nsize: " << width << "x" << height << "\ncolor: "
        << viz::field_name(field) << "\nview: " << sc.xmin << " " << sc.xmax << " " << sc.ymin << " " << sc.ymax
        << "\nmap_pixels: " << lay.map.x << " " << lay.map.y << " " << lay.map.w << " " << lay.map.h
        << "\nfloe_range: " << sc.floe.lo << " " << sc.floe.hi << "\nsea_range: " << sc.sea.lo << " " << sc.sea.hi
        << "\ntime_ms: " << std::setprecision(4) << elapsed_ms(start) << "\n";
      return 0;
    }

    // Every K-th record, with fixed scales so that the frames compare.
    std::vector<std::size_t> records;
    for (std::size_t k = 0; k < run.records(); k += args->every) records.push_back(k);
    const bool temporary = args->frames.empty();
    const fs::path dir = temporary ? fs::temp_directory_path() / ("floesim_frames_" + std::to_string(getpid()))
                                   : fs::path(args->frames);
    std::error_code ec;
    fs::create_directories(dir, ec);
    if (ec || !fs::is_directory(dir)) throw InputError(dir.string() + ": cannot create the frames folder (" + ec.message() + ")");
    const viz::FrameScales sc = viz::frame_scales(run, records, field);
    viz::Canvas canvas(width, height);
    char name[32];
    for (std::size_t f = 0; f < records.size(); ++f) {
      viz::draw_frame(canvas, run, records[f], field, sc);
      std::snprintf(name, sizeof name, "frame_%05zu.png", f);
      canvas.save_png((dir / name).string());
    }
    o << std::setprecision(10) << "frames: " << records.size() << "\n";
    if (!temporary) o << "folder: " << fs::absolute(dir).string() << "\n";
    o << "size: " << width << "x" << height << "\ncolor: " << viz::field_name(field) << "\nview: " << sc.xmin << " "
      << sc.xmax << " " << sc.ymin << " " << sc.ymax << "\nfloe_range: " << sc.floe.lo << " " << sc.floe.hi
      << "\nsea_range: " << sc.sea.lo << " " << sc.sea.hi << "\n";

    int status = 0;
    if (args->mp4) {
      const std::string ffmpeg = find_on_path("ffmpeg");
      const std::string out = args->output.empty() ? stem + ".mp4" : args->output;
      if (ffmpeg.empty()) {
        std::cerr << "floesim: note: ffmpeg is not installed (Debian: apt-get install ffmpeg), so no video was made"
                  << (temporary ? "; use --frames DIR to keep the PNG frames" : "; the PNG frames are in " + dir.string())
                  << "\n";
        o << "video: skipped (ffmpeg not found)\n";
      } else {
        std::ostringstream fps;
        fps << args->fps;
        // yuv420p (playable everywhere) needs even sizes: pad by a pixel if odd.
        const int code = run_program({ffmpeg, "-y", "-loglevel", "error", "-framerate", fps.str(), "-i",
                                      (dir / "frame_%05d.png").string(), "-vf", "pad=ceil(iw/2)*2:ceil(ih/2)*2",
                                      "-c:v", "libx264", "-pix_fmt", "yuv420p", out});
        if (code != 0) {
          std::cerr << "floesim: error: ffmpeg failed (exit " << code << ") making " << out << "\n";
          status = 1;
        } else {
          o << "video: " << fs::absolute(out).string() << "\n";
        }
      }
    }
    if (temporary) fs::remove_all(dir, ec);
    o << "time_ms: " << std::setprecision(4) << elapsed_ms(start) << "\n";
    return status;
  };
}

}  // namespace floesim::apps
