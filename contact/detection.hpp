#pragma once
// Which floes are near each other, how far apart, and where they touch.
//
// Broad phase: world bounding boxes, floe i's inflated by a pad
// p_i = reach_i + xi/2, listed in the cells of a uniform grid (cell side the
// mean box size; cells hashed by sorting): O(n log n + pairs). Two floes become a candidate pair when their padded
// boxes overlap; so a pair that is not a candidate is more than
// reach_a + reach_b + xi apart, and stays out of contact as long as each floe
// moves less than its reach (the time loop checks that, contact/substep.hpp).
// In a periodic domain a floe whose box crosses the domain's edge is also
// entered shifted by the period, so pairs across the seam are found with the
// shift to apply.
//
// Narrow phase (measure_pair), per candidate pair, with a range r_ab within
// which it is measured vertex by vertex (exact_range: xi plus how far the two
// floes' points can close on each other within the horizon, so a pair beyond
// it cannot come within xi during the horizon).
//   * Pairs whose (unpadded) boxes, or whose convex parts, are further apart
//     than r_ab along an axis get that separation as a lower bound ("axis").
//   * Closer parts: separation test (separating axes of both parts);
//     overlapping parts give distance 0 and `overlap = true`. Otherwise every
//     vertex v of one part and its closest point q on the other part's
//     boundary: the distance is the least |q - v| (for disjoint convex
//     polygons the minimum is reached at a vertex of one of them). A vertex
//     nearer than r_ab is a witness (v, q, N = (q - v)/|q - v|): the other
//     part lies behind the line through q normal to N, so v's distance to
//     that line, moving with the other floe, bounds v's distance from below
//     (step_limit.hpp). Vertices beyond r_ab only give their least distance
//     ("far").
//   * Contact points: every vertex v of one floe whose closest boundary point
//     q of the other is nearer than the collision distance xi gives one point
//     P = (v + q)/2 with the unit normal N along q - v (pointing from floe a to
//     floe b). An edge–edge contact thus gives its two end points; a
//     vertex–vertex contact found from both sides is kept once.

#include <algorithm>
#include <cstdint>
#include <limits>
#include <vector>

#include "contact/shapes.hpp"

