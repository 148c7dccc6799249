#pragma once
// Which floes are near each other, how far apart, and where they touch.
//
// Broad phase: world bounding boxes, each inflated by half a search margin,
// sorted along x and swept (sweep and prune): O(n log n + pairs). In a periodic
// domain a floe whose box crosses the domain's edge is also entered shifted by
// the period, so pairs across the seam are found with the shift to apply.
//
// Pairs whose (unpadded) boxes are more than xi apart get the box gap as a
// lower bound on their distance. Closer pairs get the narrow phase, per pair of
// convex parts:
//   * separation test (separating axes of both parts); overlapping parts give
//     distance 0 and `overlap = true`;
//   * distance = min over the vertices of each part of the distance to the
//     other part's boundary (for disjoint convex polygons the minimum is
//     reached at a vertex of one of them);
//   * contact points: every vertex v of one floe whose closest boundary point q
//     of the other is nearer than the collision distance xi gives one point
//     P = (v + q)/2 with the unit normal N along q - v (pointing from floe a to
//     floe b). An edge–edge contact thus gives its two end points; a
//     vertex–vertex contact found from both sides is kept once.

#include <cstdint>
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

struct DetectionOptions {
  double collision_distance = 0.01;  // xi, m: contact points below this gap
  double search_margin = 0.01;       // m: pairs whose boxes are within this are measured
  Domain domain;
};

// A pair of floes whose boxes came within the search margin.
struct NearPair {
  std::uint32_t a = 0, b = 0;  // floe indices, a < b
  Vec2 shift = Vec2::Zero();   // periodic shift added to floe b's positions
  // Distance between the floes (0 if they overlap). When `exact` is false it is
  // a lower bound: the gap between their bounding boxes along `normal` (pairs
  // whose boxes are further apart than the collision distance are not measured
  // in detail).
  double distance = 0.0;       // m
  Vec2 normal = Vec2::UnitX(); // unit, from a towards b: the gap closes at -normal . (V_b - V_a)
  Vec2 pa = Vec2::Zero(), pb = Vec2::Zero();  // closest points when exact (world; pb shifted)
  bool exact = false;
  bool overlap = false;
};

struct ContactPoint {
  std::uint32_t a = 0, b = 0;  // floes, a < b; the normal points from a to b
  Vec2 point = Vec2::Zero();   // m, world (in a's image of the domain)
  Vec2 normal = Vec2::UnitX(); // unit
  double gap = 0.0;            // m, >= 0
  Vec2 shift = Vec2::Zero();   // periodic shift of floe b for this contact
};

struct Detection {
  std::vector<NearPair> pairs;        // every pair measured
  std::vector<ContactPoint> contacts; // contact points of pairs closer than xi
};

Detection detect(const Floes& floes, const CollisionShapes& shapes, const DetectionOptions& options);

}  // namespace floesim::contact
