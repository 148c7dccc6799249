#pragma once
// Splitting a floe along a straight through crack (MODEL.md §6): the floe's
// polygon is cut along the crack's chord (crack.hpp) into two polygons that
// become two floes carrying on the parent's rigid motion.
//
// Conservation. The pieces tile the parent exactly, so their masses add up
// to its mass and their mass centres average to its centre. Each piece k
// (mass m_k, yaw inertia I_k, centroid G_k) takes the parent's motion
// (V, omega) as a rigid body: v_k = V + omega' k x (G_k - G), omega_k = omega'.
// Then sum m_k v_k = M V (momentum) and the angular momentum about G is
// omega' sum (I_k + m_k |G_k - G|^2) = omega' I' (parallel axes).
//
// Opening. Pieces that touch would be in contact (or overlap by round-off)
// at once, so they are moved apart along the crack's normal by `gap` in
// all, each by the other's mass fraction (m_0 d_0 + m_1 d_1 = 0: the mass
// centre stays put). That raises I' a little above the parent's I, so
// omega' = omega I / I' keeps the angular momentum exact (the kinetic
// energy falls by the same tiny fraction). Heave and its rate follow the
// parent's bottom plane at the new centroids; tilts are the parent's.

#include <array>
#include <optional>

#include "contact/fracture/crack.hpp"
#include "core/floe.hpp"
#include "core/floes.hpp"

namespace floesim::fracture {

struct SplitPlan {
  std::array<FloeShape, 2> shapes;     // body frames: the parent's orientation, origin at each centroid
  std::array<Vec2, 2> centroid;        // m, in the parent's body frame, after the opening
  Vec2 normal = Vec2::UnitY();         // the crack's normal (parent body frame), from piece 0 to 1
  double thickness = 1.0, density = 917.0, ocean_drag = -1.0;
};

// The two pieces of floe i (not static) cut along `chord` (in its body
// frame), opened by `gap` (m). nullopt if the chord does not cut the floe in
// two valid polygons or a piece's area is below `min_area` (m^2).
std::optional<SplitPlan> plan_split(const Floes& floes, std::size_t i, const Chord& chord, double gap,
                                    double min_area);

// The pieces' states for a parent state (as conservation above requires).
std::array<FloeState, 2> piece_states(const SplitPlan& plan, const FloeState& parent, double parent_inertia_z);

// Floe i becomes piece 0 (with a new number), piece 1 is appended; their
// states are `states`. Returns the index of piece 1.
std::size_t apply_split(Floes& floes, std::size_t i, const SplitPlan& plan, const std::array<FloeState, 2>& states);

}  // namespace floesim::fracture
