#pragma once
// A floe: a rigid slab with a simple polygonal footprint, uniform thickness and
// density (MODEL.md §1). This header builds one floe from user input, checking
// it, and derives its exact mass properties from polygon integrals.

#include <string>
#include <vector>

#include "core/geometry.hpp"

namespace floesim {

// A floe as the user gives it. World position of vertex k at t = 0:
//   position + R(yaw) vertices[k]
// (inline floes: world vertices, position 0, yaw 0; pack files: body-frame
// vertices with the floe's position and yaw). Either vertex order.
struct FloeInput {
  std::vector<Vec2> vertices;     // m, input frame
  Vec2 position = Vec2::Zero();   // m, world
  double thickness = 1.0;         // m
  double density = 917.0;         // kg/m^3
  bool is_static = false;         // obstacle: infinite mass, never moves
  double yaw = 0.0;               // rad, initial yaw
  Vec2 velocity = Vec2::Zero();   // m/s, of the centroid
  double angular_velocity = 0.0;  // rad/s
  double heave = 0.0;             // m, from floating equilibrium ([coupling] start = "given")
  double heave_rate = 0.0;        // m/s
  double ocean_drag = -1.0;       // C_w of this floe; < 0: the [forcing] default
  // A soft mooring to where the floe starts (coupling/mooring.hpp): its
  // period (s; 0: none) and damping ratio.
  double mooring_period = 0.0;
  double mooring_damping = 0.0;
  std::string origin;             // where it came from, for messages ("file.toml floe 3")
};

// Exact mass properties of a floe (body frame: origin at the centroid).
// With rho = density, h = thickness, over the footprint ω:
//   A = ∫ 1,  M = rho h A,
//   I_z = rho h ∫ |x - G|²                (yaw),
//   I_x = rho h ∫ (x2 - G2)² + M h²/12   (roll, about the body x axis),
//   I_y = rho h ∫ (x1 - G1)² + M h²/12   (pitch),
//   draft = rho h / rho_w (set by the caller, who knows rho_w).
struct MassProperties {
  double area = 0.0;     // m^2
  double mass = 0.0;     // kg (infinite for static floes)
  double inertia_z = 0.0;  // kg m^2, yaw
  double inertia_x = 0.0;  // kg m^2, roll
  double inertia_y = 0.0;  // kg m^2, pitch
};

// The validated shape: body-frame vertices (counter-clockwise, centroid at the
// origin), the world centroid, mass properties.
struct FloeShape {
  std::vector<Vec2> body;   // m, body frame
  Vec2 centroid;            // m, world position of the centroid at t = 0
  MassProperties props;     // of the slab (finite even for a static floe)
  bool reoriented = false;  // the input was clockwise and was reversed
};

// Bounds on what a floe may be given, beyond finiteness (checked here, once,
// for every source of floes: inline TOML, pack and FloeDyn files):
//  * |coordinate| <= kMaxCoordinate for vertices and position: 1e9 m, 25
//    times the Earth's circumference. Beyond it the area, inertias and contact
//    geometry lose their precision and, near 1e154, overflow;
//  * speeds <= kMaxSpeed = 1000 m/s: |velocity|, |heave_rate| and the rim
//    speed |angular_velocity| * (largest distance from the centroid to a
//    vertex). Sea ice drifts at about 1 m/s; a floe at 2e130 m/s would cross
//    the domain in far less than any step, and the adaptive step would shrink
//    without end.
//  * thickness and size (largest distance between two vertices) in
//    [kMinLength, kMaxCoordinate], density in [kMinDensity, kMaxDensity]: a
//    floe 1e-164 m thick (one flipped byte of a pack file) has a mass whose
//    inverse overflows in the first step.
inline constexpr double kMaxCoordinate = 1e9;  // m
inline constexpr double kMaxSpeed = 1e3;       // m/s
inline constexpr double kMinLength = 1e-4;     // m: 0.1 mm
inline constexpr double kMinDensity = 1.0;     // kg/m^3 (air is 1.2)
inline constexpr double kMaxDensity = 1e5;     // kg/m^3 (osmium is 2.3e4)

// Checks a floe and builds its shape. Throws InputError naming input.origin
// when: fewer than 3 vertices, a non-finite number, a coordinate or speed past
// the bounds above, zero or negative area (degenerate), a self-intersecting
// outline.
// A clockwise outline is reversed (reported through FloeShape::reoriented).
FloeShape make_floe_shape(const FloeInput& input);

}  // namespace floesim
