#include "coupling/drift.hpp"

#include <Eigen/Dense>
#include <array>
#include <cmath>

#include "core/error.hpp"

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

// The points floe i's range takes: 6 a fan triangle, 4^level of them a vertex.
std::size_t points_of(const Floes& floes, std::size_t i, int level) {
  return kRule.size() * (std::size_t{1} << (2 * level)) * (floes.offsets[i + 1] - floes.offsets[i]);
}

// Appends floe i's points (the fan triangles (G, v_k, v_{k+1})) as its range.
void append_floe(FootprintQuadrature& q, const Floes& floes, std::size_t i) {
  const auto v = floes.vertices(i);
  q.first[i] = q.point.size();
  for (std::size_t k = 0; k < v.size(); ++k) add_triangle(q, Vec2::Zero(), v[k], v[(k + 1) % v.size()], q.level);
  q.count[i] = static_cast<std::uint32_t>(q.point.size() - q.first[i]);
}

// The live ranges copied in floe order into arrays of `capacity` points.
void compact(FootprintQuadrature& q, std::size_t capacity) {
  std::vector<Vec2> point;
  std::vector<double> weight;
  point.reserve(capacity);
  weight.reserve(capacity);
  for (std::size_t i = 0; i < q.count.size(); ++i) {
    if (q.count[i] == 0) continue;
    const std::size_t from = q.first[i];
    q.first[i] = point.size();
    point.insert(point.end(), q.point.begin() + static_cast<std::ptrdiff_t>(from),
                 q.point.begin() + static_cast<std::ptrdiff_t>(from + q.count[i]));
    weight.insert(weight.end(), q.weight.begin() + static_cast<std::ptrdiff_t>(from),
                  q.weight.begin() + static_cast<std::ptrdiff_t>(from + q.count[i]));
  }
  q.point = std::move(point);
  q.weight = std::move(weight);
  q.dead = 0;
}
}  // namespace

FootprintQuadrature build_footprint_quadrature(const Floes& floes, int level) {
  FootprintQuadrature q;
  q.level = level;
  q.first.assign(floes.size(), 0);
  q.count.assign(floes.size(), 0);
  std::size_t total = 0;
  for (std::size_t i = 0; i < floes.size(); ++i) total += points_of(floes, i, level);
  q.point.reserve(total);
  q.weight.reserve(total);
  for (std::size_t i = 0; i < floes.size(); ++i) append_floe(q, floes, i);
  return q;
}

void FootprintQuadrature::forget() {
  const int kept = level;
  *this = FootprintQuadrature();
  level = kept;
}

namespace {
// Room for `needed` more points: compacted when the dead points exceed half
// the live ones (a compaction copies the live points, at most twice the
// dead ones it frees: two copies a dropped point) or when the appends would
// reallocate (the vector's doubling would hold up to twice the points),
// into room for a quarter more than the live and needed points.
void make_room(FootprintQuadrature& q, std::size_t needed) {
  const std::size_t live = q.point.size() - q.dead;
  if (2 * q.dead > live || q.point.size() + needed > q.point.capacity())
    compact(q, live + needed + (live + needed) / 4);
}
}  // namespace

void FootprintQuadrature::hold(const Floes& floes, std::span<const std::uint8_t> held) {
  const std::size_t n = floes.size();
  FLOESIM_ASSERT(held.empty() || held.size() == n);
  first.resize(n, 0);
  count.resize(n, 0);
  std::size_t needed = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const bool keep = held.empty() || held[i] != 0;
    if (!keep && count[i] > 0) {
      dead += count[i];
      count[i] = 0;
    } else if (keep && count[i] == 0) {
      needed += points_of(floes, i, level);
    }
  }
  make_room(*this, needed);
  if (needed == 0) return;
  for (std::size_t i = 0; i < n; ++i)
    if ((held.empty() || held[i] != 0) && count[i] == 0) append_floe(*this, floes, i);
}

void FootprintQuadrature::ensure(const Floes& floes, std::span<const std::uint32_t> which) {
  FLOESIM_ASSERT(count.size() == floes.size());
  std::size_t needed = 0;
  for (const std::uint32_t i : which)
    if (count[i] == 0) needed += points_of(floes, i, level);
  if (needed == 0) return;
  make_room(*this, needed);
  for (const std::uint32_t i : which)
    if (count[i] == 0) append_floe(*this, floes, i);
}

FloeBytes FootprintQuadrature::memory(std::span<const std::uint8_t> held) const {
  std::size_t floes = 0, points = 0;
  for (std::size_t i = 0; i < count.size(); ++i)
    if (held.empty() || (i < held.size() && held[i])) {
      ++floes;
      points += count[i];
    }
  // A layout of the held floes alone: their offsets (one more) and points.
  return {capacity_bytes(first) + capacity_bytes(count) + capacity_bytes(point) + capacity_bytes(weight),
          (floes + 1) * sizeof(std::size_t) + points * (sizeof(Vec2) + sizeof(double))};
}

