#include "fluid/bem.hpp"

#include <Eigen/Dense>

#include <array>
#include <chrono>
#include <cmath>
#include <numbers>
#include <sstream>

#include "core/error.hpp"

namespace floesim::fluid {

namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;
using Point = std::array<double, 2>;
constexpr double pi = std::numbers::pi;

struct Panel {
  Point a, b;  // traversed counter-clockwise around the fluid: outward normal (t_y, -t_x)
};

void add_segment(std::vector<Panel>& panels, Point a, Point b, double h) {
  const double len = std::hypot(b[0] - a[0], b[1] - a[1]);
  const int n = std::max(1, static_cast<int>(std::ceil(len / h - 1e-9)));
  for (int k = 0; k < n; ++k) {
    const double t0 = static_cast<double>(k) / n, t1 = static_cast<double>(k + 1) / n;
    panels.push_back({{a[0] + t0 * (b[0] - a[0]), a[1] + t0 * (b[1] - a[1])},
                      {a[0] + t1 * (b[0] - a[0]), a[1] + t1 * (b[1] - a[1])}});
  }
}

// ∫ ln r ds over the panel, r from the point p.
double log_integral(const Panel& pan, Point p) {
  const double lx = pan.b[0] - pan.a[0], ly = pan.b[1] - pan.a[1];
  const double len = std::hypot(lx, ly);
  const double tx = lx / len, ty = ly / len;
  const double ax = pan.a[0] - p[0], ay = pan.a[1] - p[1];
  const double s1 = ax * tx + ay * ty, s2 = s1 + len;
  const double d = ax * ty - ay * tx;
  auto f = [d](double s) {
    const double r2 = s * s + d * d;
    double v = -s;
    if (r2 > 0.0) v += 0.5 * s * std::log(r2);
    if (d != 0.0) v += d * std::atan(s / d);
    return v;
  };
  return f(s2) - f(s1);
}

std::shared_ptr<const DenseSetup> build(const SeaParams& p, double ratio) {
  const auto start = std::chrono::steady_clock::now();
  const int ns = p.cells[0];
  const double len = p.size[0], width = p.size[1];
  const double h = len / ns;

  // Panels: the surface first (panel i is grid cell i), then left wall, bottom, right wall.
  std::vector<Panel> panels;
  for (int i = 0; i < ns; ++i) panels.push_back({{(i + 1) * h, 0.0}, {i * h, 0.0}});
  const std::vector<Point> bottom = bottom_profile(p);
  add_segment(panels, {0.0, 0.0}, bottom.front(), ratio * h);
  for (std::size_t k = 1; k < bottom.size(); ++k)
    add_segment(panels, bottom[k - 1], bottom[k], ratio * h);
  add_segment(panels, bottom.back(), {len, 0.0}, ratio * h);
  const int n = static_cast<int>(panels.size());

  // Bordered collocation system [1/2 I + H, 1; w^T, 0] [phi; c] = [G q; 0].
  MatrixXd a = MatrixXd::Zero(n + 1, n + 1);
  MatrixXd rhs = MatrixXd::Zero(n + 1, ns);
  for (int i = 0; i < n; ++i) {
    const Point c = {0.5 * (panels[i].a[0] + panels[i].b[0]),
                     0.5 * (panels[i].a[1] + panels[i].b[1])};
    for (int j = 0; j < n; ++j) {
      if (i != j) {
        // ∫ dG/dn_y ds = -(1/2 pi) x (angle the panel subtends at c).
        const double ax = panels[j].a[0] - c[0], ay = panels[j].a[1] - c[1];
        const double bx = panels[j].b[0] - c[0], by = panels[j].b[1] - c[1];
        a(i, j) = -std::atan2(ax * by - ay * bx, ax * bx + ay * by) / (2.0 * pi);
      }
      if (j < ns) rhs(i, j) = -log_integral(panels[j], c) / (2.0 * pi);
    }
    a(i, i) += 0.5;
    a(i, n) = 1.0;
  }
  for (int j = 0; j < ns; ++j) a(n, j) = h;
  const MatrixXd phi_full = a.partialPivLu().solve(rhs);
  const MatrixXd phi = phi_full.topRows(ns);  // Neumann-to-Dirichlet map on the surface

  MatrixXd m = p.rho * width * h * phi;  // rho w D Phi, D = h I
  m = (0.5 * (m + m.transpose())).eval();
  // K = w (rho g D + sigma L), the faces between neighbouring panels.
  std::vector<Eigen::Triplet<double>> entries;
  for (int i = 0; i < ns; ++i) {
    entries.emplace_back(i, i, width * p.rho * p.g * h);
    if (i + 1 < ns) {  // face between cells i and i + 1
      const double s = width * p.sigma / h;
      entries.emplace_back(i, i, s);
      entries.emplace_back(i + 1, i + 1, s);
      entries.emplace_back(i, i + 1, -s);
      entries.emplace_back(i + 1, i, -s);
    }
  }
  Eigen::SparseMatrix<double> k(ns, ns);
  k.setFromTriplets(entries.begin(), entries.end());

  auto ops = std::make_shared<DenseSetup>();
  ops->panels = n;
  reduce_to_modes(k, m, phi, width * h, 0, *ops);
  ops->cost.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return ops;
}

// The set-up of a basin, cached process-wide (16 kept), keyed by everything that enters it.
DenseModalSea::Cached cached(const SeaParams& p, const SeaOptions& options) {
  if (!(options.bem_panel_ratio > 0.0))
    throw InputError("[sea] cells: the BEM panel ratio must be > 0");
  const double ratio = options.bem_panel_ratio;
  std::ostringstream key;
  key.precision(17);
  key << p.size[0] << ' ' << p.size[1] << ' ' << p.cells[0] << ' ' << p.depth << ' ' << p.rho
      << ' ' << p.g << ' ' << p.sigma << ' ' << ratio;
  for (const auto& b : p.bottom) key << ' ' << b[0] << ',' << b[1];
  return cached_setup<BemSea>(key.str(), 16, [&] { return build(p, ratio); });
}

SurfaceGrid basin_grid(const SeaParams& p) {
  SurfaceGrid g;
  g.dims = 1;
  g.nx = p.cells[0];
  g.ny = 1;
  g.lx = p.size[0];
  g.ly = p.size[1];
  g.edge = GridEdge::wall;
  return g;
}

}  // namespace

