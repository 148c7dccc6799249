#include "core/geometry.hpp"

#include <algorithm>
#include <array>
#include <cmath>

namespace floesim {

PolygonMoments polygon_moments(std::span<const Vec2> v) {
  PolygonMoments m;
  const std::size_t n = v.size();
  // Accumulate relative to the first vertex to limit cancellation for polygons
  // far from the origin, then shift the moments back (parallel-axis rules).
  const Vec2 o = n ? v[0] : Vec2::Zero();
  for (std::size_t i = 0; i < n; ++i) {
    const Vec2 a = v[i] - o, b = v[(i + 1) % n] - o;
    const double c = cross(a, b);
    m.area += c;
    m.sx += c * (a.x() + b.x());
    m.sy += c * (a.y() + b.y());
    m.sxx += c * (a.x() * a.x() + a.x() * b.x() + b.x() * b.x());
    m.syy += c * (a.y() * a.y() + a.y() * b.y() + b.y() * b.y());
    m.sxy += c * (a.x() * b.y() + 2.0 * a.x() * a.y() + 2.0 * b.x() * b.y() + b.x() * a.y());
  }
  m.area /= 2.0;
  m.sx /= 6.0;
  m.sy /= 6.0;
  m.sxx /= 12.0;
  m.syy /= 12.0;
  m.sxy /= 24.0;
  // Moments about the origin from moments about o: x = x' + o.
  PolygonMoments r;
  r.area = m.area;
  r.sx = m.sx + o.x() * m.area;
  r.sy = m.sy + o.y() * m.area;
  r.sxx = m.sxx + 2.0 * o.x() * m.sx + o.x() * o.x() * m.area;
  r.syy = m.syy + 2.0 * o.y() * m.sy + o.y() * o.y() * m.area;
  r.sxy = m.sxy + o.x() * m.sy + o.y() * m.sx + o.x() * o.y() * m.area;
  return r;
}

double signed_area(std::span<const Vec2> v) {
  double a = 0.0;
  for (std::size_t i = 0; i < v.size(); ++i) a += cross(v[i], v[(i + 1) % v.size()]);
  return a / 2.0;
}

namespace {
// 16-point Gauss–Legendre nodes and weights on [-1, 1] (symmetric halves).
constexpr std::array<double, 8> kGaussX = {0.0950125098376374, 0.2816035507792589,
                                           0.4580167776572274, 0.6178762444026438,
                                           0.7554044083550030, 0.8656312023878318,
                                           0.9445750230732326, 0.9894009349916499};
constexpr std::array<double, 8> kGaussW = {0.1894506104550685, 0.1826034150449236,
                                           0.1691565193950025, 0.1495959888165767,
                                           0.1246289712555339, 0.0951585116824928,
                                           0.0622535239386479, 0.0271524594117541};
}  // namespace

double polar_moment3(std::span<const Vec2> v, const Vec2& c) {
  // Fan triangle (c, a, b): the edge a->b is the line at distance d from c with
  // foot angle phi, r_edge(θ) = d / cos(θ - phi). The signed angle sweep makes
  // the fan sum exact for any simple polygon (overlapping fans cancel).
  double total = 0.0;
  const std::size_t n = v.size();
  for (std::size_t i = 0; i < n; ++i) {
    const Vec2 a = v[i] - c, b = v[(i + 1) % n] - c;
    const double ta = std::atan2(a.y(), a.x());
    double sweep = std::atan2(cross(a, b), a.dot(b));  // signed angle a -> b
    if (std::abs(sweep) < 1e-300) continue;
    const Vec2 e = b - a;
    const double len = e.norm();
    if (len == 0.0) continue;
    const double d = cross(a, e) / len;  // signed distance from c to the edge line
    const double phi = std::atan2(e.x(), -e.y());  // direction of the edge's normal
    // Split the sweep so each Gauss panel stays away from the edge's ends.
    const int panels = 4;
    for (int p = 0; p < panels; ++p) {
      const double t0 = ta + sweep * p / panels, t1 = ta + sweep * (p + 1) / panels;
      const double mid = 0.5 * (t0 + t1), half = 0.5 * (t1 - t0);
      for (std::size_t k = 0; k < kGaussX.size(); ++k) {
        for (double s : {-1.0, 1.0}) {
          const double th = mid + s * half * kGaussX[k];
          const double r = d / std::cos(th - phi);
          total += kGaussW[k] * half * std::pow(std::abs(r), 5) / 5.0;
        }
      }
    }
  }
  return std::abs(total);
}

namespace {
int orientation(const Vec2& a, const Vec2& b, const Vec2& c) {
  const double v = cross(b - a, c - a);
  const double scale = (b - a).norm() * (c - a).norm();
  if (std::abs(v) <= 1e-14 * scale) return 0;
  return v > 0 ? 1 : -1;
}
bool on_segment(const Vec2& a, const Vec2& b, const Vec2& p) {
  return std::min(a.x(), b.x()) <= p.x() && p.x() <= std::max(a.x(), b.x()) &&
         std::min(a.y(), b.y()) <= p.y() && p.y() <= std::max(a.y(), b.y());
}
bool segments_intersect(const Vec2& p1, const Vec2& p2, const Vec2& q1, const Vec2& q2) {
  const int o1 = orientation(p1, p2, q1), o2 = orientation(p1, p2, q2);
  const int o3 = orientation(q1, q2, p1), o4 = orientation(q1, q2, p2);
  if (o1 != o2 && o3 != o4 && o1 != 0 && o2 != 0 && o3 != 0 && o4 != 0) return true;
  if (o1 == 0 && on_segment(p1, p2, q1)) return true;
  if (o2 == 0 && on_segment(p1, p2, q2)) return true;
  if (o3 == 0 && on_segment(q1, q2, p1)) return true;
  if (o4 == 0 && on_segment(q1, q2, p2)) return true;
  return false;
}
}  // namespace

std::optional<std::pair<std::size_t, std::size_t>> find_self_intersection(std::span<const Vec2> v) {
  const std::size_t n = v.size();
  for (std::size_t i = 0; i < n; ++i) {
    const Vec2 &a = v[i], &b = v[(i + 1) % n];
    if ((b - a).squaredNorm() == 0.0) return std::pair{i, (i + 1) % n};  // repeated vertex
    for (std::size_t j = i + 1; j < n; ++j) {
      const Vec2 &c = v[j], &d = v[(j + 1) % n];
      const bool adjacent = (j == i + 1) || (i == 0 && j == n - 1);
      if (adjacent) {
        // Neighbours share one vertex; they are bad only if they fold back onto
        // each other (collinear and overlapping).
        const Vec2 shared = (j == i + 1) ? b : a;
        const Vec2 p = (j == i + 1) ? a : b;
        const Vec2 q = (j == i + 1) ? d : c;
        if (orientation(p, shared, q) == 0 && (p - shared).dot(q - shared) > 0.0)
          return std::pair{i, j};
        continue;
      }
      if (segments_intersect(a, b, c, d)) return std::pair{i, j};
    }
  }
  return std::nullopt;
}

bool point_in_polygon(std::span<const Vec2> v, const Vec2& p) {
  bool inside = false;
  const std::size_t n = v.size();
  for (std::size_t i = 0, j = n - 1; i < n; j = i++) {
    if ((v[i].y() > p.y()) != (v[j].y() > p.y())) {
      const double x = v[j].x() + (p.y() - v[j].y()) * (v[i].x() - v[j].x()) / (v[i].y() - v[j].y());
      if (p.x() < x) inside = !inside;
    }
  }
  return inside;
}

}  // namespace floesim
