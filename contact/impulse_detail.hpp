#pragma once
// What impulse.cpp and step_collisions.cpp share (private to contact/):
// the contact components' disjoint sets and the approach speed of a
// contact's two points.
#include <cstdint>
#include <span>
#include <unordered_map>
#include <vector>

#include "contact/detection.hpp"
#include "contact/impulse.hpp"
#include "contact/jam.hpp"

namespace floesim::contact::detail {

// Disjoint sets over the floes that have contacts (local indices), so a call
// costs the size of its contact list, not of the pack.
struct Components {
  DisjointSets sets;
  std::unordered_map<std::uint32_t, std::uint32_t> local;  // floe -> local index
  std::size_t size() const { return sets.size(); }
  // The local index of floe f, added on first sight.
  std::uint32_t node(std::uint32_t f) {
    auto [it, fresh] = local.emplace(f, 0u);
    if (fresh) it->second = sets.add();
    return it->second;
  }
  // The root of floe f's component; f must have been seen.
  std::uint32_t root_of(std::uint32_t f) { return sets.find(local.at(f)); }
  std::uint32_t find(std::uint32_t i) { return sets.find(i); }
  void join(std::uint32_t a, std::uint32_t b) { sets.join(a, b); }
};

// record_impulses (impulse.hpp), and for each load it appends the index of
// its contact in `contacts` into `contact_of` (a share's record: the loads'
// places follow their contacts').
void record_impulses(ImpulseRecord& record, const Floes& floes, std::span<const ContactPoint> contacts,
                     std::span<const ContactImpulse> impulses, std::span<const std::uint8_t> sustained,
                     std::vector<std::uint32_t>* contact_of);

// Velocity of floe f's point p (world, in f's own image).
inline Vec2 point_velocity(const FloeState& s, const Vec2& p) { return arm_velocity(s, p - Vec2{s.x, s.y}); }
// The normal approach speed of a contact's two points (> 0: approaching),
// with the floes' velocities taken from `s` (the positions are the present
// ones: velocities from the start of the step are compared at the same points).
inline double approach(const Floes& floes, std::span<const FloeState> s, std::uint32_t a, std::uint32_t b,
                       const Vec2& pa, const Vec2& pb_own, const Vec2& normal) {
  FloeState va = s[a], vb = s[b];
  va.x = floes.state[a].x; va.y = floes.state[a].y;
  vb.x = floes.state[b].x; vb.y = floes.state[b].y;
  return -normal.dot(point_velocity(vb, pb_own) - point_velocity(va, pa));
}

}  // namespace floesim::contact::detail