std::vector<std::array<double, 2>> bottom_profile(const SeaParams& p) {
  using Point = std::array<double, 2>;
  const double len = p.size[0];
  if (p.bottom.empty()) return {Point{0.0, -p.depth}, Point{len, -p.depth}};
  auto z_at = [&](double x) {
    const auto& b = p.bottom;
    for (std::size_t i = 1; i < b.size(); ++i)
      if (x <= b[i][0]) {
        const double t = (x - b[i - 1][0]) / (b[i][0] - b[i - 1][0]);
        return b[i - 1][1] + t * (b[i][1] - b[i - 1][1]);
      }
    return b.back()[1];
  };
  std::vector<Point> out{{0.0, z_at(0.0)}};
  for (const auto& v : p.bottom)
    if (v[0] > 0.0 && v[0] < len) out.push_back({v[0], v[1]});
  out.push_back({len, z_at(len)});
  return out;
}

BemSea::BemSea(const SeaParams& params, const SeaOptions& options)
    : DenseModalSea(basin_grid(params), cached(params, options)) {}

void BemSea::flow(double dt) {
  bank_.flow(dt);
  time_ += dt;
  invalidate();
}

void BemSea::compute_field(Field f, std::span<double> out) {
  Eigen::Map<VectorXd> o(out.data(), static_cast<Eigen::Index>(out.size()));
  // Centred difference with mirror ghosts (d/dx = 0 at the walls).
  auto derivative = [&](const VectorXd& g) {
    const int n = grid_.nx;
    const double h2 = 2.0 * grid_.dx();
    for (int i = 0; i < n; ++i) o(i) = (g(std::min(i + 1, n - 1)) - g(std::max(i - 1, 0))) / h2;
  };
  switch (f) {
    case Field::elevation: o = surface_elevation(); break;
    case Field::velocity_z: synthesize(bank_.v(), out); break;
    case Field::slope_x: derivative(surface_elevation()); break;
    case Field::velocity_x: derivative(surface_potential()); break;
    case Field::slope_y:
    case Field::velocity_y: o.setZero(); break;
  }
}

}  // namespace floesim::fluid
