#pragma once
// Horizontal rigid motion of floes under ocean drag, air drag and Coriolis
// (MODEL.md §2; Rabatel et al. 2015). Per unit footprint area at point P:
//   ocean:    tau_w(P) = rho_w C_w |u| u,   u = U_w(P) - v_P,
//             v_P = V + omega k x (P - G)   (Varignon: drag also brakes rotation)
//   air:      tau_a    = rho_a C_a |U_a| U_a (independent of the ice velocity)
// and on the whole floe the Coriolis force -f k x (M V). With W = (V, omega)
// and the mass matrix M = diag(M, M, I_z):
//   M dW/dt = F(W) = ∫ B^T tau_w dA + (A tau_a, 0) + F_c(W),
//   B(P) = [I_2 | k x r] (2x3), r = P - G, so the torque is ∫ (k x r) . tau_w.
//
// Integrator (semi-implicit, one 3x3 solve per floe): the ocean drag is
// linearised about W_n and taken implicitly (linearised backward Euler,
// L-stable: no oscillation however stiff the drag), the Coriolis term by the
// trapezoidal rule (a Cayley rotation: inertial circles keep their radius):
//   (M - dt J_w - dt/2 J_c) (W_{n+1} - W_n) = dt F(W_n),
//   J_w = dF_w/dW = -rho_w C_w ∫ B^T (|u| I + u u^T / |u|) B dA  (symmetric, <= 0),
//   J_c = [[0, f M, 0], [-f M, 0, 0], [0, 0, 0]].
// Then positions move with the new velocity: x_{n+1} = x_n + dt W_{n+1}.
// Steady states (F = 0) are reproduced exactly; transients are first order
// in dt for the drag and second order for Coriolis (docs/drift.md).
//
// The footprint integrals use a fixed quadrature in the body frame: the fan
// triangles (G, v_i, v_{i+1}) (signed, so exact for non-convex floes),
// each split into 4^level sub-triangles (level 0 by default: the fan
// triangles themselves) with the 6-point degree-4 rule.

#include <cstdint>
#include <span>
#include <vector>

#include "core/floes.hpp"

namespace floesim {

struct DriftParams {
  double rho_water = 1025.0;  // kg/m^3
  double ocean_drag = 5e-3;   // C_w for floes without their own
  double rho_air = 1.341;     // kg/m^3
  double air_drag = 1.7e-3;   // C_a
  double coriolis = 0.0;      // f, 1/s
};

// Quadrature points of the floes, body frame: floe i's are
// [first[i], first[i] + count[i]) of `point` and `weight` (a function of its
// body vertices and the level alone).
//
// Held by band (docs/parallel.md, "The arrays held by band: measured
// (mem27)"): on several ranks a rank drifts only the floes it owns, so it
// keeps the points of the floes it holds (its own and its band) and none of
// the others' (count 0; hold()). The floes' ranges then are not in floe
// order: a floe entering the held set gets its range appended at the end
// (its own points, built from its vertices, which every rank keeps), a floe
// leaving it leaves a dead range behind, and the arrays are compacted (the
// live ranges copied in floe order) when the dead points exceed half the
// live ones or an append would outgrow the capacity. With CSR offsets
// instead, an entering floe would shift every later floe's points; here the
// per-floe cost of the layout is one more array (12 B a floe: the offset
// and a count). A floe's points are the same values wherever they lie, so
// the drag reads the same bits.
struct FootprintQuadrature {
  int level = 0;                     // each fan triangle split into 4^level (build_footprint_quadrature)
  std::vector<std::size_t> first;    // per floe: its first point
  std::vector<std::uint32_t> count;  // per floe: its points (0: not held, or not built yet)
  std::vector<Vec2> point;           // m, body frame (relative to the centroid)
  std::vector<double> weight;        // m^2 (signed); a floe's sum to its area
  std::size_t dead = 0;              // points in no floe's range (left by floes no longer held)

  std::span<const Vec2> points(std::size_t i) const { return {point.data() + first[i], count[i]}; }
  std::span<const double> weights(std::size_t i) const { return {weight.data() + first[i], count[i]}; }
  bool has(std::size_t i) const { return i < count.size() && count[i] > 0; }
  // Keeps the points of the floes `held` marks (empty: every floe) and of
  // no other: drops the others' ranges, builds the held floes' that have
  // none (a floe entering the held set; the floes added since the last
  // call, e.g. a split's pieces, start with none), compacts when due.
  // Floes whose vertices changed (Floes::replace) must be forgotten first
  // (forget()).
  void hold(const Floes& floes, std::span<const std::uint8_t> held);
  // Builds the ranges of the listed floes that have none (those come to
  // this rank since the last hold(), by a move of the cuts), for these
  // floes (hold() called for them).
  void ensure(const Floes& floes, std::span<const std::uint32_t> which);
  // Every range dropped and the arrays freed (the floes changed).
  void forget();
  // What these arrays allocate, against the held floes' entries
  // (core/floe_bytes.hpp; `held` empty: every floe).
  FloeBytes memory(std::span<const std::uint8_t> held) const;
};
// Every floe's points, in floe order.
FootprintQuadrature build_footprint_quadrature(const Floes& floes, int level = 0);

// Force and Jacobian of ocean + air drag on floe i (world frame, about G).
struct DragLoad {
  Eigen::Vector3d force = Eigen::Vector3d::Zero();     // Fx, Fy (N), torque (N m)
  Eigen::Matrix3d jacobian = Eigen::Matrix3d::Zero();  // dF/dW of the ocean drag
};
// `water` gives U_w at each quadrature point of floe i (world frame), or is
// empty for the uniform `current`.
DragLoad drag_load(const Floes& floes, const FootprintQuadrature& q, std::size_t i,
                   const DriftParams& p, const Vec2& current, const Vec2& wind,
                   std::span<const Vec2> water = {});

// Velocities W_n -> W_{n+1} of floes [begin, end) over dt as stated above
// (positions are moved separately, after collisions, by advance_positions).
// Static floes do not move. `floe_current`, if not empty, replaces `current`
// floe by floe (the current plus the waves' orbital velocity under each floe).
void drift_velocities(Floes& floes, const FootprintQuadrature& q, const DriftParams& p,
                      const Vec2& current, const Vec2& wind, double dt, std::size_t begin, std::size_t end,
                      std::span<const Vec2> floe_current = {});
// The same for the floes listed in `which` (e.g. a rank's own floes).
void drift_velocities(Floes& floes, const FootprintQuadrature& q, const DriftParams& p,
                      const Vec2& current, const Vec2& wind, double dt, std::span<const std::uint32_t> which,
                      std::span<const Vec2> floe_current = {});

// x_{n+1} = x_n + dt W for floes [begin, end).
void advance_positions(Floes& floes, double dt, std::size_t begin, std::size_t end);

}  // namespace floesim
