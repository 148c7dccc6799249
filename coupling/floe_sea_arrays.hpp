#pragma once
// FloeSeaContact's arrays of one entry a floe (coupling/floe_sea.hpp), in
// groups of one life. The rule core/floes.hpp states for Floes (every
// per-floe array handled where the floes change and counted in memory())
// holds for a group by construction: a group is a struct whose members are
// all std::vectors indexed by floe, and whose static `arrays(g)` ties every
// one of them; it is sized (fit_floes) and counted (floe_group_bytes)
// through that list alone, so an array is sized and counted with its group
// or not at all. lists_every_array checks that the list holds every member
// (the members being vectors only, their sizes sum to the struct's), and
// each group below is static_asserted with it: an array added to a group
// and left out of its list does not build.
//
// What each entry means is said at the group's use in FloeSeaContact; the
// groups' lives (where FloeSeaContact sizes them):
//   FloeSeaConstants    from the floes' constants; sized with the floes (floes_changed)
//   FloeSeaKicks        the loads the kicks apply; sized and zeroed with the floes
//   FloeSeaEvaluated    what an evaluation of the contact poses and finds per floe; sized with the floes
//   FloeSeaImplicit     the implicit step's; sized at each implicit step (empty with the explicit kicks)
//   FloeSeaSerialPlaces by owner, the boxes of the floes this rank has; sized at each order_by_owner

#include <cstddef>
#include <cstdint>
#include <tuple>
#include <type_traits>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "core/floe_bytes.hpp"
#include "core/geometry.hpp"
#include "coupling/footprint.hpp"
#include "coupling/penalty_step.hpp"
#include "parallel/cell_routes.hpp"

namespace floesim {

// Loads of the sea on floe i, world frame.
struct FloeSeaLoad {
  Eigen::Vector3d vertical = Eigen::Vector3d::Zero();    // Fz (N, weight included), moments about G (N m)
  Eigen::Vector3d horizontal = Eigen::Vector3d::Zero();  // Fx, Fy (N), torque about z (N m)
};

// Every array of the group to n entries, the entries of floes below the old
// size kept (the new ones value-initialised: the caller sets them). Growing,
// an array gets exactly n places (not the doubling of a plain resize): the
// floes' count changes only at a split or a restore.
template <class Group>
void fit_floes(Group& g, std::size_t n) {
  std::apply(
      [n](auto&... v) {
        ((v.capacity() < n ? v.reserve(n) : void()), ...);
        (v.resize(n), ...);
      },
      Group::arrays(g));
}

// The group's bytes (core/floe_bytes.hpp): its arrays' capacity, and of
// `held` floes' entries (an empty array, unused in this run, none).
template <class Group>
FloeBytes floe_group_bytes(const Group& g, std::size_t held) {
  FloeBytes b;
  std::apply([&](const auto&... v) { ((b += per_floe_bytes(v, held)), ...); }, Group::arrays(g));
  return b;
}

namespace detail {
template <class Group>
using FloeArrayList = decltype(Group::arrays(std::declval<Group&>()));
template <class Group, class F, std::size_t... I>
constexpr std::size_t sum_over_arrays(F f, std::index_sequence<I...>) {
  using List = FloeArrayList<Group>;
  return (std::size_t{0} + ... + f(std::type_identity<std::remove_cvref_t<std::tuple_element_t<I, List>>>{}));
}
template <class Group, class F>
constexpr std::size_t sum_over_arrays(F f) {
  return sum_over_arrays<Group>(f, std::make_index_sequence<std::tuple_size_v<FloeArrayList<Group>>>{});
}
}  // namespace detail

// One floe's entry over the group's arrays (bytes).
template <class Group>
constexpr std::size_t floe_entry_bytes() {
  return detail::sum_over_arrays<Group>([](auto t) { return sizeof(typename decltype(t)::type::value_type); });
}

// Whether Group::arrays lists every member of the group (see the top).
template <class Group>
constexpr bool lists_every_array() {
  return detail::sum_over_arrays<Group>([](auto t) { return sizeof(typename decltype(t)::type); }) == sizeof(Group);
}

// From the floes' constants.
struct FloeSeaConstants {
  std::vector<std::uint8_t> dynamic;           // 1: the sea moves the floe (not static)
  std::vector<std::uint8_t> tilt;              // slopes resisted: 0 none, 1 pitch, 2 pitch and roll
  std::vector<double> bottom0;                 // z0_i, m
  std::vector<Eigen::Matrix2d> body_moments;   // rho h ∫ r r^T in the body frame
  static auto arrays(auto& g) { return std::tie(g.dynamic, g.tilt, g.bottom0, g.body_moments); }
};
static_assert(lists_every_array<FloeSeaConstants>());

// The loads the kicks apply (kick_floes).
struct FloeSeaKicks {
  // The last evaluation's (with the implicit step's step_mean loads, the
  // horizontal part is the last step's mean).
  std::vector<FloeSeaLoad> loads;
  // Implicit integrator: the last step's mean horizontal load, and the
  // impulse the present step's first half kick applied.
  std::vector<Eigen::Vector3d> step_horizontal, first_half;
  static auto arrays(auto& g) { return std::tie(g.loads, g.step_horizontal, g.first_half); }
};
static_assert(lists_every_array<FloeSeaKicks>());

// What an evaluation of the contact poses and finds per floe.
struct FloeSeaEvaluated {
  std::vector<FloePose> poses;  // where the next placement puts each floe (the floes it reads)
  std::vector<Vec2> water;      // incident velocity under each floe, with the loads
  std::vector<Vec2> slope;      // the bottom slope the horizontal loads are taken at
  std::vector<double> wetted;   // sum psi_c a_c [delta_c]^+ over the floe's area pieces
  static auto arrays(auto& g) { return std::tie(g.poses, g.water, g.slope, g.wetted); }
};
static_assert(lists_every_array<FloeSeaEvaluated>());

// The implicit step's.
struct FloeSeaImplicit {
  std::vector<VerticalInertia> inertia;     // on the floe's vertical DOFs, at its yaw
  std::vector<double> yaw;                  // gather_tilted_yaw's (the tilted floes of order_)
  std::vector<Eigen::Vector3d> free_bottom;  // (z, a) at t + h with no penalty
  static auto arrays(auto& g) { return std::tie(g.inertia, g.yaw, g.free_bottom); }
};
static_assert(lists_every_array<FloeSeaImplicit>());

// By owner (order_by_owner): each floe's box of its pieces' cells
// (parallel::CellBox, first_cell kNone: none, or not sent to this rank).
struct FloeSeaSerialPlaces {
  std::vector<parallel::CellBox> box;
  static auto arrays(auto& g) { return std::tie(g.box); }
};
static_assert(lists_every_array<FloeSeaSerialPlaces>());

}  // namespace floesim