namespace floesim::contact {

// The domain: open plane, or a periodic box (a torus).
struct Domain {
  bool periodic = false;
  double xmin = 0.0, xmax = 0.0, ymin = 0.0, ymax = 0.0;  // m
  double width() const { return xmax - xmin; }
  double height() const { return ymax - ymin; }
};

// Which floes a detection poses (and enters in the broad phase), and which of
// the pairs found among them it keeps and measures: those whose floe a (the
// lower index) has keep[a] != 0. A pair is found only when both its floes are
// posed, so a caller that keeps the pairs of floe a must pose every floe whose
// padded box can reach a's (parallel/place.hpp's halo). The pairs kept are
// then the serial detection's pairs of those floes, measured the same way.
struct DetectionSubset {
  std::vector<std::uint32_t> posed;  // ascending floe indices
  std::vector<std::uint8_t> keep;    // per floe; empty: the whole detection (posed is ignored)
  bool everything() const { return keep.empty(); }
};

struct DetectionOptions {
  double collision_distance = 0.01;  // xi, m: contact points below this gap
  // How far each floe may move before the pair list must be rebuilt (m): per
  // floe when `reach` is given (one entry per floe), else search_margin/2 - xi/2
  // for all.
  double search_margin = 0.01;       // m
  std::vector<double> reach;         // m, per floe (optional)
  double reach_of(std::size_t floe) const {
    return reach.empty() ? std::max(0.0, 0.5 * search_margin - 0.5 * collision_distance) : reach[floe];
  }
  double horizon = 0.0;              // s: pairs are measured vertex by vertex within exact_range(horizon)
  Domain domain;
  // A part of the detection (parallel/place.hpp: a rank detects by place).
  // Default: every floe posed, every pair kept.
  DetectionSubset subset;
};

// A vertex of one floe and its closest point on the other (world; b's shifted).
struct Witness {
  Vec2 pa = Vec2::Zero(), pb = Vec2::Zero();  // on a, on b (one of them is the vertex)
  Vec2 normal = Vec2::UnitX();                // unit, (pb - pa)/distance
  double distance = 0.0;                      // m
  bool vertex_of_b = false;                   // the vertex is b's (pb), the closest point on a's boundary
};

// A pair of floes whose padded boxes overlap.
struct NearPair {
  std::uint32_t a = 0, b = 0;  // floe indices, a < b
  Vec2 shift = Vec2::Zero();   // periodic shift added to floe b's positions
  // Distance between the floes (0 if they overlap): exact when `exact`, else a
  // lower bound (the axis separation).
  double distance = 0.0;       // m
  Vec2 normal = Vec2::UnitX(); // unit, from a towards b (closest points, or the axis)
  Vec2 pa = Vec2::Zero(), pb = Vec2::Zero();  // closest points when exact (world; pb shifted)
  bool exact = false;
  bool overlap = false;
  // Lower bounds: the least axis separation (infinite if none; when several
  // parts gave one, along different axes, `axis_any` says the axis is not
  // known), and the least distance of the vertices that are not witnesses.
  double axis_distance = std::numeric_limits<double>::infinity();
  Vec2 axis_normal = Vec2::UnitX();
  bool axis_any = false;
  double far_distance = std::numeric_limits<double>::infinity();
  // Its witnesses and contact points: [first, first + count) of the lists it
  // was measured into.
  std::uint32_t first_witness = 0, witness_count = 0;
  std::uint32_t first_contact = 0, contact_count = 0;
};

// The order of detect()'s pairs: by floe a, then b, then b's shift (x, then
// y). For anything with fields a, b and shift (the candidates, NearPair).
template <class P>
bool pair_before(const P& x, const P& y) {
  if (x.a != y.a) return x.a < y.a;
  if (x.b != y.b) return x.b < y.b;
  if (x.shift.x() != y.shift.x()) return x.shift.x() < y.shift.x();
  return x.shift.y() < y.shift.y();
}

struct ContactPoint {
  std::uint32_t a = 0, b = 0;  // floes, a < b; the normal points from a to b
  Vec2 point = Vec2::Zero();   // m, world (in a's image of the domain)
  Vec2 normal = Vec2::UnitX(); // unit
  double gap = 0.0;            // m, >= 0
  Vec2 shift = Vec2::Zero();   // periodic shift of floe b for this contact
  bool speculative = false;    // gap >= xi: may close, but not below xi/2 within the step (impulse.hpp)
  bool vertex_of_b = false;    // the point pairs b's vertex with a's boundary (else a's vertex, b's boundary)
  double turning = 0.0;        // m: closing over the speculative step beyond the linearised gap (step_limit.hpp)
};

struct Detection {
  std::vector<NearPair> pairs;        // every candidate pair, measured
  std::vector<ContactPoint> contacts; // contact points of pairs closer than xi
  std::vector<Witness> witnesses;     // of the pairs measured vertex by vertex
  std::vector<double> reach;          // m, per floe: the reach the pair list was built for
};

struct Box {
  double xmin, xmax, ymin, ymax;
  bool overlaps(const Box& o) const {
    return xmin <= o.xmax && o.xmin <= xmax && ymin <= o.ymax && o.ymin <= ymax;
  }
};

// The floes' convex parts in world coordinates at their present poses (same
// layout as CollisionShapes::vertices), with part and floe bounding boxes.
// update() re-poses one floe, so a few moving floes cost only themselves.
class PosedShapes {
public:
  PosedShapes() = default;
  PosedShapes(const Floes& floes, const CollisionShapes& shapes);  // all floes posed
  // Only `which` posed (the others' parts and boxes are not set: not to be read).
  PosedShapes(const Floes& floes, const CollisionShapes& shapes, std::span<const std::uint32_t> which);
  void update(const Floes& floes, std::size_t floe);
  std::span<const Vec2> part(std::size_t p) const {
    return {world_.data() + shapes_->vertex_offsets[p], shapes_->vertex_offsets[p + 1] - shapes_->vertex_offsets[p]};
  }
  const Box& part_box(std::size_t p) const { return part_box_[p]; }
  const Box& floe_box(std::size_t i) const { return floe_box_[i]; }
  const CollisionShapes& shapes() const { return *shapes_; }

private:
  const CollisionShapes* shapes_ = nullptr;
  std::vector<Vec2> world_;
  std::vector<Box> part_box_, floe_box_;
};

// xi plus the distance floes a and b can close within `horizon` at their
// present velocities: |V_b - V_a| + |omega_a| R_a + |omega_b| R_b bounds the
// relative speed of any two of their points.
double exact_range(const Floes& floes, const CollisionShapes& shapes, std::uint32_t a, std::uint32_t b,
                   double horizon, double collision_distance);

// Measures the pair (a, b) with b shifted by `shift` at the poses of `posed`
// (narrow phase above, vertex by vertex within `range`); appends its contact
// points and witnesses to the lists.
NearPair measure_pair(const PosedShapes& posed, std::uint32_t a, std::uint32_t b, const Vec2& shift,
                      double collision_distance, double range, std::vector<ContactPoint>& contacts,
                      std::vector<Witness>& witnesses);

Detection detect(const Floes& floes, const CollisionShapes& shapes, const DetectionOptions& options);

}  // namespace floesim::contact
