#pragma once
// Floe pack files: our own layout ("floesim-pack-1") and FloeDyn input files,
// told apart automatically (docs/formats.md describes both).
//
// floesim-pack-1 (HDF5; root attribute format = "floesim-pack-1"):
//   /floes/offsets   int64 [n+1]   floe i owns vertices[offsets[i] .. offsets[i+1])
//   /floes/vertices  f64 [V, 2]    m, body frame (origin at the centroid), CCW
//   /floes/pose      f64 [n, 3]    x, y (m, world centroid), yaw (rad)
//   /floes/velocity  f64 [n, 3]    vx, vy (m/s), yaw rate (rad/s)      (optional: 0)
//   /floes/thickness f64 [n]       m                                   (optional: [floes] thickness)
//   /floes/density   f64 [n]       kg/m^3                              (optional: [floes] density)
//   /floes/static    u8 [n]        1 = obstacle                        (optional: 0)
//   /floes/ocean_drag f64 [n]      C_w; NaN or < 0 = [forcing] default (optional)
//   /window          f64 [4]       xmin, xmax, ymin, ymax (m)          (optional)
//
// FloeDyn input (data/floedyn/README.md): /floe_shapes/{i} body-frame
// vertices with attributes C_w, optional obstacle and thickness; /floe_states
// [T, N, 9 or 11], record 0 used; /window.

#include <array>
#include <optional>
#include <string>
#include <vector>

#include "core/floe.hpp"

namespace floesim {

struct Floes;

struct PackDefaults {
  double thickness = 1.0;   // m, for floes whose file gives none
  double density = 917.0;   // kg/m^3
};

struct Pack {
  std::string format;                         // "floesim-pack-1" or "floedyn"
  std::vector<FloeInput> floes;               // not yet validated (see make_floe_shape)
  std::optional<std::array<double, 4>> window;  // xmin, xmax, ymin, ymax
};

// Reads a pack file of either format. Throws InputError naming the file and the
// dataset for anything missing, mis-shaped or non-finite, or a file that
// crashes the HDF5 library: the file is first read in a child process (fork;
// where that fails, only in this one).
Pack read_pack(const std::string& path, const PackDefaults& defaults = {});
// The same read in this process only (a corrupt file may crash it): for the
// fuzz target, which must see such crashes.
Pack read_pack_in_process(const std::string& path, const PackDefaults& defaults = {});

// Writes floes (their current state) as a floesim-pack-1 file.
void write_pack(const std::string& path, const Floes& floes,
                const std::optional<std::array<double, 4>>& window = std::nullopt);

}  // namespace floesim
