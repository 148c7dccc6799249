#pragma once
// All floes of a run, stored as contiguous per-floe arrays (structure of
// arrays) so that phases can run over index ranges, and later over the floes
// of one subdomain. Vertices of all floes are concatenated in one array with
// offsets (CSR style), in each floe's body frame (origin at the centroid).

#include <cstdint>
#include <span>
#include <vector>

#include "core/floe.hpp"
#include "core/floe_bytes.hpp"

namespace floesim {

// The state of one floe; the order of the fields is the column order of
// /floes/state in the run file.
struct FloeState {
  double x = 0.0, y = 0.0;        // m, world position of the centroid
  double yaw = 0.0;               // rad
  double vx = 0.0, vy = 0.0;      // m/s
  double yaw_rate = 0.0;          // rad/s
  double heave = 0.0;             // m, from floating equilibrium
  double pitch = 0.0, roll = 0.0; // rad (small): bottom slope a = (pitch, roll)
  double heave_rate = 0.0, pitch_rate = 0.0, roll_rate = 0.0;
};
// The horizontal pose after a free flight of h seconds: straight path at
// (vx, vy), yaw turning at yaw_rate. The vertical DOFs are left as they are.
inline FloeState drifted(FloeState s, double h) {
  s.x += h * s.vx;
  s.y += h * s.vy;
  s.yaw += h * s.yaw_rate;
  return s;
}

// Horizontal velocity of the floe's point at arm r from its centroid (world
// frame): v + omega e_z x r.
inline Vec2 arm_velocity(const FloeState& s, const Vec2& r) {
  return Vec2{s.vx, s.vy} + s.yaw_rate * Vec2{-r.y(), r.x()};
}

inline constexpr int kStateColumns = 12;
static_assert(sizeof(FloeState) == kStateColumns * sizeof(double));
inline constexpr const char* kStateColumnNames[kStateColumns] = {
    "x", "y", "yaw", "vx", "vy", "yaw_rate",
    "heave", "pitch", "roll", "heave_rate", "pitch_rate", "roll_rate"};

struct Floes {
  // Declared so that Floes is not an aggregate. GCC 12 destroys twice a member that
  // is an aggregate with default member initializers (offsets{0}) when it is
  // brace-initialised with `{}` inside an enclosing aggregate whose later
  // initialiser throws: `Scenario s{config, {}, make_forcing(...)}` aborted with
  // "double free" on every bad forcing file (issue 17). A constructor makes `{}`
  // a constructor call, which GCC cleans up correctly.
  Floes() = default;

  std::vector<std::size_t> offsets{0};  // floe i owns body[offsets[i] .. offsets[i+1])
  std::vector<Vec2> body;               // m, body-frame vertices, counter-clockwise

  std::vector<double> thickness;        // m
  std::vector<double> density;          // kg/m^3
  std::vector<double> area;             // m^2
  std::vector<double> mass;             // kg (the slab's, also for static floes)
  std::vector<double> inertia_z;        // kg m^2
  std::vector<double> inertia_x, inertia_y;
  std::vector<double> ocean_drag;       // C_w per floe (< 0: use the run's default)
  std::vector<std::uint8_t> is_static;  // 1: obstacle, infinite mass
  std::vector<FloeState> state;
  // The floe's number in the run file (/floes/...): the order of creation.
  // A floe that splits ends; its pieces get new numbers (core/run_file.hpp).
  std::vector<std::uint32_t> id;
  std::uint32_t ids_issued = 0;         // numbers given so far

  std::size_t size() const { return thickness.size(); }
  bool empty() const { return thickness.empty(); }

  std::span<const Vec2> vertices(std::size_t i) const {
    return {body.data() + offsets[i], offsets[i + 1] - offsets[i]};
  }
  // Inverse mass and yaw inertia: 0 for static floes.
  double inv_mass(std::size_t i) const { return is_static[i] ? 0.0 : 1.0 / mass[i]; }
  double inv_inertia_z(std::size_t i) const { return is_static[i] ? 0.0 : 1.0 / inertia_z[i]; }
  // draft = rho_i h / rho_w: depth of the bottom of a floe floating at rest.
  double draft(std::size_t i, double rho_water) const {
    return density[i] * thickness[i] / rho_water;
  }
  // World position of the body-frame point p of floe i.
  Vec2 to_world(std::size_t i, const Vec2& p) const {
    const FloeState& s = state[i];
    return Vec2{s.x, s.y} + rotate(p, s.yaw);
  }
  std::vector<Vec2> world_vertices(std::size_t i) const;

  // Appends a validated floe; returns its index.
  std::size_t add(const FloeShape& shape, const FloeInput& input);
  // Puts a new floe (with a new id) in the place of floe i; the state is the
  // input's, as add() sets it.
  void replace(std::size_t i, const FloeShape& shape, const FloeInput& input);
  // A copy of the listed floes, in that order, with their ids.
  Floes select(std::span<const std::size_t> which) const;
  // Every per-floe array above must be handled by add, replace and select,
  // and counted by memory() (below).

  // What these arrays allocate (core/floe_bytes.hpp), against the entries of
  // the floes `held` marks (empty: every floe): the constants (thickness to
  // is_static, and id), the body vertices (CSR), the states.
  struct Memory {
    FloeBytes constants, vertices, state;
  };
  Memory memory(std::span<const std::uint8_t> held) const;
};

}  // namespace floesim
