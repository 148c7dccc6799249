#include "coupling/drift.hpp"

#include <Eigen/Dense>
#include <array>
#include <cmath>

namespace floesim {

namespace {
// 6-point degree-4 rule on a triangle (Dunavant 1985): barycentric points and
// weights (weights sum to 1; multiply by the triangle's area).
struct TriRule { double a, b, c, w; };
constexpr std::array<TriRule, 6> kRule = {{
    {0.108103018168070, 0.445948490915965, 0.445948490915965, 0.223381589678011},
    {0.445948490915965, 0.108103018168070, 0.445948490915965, 0.223381589678011},
    {0.445948490915965, 0.445948490915965, 0.108103018168070, 0.223381589678011},
    {0.816847572980459, 0.091576213509771, 0.091576213509771, 0.109951743655322},
    {0.091576213509771, 0.816847572980459, 0.091576213509771, 0.109951743655322},
    {0.091576213509771, 0.091576213509771, 0.816847572980459, 0.109951743655322},
}};

void add_triangle(FootprintQuadrature& q, const Vec2& a, const Vec2& b, const Vec2& c, int level) {
  if (level > 0) {
    const Vec2 ab = 0.5 * (a + b), bc = 0.5 * (b + c), ca = 0.5 * (c + a);
    add_triangle(q, a, ab, ca, level - 1);
    add_triangle(q, ab, b, bc, level - 1);
    add_triangle(q, ca, bc, c, level - 1);
    add_triangle(q, ab, bc, ca, level - 1);
    return;
  }
  const double area = 0.5 * cross(b - a, c - a);  // signed
  for (const TriRule& r : kRule) {
    q.point.push_back(r.a * a + r.b * b + r.c * c);
    q.weight.push_back(r.w * area);
  }
}
}  // namespace

FootprintQuadrature build_footprint_quadrature(const Floes& floes, int level) {
  FootprintQuadrature q;
  for (std::size_t i = 0; i < floes.size(); ++i) {
    const auto v = floes.vertices(i);
    for (std::size_t k = 0; k < v.size(); ++k)
      add_triangle(q, Vec2::Zero(), v[k], v[(k + 1) % v.size()], level);
    q.offsets.push_back(q.point.size());
  }
  return q;
}

DragLoad drag_load(const Floes& floes, const FootprintQuadrature& q, std::size_t i,
                   const DriftParams& p, const Vec2& current, const Vec2& wind,
                   std::span<const Vec2> water) {
  DragLoad load;
  const FloeState& s = floes.state[i];
  const double cw = floes.ocean_drag[i] >= 0.0 ? floes.ocean_drag[i] : p.ocean_drag;
  const double k = p.rho_water * cw;
  const Vec2 V{s.vx, s.vy};
  const double c = std::cos(s.yaw), sn = std::sin(s.yaw);
  const std::size_t begin = q.offsets[i], end = q.offsets[i + 1];
  for (std::size_t j = begin; j < end; ++j) {
    const Vec2& b = q.point[j];
    const Vec2 r{c * b.x() - sn * b.y(), sn * b.x() + c * b.y()};
    const Vec2 kr{-r.y(), r.x()};  // k x r
    const Vec2 U = water.empty() ? current : water[j - begin];
    const Vec2 u = U - (V + s.yaw_rate * kr);
    const double un = u.norm();
    const double w = q.weight[j] * k;
    const Vec2 tau = w * un * u;
    load.force.x() += tau.x();
    load.force.y() += tau.y();
    load.force.z() += kr.dot(tau);
    // A = |u| I + u u^T/|u|  (derivative of |u| u), B = [I | kr].
    if (un > 0.0) {
      Eigen::Matrix2d A = un * Eigen::Matrix2d::Identity() + (u * u.transpose()) / un;
      Eigen::Matrix<double, 2, 3> B;
      B << 1.0, 0.0, kr.x(), 0.0, 1.0, kr.y();
      load.jacobian.noalias() -= w * B.transpose() * A * B;
    }
  }
  // Air drag: uniform stress over the footprint, no torque about G.
  const Vec2 ta = p.rho_air * p.air_drag * wind.norm() * wind * floes.area[i];
  load.force.x() += ta.x();
  load.force.y() += ta.y();
  return load;
}

void drift_velocities(Floes& floes, const FootprintQuadrature& q, const DriftParams& p,
                      const Vec2& current, const Vec2& wind, double dt, std::size_t begin, std::size_t end) {
  for (std::size_t i = begin; i < end; ++i) {
    if (floes.is_static[i]) continue;
    FloeState& s = floes.state[i];
    const double m = floes.mass[i];
    const DragLoad load = drag_load(floes, q, i, p, current, wind);
    // Coriolis -f k x (m V) = f m (vy, -vx).
    const double fm = p.coriolis * m;
    Eigen::Vector3d F = load.force;
    F.x() += fm * s.vy;
    F.y() -= fm * s.vx;
    Eigen::Matrix3d Jc = Eigen::Matrix3d::Zero();
    Jc(0, 1) = fm;
    Jc(1, 0) = -fm;
    Eigen::Matrix3d A = Eigen::Vector3d(m, m, floes.inertia_z[i]).asDiagonal();
    A -= dt * load.jacobian + 0.5 * dt * Jc;
    const Eigen::Vector3d dW = A.partialPivLu().solve(dt * F);
    s.vx += dW.x();
    s.vy += dW.y();
    s.yaw_rate += dW.z();
  }
}

void advance_positions(Floes& floes, double dt, std::size_t begin, std::size_t end) {
  for (std::size_t i = begin; i < end; ++i) {
    if (floes.is_static[i]) continue;
    FloeState& s = floes.state[i];
    s.x += dt * s.vx;
    s.y += dt * s.vy;
    s.yaw += dt * s.yaw_rate;
  }
}

}  // namespace floesim
