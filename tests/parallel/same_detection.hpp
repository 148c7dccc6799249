#pragma once
// The contact detection compared bit for bit, field by field (structs'
// padding bytes are not values; doubles by their bits, so -0 and +0 differ),
// shared by the tests of the detection's parts and merges.
#include <cstring>
#include <vector>

#include "contact/detection.hpp"
#include "contact/impulse.hpp"
#include "core/geometry.hpp"

namespace floesim::test {

inline bool bits(double a, double b) { return std::memcmp(&a, &b, sizeof(double)) == 0; }
inline bool bits(const Vec2& a, const Vec2& b) { return bits(a.x(), b.x()) && bits(a.y(), b.y()); }
inline bool same(const contact::NearPair& x, const contact::NearPair& y) {
  return x.a == y.a && x.b == y.b && bits(x.shift, y.shift) && bits(x.distance, y.distance) &&
         bits(x.normal, y.normal) && bits(x.pa, y.pa) && bits(x.pb, y.pb) && x.exact == y.exact &&
         x.overlap == y.overlap && bits(x.axis_distance, y.axis_distance) && bits(x.axis_normal, y.axis_normal) &&
         x.axis_any == y.axis_any && bits(x.far_distance, y.far_distance) && x.first_witness == y.first_witness &&
         x.witness_count == y.witness_count && x.first_contact == y.first_contact && x.contact_count == y.contact_count;
}
inline bool same(const contact::ContactPoint& x, const contact::ContactPoint& y) {
  return x.a == y.a && x.b == y.b && bits(x.point, y.point) && bits(x.normal, y.normal) && bits(x.gap, y.gap) &&
         bits(x.shift, y.shift) && x.speculative == y.speculative && x.vertex_of_b == y.vertex_of_b &&
         bits(x.turning, y.turning);
}
inline bool same(const contact::Witness& x, const contact::Witness& y) {
  return bits(x.pa, y.pa) && bits(x.pb, y.pb) && bits(x.normal, y.normal) && bits(x.distance, y.distance) &&
         x.vertex_of_b == y.vertex_of_b;
}
inline bool same(const contact::GroupEdge& x, const contact::GroupEdge& y) {
  return x.a == y.a && x.b == y.b && x.flags == y.flags && x.owner_a == y.owner_a && x.owner_b == y.owner_b;
}
template <class T>
inline bool same_lists(const std::vector<T>& a, const std::vector<T>& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t k = 0; k < a.size(); ++k)
    if (!same(a[k], b[k])) return false;
  return true;
}
inline bool same_detection(const contact::Detection& a, const contact::Detection& b) {
  return same_lists(a.pairs, b.pairs) && same_lists(a.contacts, b.contacts) && same_lists(a.witnesses, b.witnesses);
}
}  // namespace floesim::test
