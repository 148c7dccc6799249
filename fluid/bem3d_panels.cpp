#include "fluid/bem3d_panels.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <numbers>

#include "fluid/bem.hpp"

namespace floesim::fluid {

namespace {

constexpr double pi = std::numbers::pi;

P3 sub(const P3& a, const P3& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
double dot(const P3& a, const P3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
P3 cross(const P3& a, const P3& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
double norm(const P3& a) { return std::sqrt(dot(a, a)); }

// Appends the quadrilateral a b c d, ordered counter-clockwise about `outward`.
void add_quad(std::vector<Panel>& out, const P3& a, const P3& b, const P3& c, const P3& d, const P3& outward) {
  const P3 n = cross(sub(c, a), sub(d, b));  // twice the vector area
  if (dot(n, outward) >= 0.0)
    out.push_back({{a, b, c, d}, 4});
  else
    out.push_back({{a, d, c, b}, 4});
}

void add_triangle(std::vector<Panel>& out, const P3& a, const P3& b, const P3& c, const P3& outward) {
  const P3 n = cross(sub(b, a), sub(c, a));
  if (dot(n, outward) >= 0.0)
    out.push_back({{a, b, c, c}, 3});
  else
    out.push_back({{a, c, b, b}, 3});
}

// The bottom z_b(x, y) and the columns along x that the bottom and walls are
// cut into: the polyline's segments (its vertices are column edges), or, for
// a bottom grid, equal columns, with z bilinear between the grid's nodes.
struct Bottom {
  std::vector<double> xs;  // column edges, 0 .. lx
  bool planar = true;      // z varies along x only: the bottom's quads are flat
  std::function<double(double, double)> z;
};

Bottom bottom_of(const SeaParams& p, double ratio) {
  const double lx = p.size[0], ly = p.size[1], dx = lx / p.cells[0];
  Bottom b;
  if (!p.bottom_grid.empty()) {
    b.planar = false;
    const int n = std::max(1, static_cast<int>(std::ceil(lx / (ratio * dx) - 1e-9)));
    for (int c = 0; c <= n; ++c) b.xs.push_back(lx * c / n);
    b.z = [&p, lx, ly](double x, double y) {
      const int mx = p.bottom_nx, my = p.bottom_ny;
      const double u = std::clamp(x / lx, 0.0, 1.0) * (mx - 1), v = std::clamp(y / ly, 0.0, 1.0) * (my - 1);
      const int i = std::min(static_cast<int>(u), mx - 2), j = std::min(static_cast<int>(v), my - 2);
      const double s = u - i, t = v - j;
      auto at = [&](int ii, int jj) { return p.bottom_grid[static_cast<std::size_t>(jj * mx + ii)]; };
      return (1 - s) * (1 - t) * at(i, j) + s * (1 - t) * at(i + 1, j) + s * t * at(i + 1, j + 1) + (1 - s) * t * at(i, j + 1);
    };
    return b;
  }
  // Each segment of the polyline cut into pieces of about ratio dx (along the slope).
  const auto line = bottom_profile(p);
  b.xs.push_back(line[0][0]);
  for (std::size_t k = 1; k < line.size(); ++k) {
    const double len = std::hypot(line[k][0] - line[k - 1][0], line[k][1] - line[k - 1][1]);
    const int n = std::max(1, static_cast<int>(std::ceil(len / (ratio * dx) - 1e-9)));
    for (int m = 1; m <= n; ++m) b.xs.push_back(line[k - 1][0] + (line[k][0] - line[k - 1][0]) * m / n);
  }
  b.z = [line](double x, double) {
    for (std::size_t i = 1; i < line.size(); ++i)
      if (x <= line[i][0]) {
        const double t = (x - line[i - 1][0]) / (line[i][0] - line[i - 1][0]);
        return line[i - 1][1] + t * (line[i][1] - line[i - 1][1]);
      }
    return line.back()[1];
  };
  return b;
}


PanelIntegrals far_integrals(const FarRule& r, const P3& p) {
  PanelIntegrals out;
  for (std::size_t k = 0; k < 4; ++k) {
    const P3 d = sub(r.point[k], p);
    const double inv = 1.0 / norm(d);
    out.single += r.weight[k] * inv;
    out.double_ -= r.weight[k] * dot(d, r.normal) * inv * inv * inv;
  }
  out.single /= 4.0 * pi;
  out.double_ /= 4.0 * pi;
  return out;
}

}  // namespace

P3 centroid(const Panel& q) {
  P3 c{};
  for (const P3& v : q.vertices())
    for (int k = 0; k < 3; ++k) c[k] += v[k] / static_cast<double>(q.size);
  return c;
}

// The watertight boundary of the basin: the surface cells first (panel
// j nx + i is grid cell (i, j)), then the bottom and the four walls.
std::vector<Panel> basin_panels(const SeaParams& p, double ratio) {
  const int nx = p.cells[0], ny = p.cells[1];
  const double lx = p.size[0], ly = p.size[1], dx = lx / nx, dy = ly / ny;
  std::vector<Panel> out;
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i)
      add_quad(out, {i * dx, j * dy, 0.0}, {(i + 1) * dx, j * dy, 0.0}, {(i + 1) * dx, (j + 1) * dy, 0.0},
               {i * dx, (j + 1) * dy, 0.0}, {0.0, 0.0, 1.0});

  const Bottom bottom = bottom_of(p, ratio);
  const std::vector<double>& xs = bottom.xs;
  const int cols = static_cast<int>(xs.size()) - 1;
  const int rows = std::max(1, static_cast<int>(std::ceil(ly / (ratio * dy) - 1e-9)));
  auto y = [&](int r) { return ly * r / rows; };
  auto node = [&](int c, int r) { return P3{xs[static_cast<std::size_t>(c)], y(r), bottom.z(xs[static_cast<std::size_t>(c)], y(r))}; };
  double deepest = 0.0;
  for (int c = 0; c <= cols; ++c)
    for (int r = 0; r <= rows; ++r) deepest = std::max(deepest, -node(c, r)[2]);
  const int layers = std::max(1, static_cast<int>(std::ceil(deepest / (ratio * std::min(dx, dy)) - 1e-9)));
  auto t = [&](int l) { return static_cast<double>(l) / layers; };  // fraction of the local depth
  auto scaled = [](P3 v, double f) { return P3{v[0], v[1], f * v[2]}; };

  const P3 down = {0.0, 0.0, -1.0};
  for (int c = 0; c < cols; ++c)
    for (int r = 0; r < rows; ++r) {
      const P3 a = node(c, r), b = node(c + 1, r), e = node(c + 1, r + 1), d = node(c, r + 1);
      if (bottom.planar) {
        add_quad(out, a, b, e, d, down);
      } else {  // a bilinear patch is not flat: two triangles
        add_triangle(out, a, b, e, down);
        add_triangle(out, a, e, d, down);
      }
    }
  // Walls: each column (row) of the bottom carried up in equal fractions of
  // its local depth; every such panel lies in its wall's plane.
  for (int l = 0; l < layers; ++l) {
    for (int r = 0; r < rows; ++r)
      for (int end : {0, cols})
        add_quad(out, scaled(node(end, r), t(l)), scaled(node(end, r + 1), t(l)), scaled(node(end, r + 1), t(l + 1)),
                 scaled(node(end, r), t(l + 1)), {end == 0 ? -1.0 : 1.0, 0.0, 0.0});
    for (int c = 0; c < cols; ++c)
      for (int side : {0, rows})
        add_quad(out, scaled(node(c, side), t(l)), scaled(node(c + 1, side), t(l)), scaled(node(c + 1, side), t(l + 1)),
                 scaled(node(c, side), t(l + 1)), {0.0, side == 0 ? -1.0 : 1.0, 0.0});
  }
  return out;
}

FarRule far_rule(const Panel& panel) {
  FarRule r;
  const auto& q = panel.v;
  r.centre = centroid(panel);
  if (panel.size == 3) {
    // The three-point rule at (2/3, 1/6, 1/6) and its permutations (degree 2).
    const double area = 0.5 * norm(cross(sub(q[1], q[0]), sub(q[2], q[0])));
    for (std::size_t k = 0; k < 3; ++k) {
      for (int c = 0; c < 3; ++c) r.point[k][c] = (4.0 * q[k][c] + q[(k + 1) % 3][c] + q[(k + 2) % 3][c]) / 6.0;
      r.weight[k] = area / 3.0;
    }
    r.weight[3] = 0.0;
    r.point[3] = r.centre;
    r.normal = cross(sub(q[1], q[0]), sub(q[2], q[0]));
    const double nn = norm(r.normal);
    for (double& c : r.normal) c /= nn;
    r.diameter = std::max({norm(sub(q[1], q[0])), norm(sub(q[2], q[1])), norm(sub(q[0], q[2]))});
    return r;
  }
  const double g = 0.5 / std::sqrt(3.0);
  int k = 0;
  for (double s : {0.5 - g, 0.5 + g})
    for (double t : {0.5 - g, 0.5 + g}) {
      P3 y{}, ys{}, yt{};
      for (int c = 0; c < 3; ++c) {
        y[c] = (1 - s) * (1 - t) * q[0][c] + s * (1 - t) * q[1][c] + s * t * q[2][c] + (1 - s) * t * q[3][c];
        ys[c] = (1 - t) * (q[1][c] - q[0][c]) + t * (q[2][c] - q[3][c]);
        yt[c] = (1 - s) * (q[3][c] - q[0][c]) + s * (q[2][c] - q[1][c]);
      }
      r.point[static_cast<std::size_t>(k)] = y;
      r.weight[static_cast<std::size_t>(k)] = 0.25 * norm(cross(ys, yt));
      ++k;
    }
  r.normal = cross(sub(q[2], q[0]), sub(q[3], q[1]));
  const double nn = norm(r.normal);
  for (double& c : r.normal) c /= nn;
  r.diameter = std::max(norm(sub(q[2], q[0])), norm(sub(q[3], q[1])));
  return r;
}


PanelIntegrals panel_integrals(std::span<const std::array<double, 3>> poly, const std::array<double, 3>& p) {
  const std::size_t nv = poly.size();
  // Unit normal by Newell's rule; the projection rho of p on the plane, height h above it.
  P3 n{};
  for (std::size_t i = 0; i < nv; ++i) {
    const P3 c = cross(poly[i], poly[(i + 1) % nv]);
    for (int k = 0; k < 3; ++k) n[k] += c[k];
  }
  const double nn = norm(n);
  for (double& c : n) c /= nn;
  const double h = dot(sub(p, poly[0]), n), ah = std::abs(h);
  const P3 rho = {p[0] - h * n[0], p[1] - h * n[1], p[2] - h * n[2]};

  // Single layer, by the edge formula (Wilton et al. 1984, IEEE TAP 32:276):
  //   ∫ dS / r = sum_e t_e [asinh(l+/R0) - asinh(l-/R0)]
  //            - |h| sum_e [atan(t_e l+ / (R0^2 + |h| R+)) - atan(t_e l- / (R0^2 + |h| R-))],
  // edge e from a to b, l- and l+ the abscissae of a and b along it from the
  // foot of rho, t_e the distance of rho to its line (positive inside),
  // R0^2 = t_e^2 + h^2, R+- = sqrt(l+-^2 + R0^2).
  double s1 = 0.0, s2 = 0.0;
  for (std::size_t i = 0; i < nv; ++i) {
    const P3& a = poly[i];
    const P3& b = poly[(i + 1) % nv];
    P3 l = sub(b, a);
    const double len = norm(l);
    for (double& c : l) c /= len;
    const P3 u = cross(l, n);  // in the plane, out of the polygon
    const P3 ar = sub(a, rho);
    const double t = dot(ar, u), lm = dot(ar, l), lp = lm + len;
    const double r02 = t * t + h * h;
    if (std::abs(t) <= 1e-14 * len) continue;  // rho on the edge's line: the term is 0
    const double r0 = std::sqrt(r02);
    s1 += t * (std::asinh(lp / r0) - std::asinh(lm / r0));
    if (ah > 0.0) {
      const double rp = std::sqrt(lp * lp + r02), rm = std::sqrt(lm * lm + r02);
      s2 += std::atan(t * lp / (r02 + ah * rp)) - std::atan(t * lm / (r02 + ah * rm));
    }
  }
  PanelIntegrals out;
  out.single = (s1 - ah * s2) / (4.0 * pi);

  // Double layer: d/dn_y (1 / (4 pi r)) = -(y - p).n / (4 pi r^3), whose integral
  // is -Omega / (4 pi), Omega the solid angle of the panel seen from p (signed:
  // positive when p is on the side the normal points away from). By triangles
  // of a fan (Van Oosterom & Strackee 1983, IEEE TBME 30:125).
  double omega = 0.0;
  const P3 a = sub(poly[0], p);
  const double ra = norm(a);
  for (std::size_t k = 1; k + 1 < nv; ++k) {
    const P3 b = sub(poly[k], p), c = sub(poly[k + 1], p);
    const double rb = norm(b), rc = norm(c);
    const double num = dot(a, cross(b, c));
    const double den = ra * rb * rc + dot(a, b) * rc + dot(a, c) * rb + dot(b, c) * ra;
    omega += 2.0 * std::atan2(num, den);
  }
  out.double_ = -omega / (4.0 * pi);
  return out;
}

PanelIntegrals integrals_at(const Panel& panel, const FarRule& rule, const P3& p, double near) {
  const P3 d = sub(p, rule.centre);
  if (dot(d, d) > near * near * rule.diameter * rule.diameter) return far_integrals(rule, p);
  return panel_integrals(panel.vertices(), p);
}

}  // namespace floesim::fluid
