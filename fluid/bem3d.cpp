#include "fluid/bem3d.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <functional>
#include <map>
#include <mutex>
#include <numbers>
#include <optional>
#include <sstream>

#include "core/error.hpp"
#include "fluid/bem.hpp"
#include "fluid/tank.hpp"
#include "fluid/waves.hpp"

namespace floesim::fluid {

namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;
using P3 = std::array<double, 3>;
constexpr double pi = std::numbers::pi;

P3 sub(const P3& a, const P3& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
double dot(const P3& a, const P3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
P3 cross(const P3& a, const P3& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
double norm(const P3& a) { return std::sqrt(dot(a, a)); }

// A flat panel: a quadrilateral, or a triangle (size 3), counter-clockwise
// about the fluid's outward normal.
struct Panel {
  std::array<P3, 4> v;
  std::size_t size = 4;
  std::span<const P3> vertices() const { return {v.data(), size}; }
};

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

P3 centroid(const Panel& q) {
  P3 c{};
  for (const P3& v : q.vertices())
    for (int k = 0; k < 3; ++k) c[k] += v[k] / static_cast<double>(q.size);
  return c;
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

// A panel's far-field rule: 2 x 2 Gauss points of a quadrilateral's bilinear
// map from the unit square, with weights times the area element, or a
// triangle's three-point rule; exact integrals within
// `near` diameters of its centroid.
struct FarRule {
  std::array<P3, 4> point;
  std::array<double, 4> weight;
  P3 normal, centre;
  double diameter = 0.0;
};

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

// The set-up of one basin: modes and the maps from modal state to surface fields.
struct Operators {
  int surface = 0;  // surface panels = grid cells
  int panels = 0;   // all panels
  std::vector<double> omega;  // per mode, ascending
  MatrixXd x;         // surface x modes: eta = x a (M-orthonormal columns)
  MatrixXd load;      // modes x surface: modal force per unit pressure, -A x^T
  MatrixXd project;   // modes x surface: a = project eta, for zero-mean eta (x^T M)
  MatrixXd potential; // surface x modes: phi on the surface per unit a'
  Bem3dSea::SetupCost cost;
};

// S -> H S H for the Householder reflection H = I - beta v v^T (S symmetric).
void reflect(MatrixXd& s, const VectorXd& v, double beta) {
  const VectorXd w = s * v;
  const double vw = v.dot(w);
  s.noalias() -= beta * (v * w.transpose() + w * v.transpose());
  s.noalias() += (beta * beta * vw) * (v * v.transpose());
}

std::shared_ptr<const Operators> build(const SeaParams& p, double ratio, double near) {
  const auto start = std::chrono::steady_clock::now();
  auto since = [](std::chrono::steady_clock::time_point t) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
  };
  Bem3dSea::SetupCost cost;
  const int nx = p.cells[0], ny = p.cells[1], ns = nx * ny;
  const double dx = p.size[0] / nx, dy = p.size[1] / ny, area = dx * dy;
  const std::vector<Panel> panels = basin_panels(p, ratio);
  const int n = static_cast<int>(panels.size());
  std::vector<P3> centres(panels.size());
  std::vector<FarRule> rules(panels.size());
  for (std::size_t i = 0; i < panels.size(); ++i) {
    centres[i] = centroid(panels[i]);
    rules[i] = far_rule(panels[i]);
  }

  // Bordered collocation system [1/2 I + D, 1; A 1^T, 0] [phi; c] = [S q; 0],
  // assembled column by column (Eigen is column-major).
  MatrixXd a = MatrixXd::Zero(n + 1, n + 1);
  MatrixXd phi = MatrixXd::Zero(n + 1, ns);
  for (int j = 0; j < n; ++j) {
    const auto uj = static_cast<std::size_t>(j);
    const double reach2 = std::pow(near * rules[uj].diameter, 2);
    for (int i = 0; i < n; ++i) {
      const P3& c = centres[static_cast<std::size_t>(i)];
      const P3 d = sub(c, rules[uj].centre);
      const PanelIntegrals in = dot(d, d) > reach2 ? far_integrals(rules[uj], c) : panel_integrals(panels[uj].vertices(), c);
      a(i, j) = in.double_;
      if (j < ns) phi(i, j) = in.single;
    }
  }
  // A panel's own principal value is 0 (flat panel); the jump is the 1/2. With
  // the far field approximate the rows no longer sum to -1/2 exactly: the
  // diagonal takes the defect (constants stay exactly in the kernel).
  for (int i = 0; i < n; ++i) {
    a(i, i) = 0.0;
    a(i, i) = -a.row(i).head(n).sum();
  }
  for (int i = 0; i < n; ++i) a(i, n) = 1.0;
  for (int j = 0; j < ns; ++j) a(n, j) = area;
  cost.bytes = 8.0 * (static_cast<double>(n + 1) * (n + 1) + 2.0 * (n + 1) * ns);
  cost.assemble = since(start);
  const auto solve_start = std::chrono::steady_clock::now();
  {
    Eigen::PartialPivLU<Eigen::Ref<MatrixXd>> lu(a);  // in place
    phi = lu.solve(phi);
  }
  a.resize(0, 0);
  phi.conservativeResize(ns, ns);  // Neumann-to-Dirichlet map on the surface
  cost.solve = since(solve_start);
  const auto modes_start = std::chrono::steady_clock::now();

  MatrixXd m = p.rho * area * phi;  // rho A Phi
  m = (0.5 * (m + m.transpose())).eval();
  MatrixXd k = MatrixXd::Zero(ns, ns);
  auto face = [&](int c0, int c1, double s) {
    k(c0, c0) += s;
    k(c1, c1) += s;
    k(c0, c1) -= s;
    k(c1, c0) -= s;
  };
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      const int c = j * nx + i;
      k(c, c) += p.rho * p.g * area;
      if (i + 1 < nx) face(c, c + 1, p.sigma * dy / dx);
      if (j + 1 < ny) face(c, c + nx, p.sigma * dx / dy);
    }

  // Zero-mean surfaces: H = I - beta v v^T, v = 1 + sqrt(ns) e_0, maps the
  // constants onto the first axis; its other columns span the zero-mean ones.
  VectorXd v = VectorXd::Ones(ns);
  v(0) += std::sqrt(static_cast<double>(ns));
  const double beta = 2.0 / v.squaredNorm();
  reflect(k, v, beta);
  reflect(m, v, beta);
  Eigen::GeneralizedSelfAdjointEigenSolver<MatrixXd> eig(k.bottomRightCorner(ns - 1, ns - 1),
                                                         m.bottomRightCorner(ns - 1, ns - 1));
  if (eig.info() != Eigen::Success)
    throw RunError("fluid: the 3D BEM eigenproblem (a_sf, m_sf) did not converge");

  auto ops = std::make_shared<Operators>();
  ops->surface = ns;
  ops->panels = n;
  ops->x = MatrixXd::Zero(ns, ns - 1);
  ops->x.bottomRows(ns - 1) = eig.eigenvectors();
  const Eigen::RowVectorXd vx = v.transpose() * ops->x;
  ops->x.noalias() -= beta * v * vx;
  ops->omega.resize(static_cast<std::size_t>(ns - 1));
  for (int j = 0; j < ns - 1; ++j)
    ops->omega[static_cast<std::size_t>(j)] = std::sqrt(std::max(0.0, eig.eigenvalues()(j)));
  // The unreflected mass matrix for the projection: M x = (H M_r H) x.
  m = p.rho * area * phi;
  m = (0.5 * (m + m.transpose())).eval();
  ops->load = -area * ops->x.transpose();
  ops->project = ops->x.transpose() * m;
  ops->potential = phi * ops->x;
  cost.modes = since(modes_start);
  cost.seconds = since(start);
  ops->cost = cost;
  return ops;
}

// Process-wide cache of set-ups, keyed by everything that enters them.
std::shared_ptr<const Operators> cached(const SeaParams& p, double ratio, double near, bool& hit) {
  static std::mutex mutex;
  static std::map<std::string, std::shared_ptr<const Operators>> cache;
  std::ostringstream key;
  key.precision(17);
  key << p.size[0] << ' ' << p.size[1] << ' ' << p.cells[0] << ' ' << p.cells[1] << ' ' << p.depth << ' '
      << p.rho << ' ' << p.g << ' ' << p.sigma << ' ' << ratio << ' ' << near;
  for (const auto& b : p.bottom) key << ' ' << b[0] << ',' << b[1];
  key << " grid " << p.bottom_nx << ' ' << p.bottom_ny;
  for (double z : p.bottom_grid) key << ' ' << z;
  std::lock_guard lock(mutex);
  if (auto it = cache.find(key.str()); it != cache.end()) {
    hit = true;
    return it->second;
  }
  hit = false;
  auto ops = build(p, ratio, near);
  if (cache.size() >= 4) cache.clear();  // dense set-ups are large: keep few
  cache.emplace(key.str(), ops);
  return ops;
}

SurfaceGrid basin_grid(const SeaParams& p) {
  SurfaceGrid g;
  g.dims = 2;
  g.nx = p.cells[0];
  g.ny = p.cells[1];
  g.lx = p.size[0];
  g.ly = p.size[1];
  g.edge = GridEdge::wall;
  return g;
}

}  // namespace

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

struct Bem3dSea::Impl {
  std::shared_ptr<const Operators> ops;
  bool hit = false;
  bool kicked = false;  // work_modes holds the projection of the last kick's pressure
  VectorXd work_modes, work_surface;
  std::optional<TankZones> tank;  // relaxation zones along x (fluid/tank.hpp)
  std::vector<double> tank_eta, tank_rate;
};

Bem3dSea::Bem3dSea(const SeaParams& params, const SeaOptions& options)
    : Sea(basin_grid(params)), impl_(std::make_unique<Impl>()) {
  if (!(options.bem_panel_ratio > 0.0))
    throw InputError("[sea] cells: the BEM panel ratio must be > 0");
  if (!(options.bem_near_field >= 1.0))
    throw InputError("[sea] cells: the BEM near-field reach must be >= 1 panel diameter");
  impl_->ops = cached(params, options.bem_panel_ratio, options.bem_near_field, impl_->hit);
  const auto& ops = *impl_->ops;
  const std::size_t nm = ops.omega.size();
  bank_ = ModalBank(ops.omega, std::vector<double>(nm, 1.0), std::vector<double>(nm, 1.0), 1);
  impl_->work_modes.resize(static_cast<Eigen::Index>(nm));
  impl_->work_surface.resize(ops.surface);
  if (options.tank.enabled) {
    FLOESIM_ASSERT(params.waves.kind == WaveKind::regular);  // refused at load (core/config.cpp)
    impl_->tank.emplace(grid_, options.tank, plane_wave(params, grid_));
    impl_->tank_eta.assign(grid_.size(), 0.0);
    impl_->tank_rate.assign(grid_.size(), 0.0);
  }
}

Bem3dSea::~Bem3dSea() = default;

const TankZones* Bem3dSea::tank() const { return impl_->tank ? &*impl_->tank : nullptr; }

void Bem3dSea::relax_tank(double t0, double h) {
  Impl& m = *impl_;
  synthesize(bank_.q(), m.tank_eta);
  synthesize(bank_.v(), m.tank_rate);
  m.tank->relax(t0, h, m.tank_eta, m.tank_rate);
  set_surface(m.tank_eta, m.tank_rate);
}

std::span<const double> Bem3dSea::frequencies() const { return impl_->ops->omega; }
int Bem3dSea::panels() const { return impl_->ops->panels; }
const Bem3dSea::SetupCost& Bem3dSea::setup_cost() const { return impl_->ops->cost; }
bool Bem3dSea::from_cache() const { return impl_->hit; }

void Bem3dSea::kick(std::span<const double> pressure, double h) {
  const auto& ops = *impl_->ops;
  FLOESIM_ASSERT(pressure.size() == static_cast<std::size_t>(ops.surface));
  const Eigen::Map<const VectorXd> p(pressure.data(), ops.surface);
  impl_->work_modes.noalias() = ops.load * p;
  impl_->kicked = true;
  bank_.kick(std::span<const double>(impl_->work_modes.data(), bank_.modes()), h);
  invalidate_rates();
}

void Bem3dSea::repeat_kick(double h) {
  FLOESIM_ASSERT(impl_->kicked);
  bank_.kick(std::span<const double>(impl_->work_modes.data(), bank_.modes()), h);
  invalidate_rates();
}

void Bem3dSea::flow(double dt) {
  if (!impl_->tank) {
    bank_.flow(dt);
  } else {
    // Strang: relax(dt/2) flow(dt) relax(dt/2), as the spectral tank.
    relax_tank(time_, 0.5 * dt);
    bank_.flow(dt);
    relax_tank(time_ + 0.5 * dt, 0.5 * dt);
  }
  time_ += dt;
  invalidate();
}

void Bem3dSea::midpoint_step(std::span<const double> p, double h) {
  if (!impl_->tank) return Sea::midpoint_step(p, h);
  relax_tank(time_, 0.5 * h);
  Sea::midpoint_step(p, h);  // advances time_ by h
  relax_tank(time_ - 0.5 * h, 0.5 * h);
}

void Bem3dSea::set_surface(std::span<const double> eta, std::span<const double> eta_t) {
  const auto& ops = *impl_->ops;
  auto project = [&](std::span<const double> f, std::span<double> a) {
    Eigen::Map<const VectorXd> fv(f.data(), ops.surface);
    impl_->work_surface = fv.array() - fv.mean();
    Eigen::Map<VectorXd>(a.data(), static_cast<Eigen::Index>(a.size())).noalias() =
        ops.project * impl_->work_surface;
  };
  project(eta, bank_.q());
  project(eta_t, bank_.v());
  invalidate();
}

void Bem3dSea::project(std::span<const double> pressure, std::span<double> s) {
  const auto& ops = *impl_->ops;
  const Eigen::Map<const VectorXd> p(pressure.data(), ops.surface);
  Eigen::Map<VectorXd>(s.data(), static_cast<Eigen::Index>(s.size())).noalias() = ops.load * p;
}

void Bem3dSea::synthesize(std::span<const double> q, std::span<double> eta) {
  const auto& ops = *impl_->ops;
  const Eigen::Map<const VectorXd> a(q.data(), static_cast<Eigen::Index>(q.size()));
  Eigen::Map<VectorXd>(eta.data(), ops.surface).noalias() = ops.x * a;
}

void Bem3dSea::compute_field(Field f, std::span<double> out) {
  const auto& ops = *impl_->ops;
  const Eigen::Index nm = static_cast<Eigen::Index>(bank_.modes());
  const Eigen::Map<const VectorXd> q(bank_.q().data(), nm), v(bank_.v().data(), nm);
  Eigen::Map<VectorXd> o(out.data(), ops.surface);
  const int nx = grid_.nx, ny = grid_.ny;
  // Centred differences with mirror ghosts (d/dn = 0 at the walls).
  auto d_dx = [&](const VectorXd& g) {
    const double h2 = 2.0 * grid_.dx();
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i)
        o(j * nx + i) = (g(j * nx + std::min(i + 1, nx - 1)) - g(j * nx + std::max(i - 1, 0))) / h2;
  };
  auto d_dy = [&](const VectorXd& g) {
    const double h2 = 2.0 * grid_.dy();
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i)
        o(j * nx + i) = (g(std::min(j + 1, ny - 1) * nx + i) - g(std::max(j - 1, 0) * nx + i)) / h2;
  };
  switch (f) {
    case Field::elevation: o.noalias() = ops.x * q; break;
    case Field::velocity_z: o.noalias() = ops.x * v; break;
    case Field::slope_x:
    case Field::slope_y:
      impl_->work_surface.noalias() = ops.x * q;
      f == Field::slope_x ? d_dx(impl_->work_surface) : d_dy(impl_->work_surface);
      break;
    case Field::velocity_x:
    case Field::velocity_y:
      impl_->work_surface.noalias() = ops.potential * v;
      f == Field::velocity_x ? d_dx(impl_->work_surface) : d_dy(impl_->work_surface);
      break;
  }
}

}  // namespace floesim::fluid