DragLoad drag_load(const Floes& floes, const FootprintQuadrature& q, std::size_t i,
                   const DriftParams& p, const Vec2& current, const Vec2& wind,
                   std::span<const Vec2> water) {
  DragLoad load;
  const FloeState& s = floes.state[i];
  const double cw = floes.ocean_drag[i] >= 0.0 ? floes.ocean_drag[i] : p.ocean_drag;
  const double k = p.rho_water * cw;
  const double c = std::cos(s.yaw), sn = std::sin(s.yaw);
  FLOESIM_ASSERT(q.has(i));  // a floe drifted is held (FootprintQuadrature::hold)
  const std::size_t begin = q.first[i], end = begin + q.count[i];
  // Force, torque and the six entries of the symmetric Jacobian, accumulated as
  // scalars: with B = [I | kr], B^T (|u| I + u u^T/|u|) B = |u| B^T B + (B^T u)(B^T u)^T / |u|,
  // B^T B = [[1, 0, kr_x], [0, 1, kr_y], [kr_x, kr_y, |r|^2]], B^T u = (u_x, u_y, kr . u).
  double fx = 0, fy = 0, tz = 0;
  double j00 = 0, j01 = 0, j02 = 0, j11 = 0, j12 = 0, j22 = 0;
  for (std::size_t j = begin; j < end; ++j) {
    const Vec2& b = q.point[j];
    const double rx = c * b.x() - sn * b.y(), ry = sn * b.x() + c * b.y();
    const double krx = -ry, kry = rx;  // k x r
    const Vec2 U = water.empty() ? current : water[j - begin];
    const double ux = U.x() - (s.vx + s.yaw_rate * krx);
    const double uy = U.y() - (s.vy + s.yaw_rate * kry);
    const double un = std::sqrt(ux * ux + uy * uy);
    const double w = q.weight[j] * k;
    const double tx = w * un * ux, ty = w * un * uy;
    fx += tx;
    fy += ty;
    tz += krx * tx + kry * ty;
    if (un > 0.0) {
      const double a0 = ux, a1 = uy, a2 = krx * ux + kry * uy;  // B^T u
      const double wu = w * un, wi = w / un;
      j00 += wu + wi * a0 * a0;
      j01 += wi * a0 * a1;
      j02 += wu * krx + wi * a0 * a2;
      j11 += wu + wi * a1 * a1;
      j12 += wu * kry + wi * a1 * a2;
      j22 += wu * (rx * rx + ry * ry) + wi * a2 * a2;
    }
  }
  load.force << fx, fy, tz;
  load.jacobian << -j00, -j01, -j02, -j01, -j11, -j12, -j02, -j12, -j22;
  // Air drag: uniform stress over the footprint, no torque about G.
  const Vec2 ta = p.rho_air * p.air_drag * wind.norm() * wind * floes.area[i];
  load.force.x() += ta.x();
  load.force.y() += ta.y();
  return load;
}

namespace {
// W_n -> W_{n+1} of dynamic floe i (drift_velocities).
void drift_velocity(Floes& floes, const FootprintQuadrature& q, const DriftParams& p, const Vec2& current,
                    const Vec2& wind, double dt, std::size_t i, std::span<const Vec2> floe_current) {
  FloeState& s = floes.state[i];
  const double m = floes.mass[i];
  const DragLoad load = drag_load(floes, q, i, p, floe_current.empty() ? current : floe_current[i], wind);
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
}  // namespace

void drift_velocities(Floes& floes, const FootprintQuadrature& q, const DriftParams& p,
                      const Vec2& current, const Vec2& wind, double dt, std::size_t begin, std::size_t end,
                      std::span<const Vec2> floe_current) {
  for (std::size_t i = begin; i < end; ++i)
    if (!floes.is_static[i]) drift_velocity(floes, q, p, current, wind, dt, i, floe_current);
}

void drift_velocities(Floes& floes, const FootprintQuadrature& q, const DriftParams& p,
                      const Vec2& current, const Vec2& wind, double dt, std::span<const std::uint32_t> which,
                      std::span<const Vec2> floe_current) {
  for (const std::uint32_t i : which)
    if (!floes.is_static[i]) drift_velocity(floes, q, p, current, wind, dt, i, floe_current);
}

void advance_positions(Floes& floes, double dt, std::size_t begin, std::size_t end) {
  for (std::size_t i = begin; i < end; ++i) {
    if (floes.is_static[i]) continue;
    floes.state[i] = drifted(floes.state[i], dt);
  }
}

}  // namespace floesim
