#include "fluid/bem.hpp"

#include <Eigen/Dense>

#include <array>
#include <chrono>
#include <cmath>
#include <map>
#include <mutex>
#include <numbers>
#include <sstream>

#include "core/error.hpp"
#include "fluid/dense_modes.hpp"

namespace floesim::fluid {

namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;
using Point = std::array<double, 2>;
constexpr double pi = std::numbers::pi;

struct Panel {
  Point a, b;  // traversed counter-clockwise around the fluid: outward normal (t_y, -t_x)
};

// The set-up of one basin: modes and the maps from modal state to surface fields.
struct Operators : DenseModes {  // surface = the surface panels
  int panels = 0;   // all panels
  double setup_seconds = 0.0;
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

std::shared_ptr<const Operators> build(const SeaParams& p, double ratio) {
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
  MatrixXd k = MatrixXd::Zero(ns, ns);
  for (int i = 0; i < ns; ++i) {
    k(i, i) += p.rho * p.g * h;
    if (i + 1 < ns) {  // face between cells i and i + 1
      const double s = p.sigma / h;
      k(i, i) += s;
      k(i + 1, i + 1) += s;
      k(i, i + 1) -= s;
      k(i + 1, i) -= s;
    }
  }
  k *= width;

  // Zero-mean surfaces: an orthonormal basis q of the complement of the constants.
  const VectorXd ones = VectorXd::Ones(ns);
  const MatrixXd qfull = Eigen::HouseholderQR<MatrixXd>(ones).householderQ();
  const MatrixXd q = qfull.rightCols(ns - 1);
  const MatrixXd kr = q.transpose() * k * q, mr = q.transpose() * m * q;
  Eigen::GeneralizedSelfAdjointEigenSolver<MatrixXd> eig(kr, mr);
  if (eig.info() != Eigen::Success)
    throw RunError("fluid: the BEM eigenproblem (a_sf, m_sf) did not converge");

  auto ops = std::make_shared<Operators>();
  ops->surface = ns;
  ops->panels = n;
  ops->x = q * eig.eigenvectors();
  ops->omega.resize(ns - 1);
  for (int j = 0; j < ns - 1; ++j) ops->omega[j] = std::sqrt(std::max(0.0, eig.eigenvalues()(j)));
  ops->load = -width * h * ops->x.transpose();
  ops->project = ops->x.transpose() * m;
  ops->potential = phi * ops->x;
  ops->setup_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return ops;
}

// Process-wide cache of set-ups, keyed by everything that enters them.
std::shared_ptr<const Operators> cached(const SeaParams& p, double ratio, bool& hit) {
  static std::mutex mutex;
  static std::map<std::string, std::shared_ptr<const Operators>> cache;
  std::ostringstream key;
  key.precision(17);
  key << p.size[0] << ' ' << p.size[1] << ' ' << p.cells[0] << ' ' << p.depth << ' ' << p.rho
      << ' ' << p.g << ' ' << p.sigma << ' ' << ratio;
  for (const auto& b : p.bottom) key << ' ' << b[0] << ',' << b[1];
  std::lock_guard lock(mutex);
  if (auto it = cache.find(key.str()); it != cache.end()) {
    hit = true;
    return it->second;
  }
  hit = false;
  auto ops = build(p, ratio);
  if (cache.size() >= 16) cache.clear();
  cache.emplace(key.str(), ops);
  return ops;
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

struct BemSea::Impl {
  std::shared_ptr<const Operators> ops;
  bool hit = false;
  bool kicked = false;  // work_modes holds the projection of the last kick's pressure
  VectorXd work_modes, work_surface;
};

BemSea::BemSea(const SeaParams& params, const SeaOptions& options)
    : Sea(basin_grid(params)), impl_(std::make_unique<Impl>()) {
  if (!(options.bem_panel_ratio > 0.0))
    throw InputError("[sea] cells: the BEM panel ratio must be > 0");
  impl_->ops = cached(params, options.bem_panel_ratio, impl_->hit);
  const auto& ops = *impl_->ops;
  const std::size_t nm = ops.omega.size();
  bank_ = ModalBank(ops.omega, std::vector<double>(nm, 1.0), std::vector<double>(nm, 1.0), 1);
  impl_->work_modes.resize(static_cast<Eigen::Index>(nm));
  impl_->work_surface.resize(ops.surface);
}

BemSea::~BemSea() = default;

std::span<const double> BemSea::frequencies() const { return impl_->ops->omega; }
int BemSea::panels() const { return impl_->ops->panels; }
double BemSea::setup_seconds() const { return impl_->ops->setup_seconds; }
bool BemSea::from_cache() const { return impl_->hit; }

void BemSea::kick(std::span<const double> pressure, double h) {
  FLOESIM_ASSERT(pressure.size() == static_cast<std::size_t>(impl_->ops->surface));
  impl_->kicked = true;
  project(pressure, {impl_->work_modes.data(), static_cast<std::size_t>(impl_->work_modes.size())});  // kept for repeat_kick
  repeat_kick(h);
}

void BemSea::repeat_kick(double h) {
  FLOESIM_ASSERT(impl_->kicked);
  bank_.kick(std::span<const double>(impl_->work_modes.data(), bank_.modes()), h);
  invalidate_rates();
}

void BemSea::flow(double dt) {
  bank_.flow(dt);
  time_ += dt;
  invalidate();
}

void BemSea::set_surface(std::span<const double> eta, std::span<const double> eta_t) {
  impl_->ops->to_modes(eta, bank_.q(), impl_->work_surface);
  impl_->ops->to_modes(eta_t, bank_.v(), impl_->work_surface);
  invalidate();
}

void BemSea::project(std::span<const double> pressure, std::span<double> s) {
  impl_->ops->to_forces(pressure, s);
}

void BemSea::synthesize(std::span<const double> q, std::span<double> eta) { impl_->ops->to_surface(q, eta); }

void BemSea::compute_field(Field f, std::span<double> out) {
  const auto& ops = *impl_->ops;
  const Eigen::Index nm = static_cast<Eigen::Index>(bank_.modes());
  const Eigen::Map<const VectorXd> q(bank_.q().data(), nm), v(bank_.v().data(), nm);
  Eigen::Map<VectorXd> o(out.data(), ops.surface);
  // Centred difference with mirror ghosts (d/dx = 0 at the walls).
  auto derivative = [&](const VectorXd& g) {
    const int n = ops.surface;
    const double h2 = 2.0 * grid_.dx();
    for (int i = 0; i < n; ++i) o(i) = (g(std::min(i + 1, n - 1)) - g(std::max(i - 1, 0))) / h2;
  };
  switch (f) {
    case Field::elevation: o.noalias() = ops.x * q; break;
    case Field::velocity_z: o.noalias() = ops.x * v; break;
    case Field::slope_x:
      impl_->work_surface.noalias() = ops.x * q;
      derivative(impl_->work_surface);
      break;
    case Field::velocity_x:
      impl_->work_surface.noalias() = ops.potential * v;
      derivative(impl_->work_surface);
      break;
    case Field::slope_y:
    case Field::velocity_y: o.setZero(); break;
  }
}

}  // namespace floesim::fluid
