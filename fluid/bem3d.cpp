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
#include "fluid/dense_modes.hpp"
#include "fluid/bem3d_panels.hpp"
#include "fluid/tank.hpp"
#include "fluid/waves.hpp"

namespace floesim::fluid {

namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;

// The set-up of one basin: modes and the maps from modal state to surface fields.
struct Operators : DenseModes {  // surface = the surface panels
  int panels = 0;   // all panels
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
    for (int i = 0; i < n; ++i) {
      const PanelIntegrals in = integrals_at(panels[uj], rules[uj], centres[static_cast<std::size_t>(i)], near);
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
  FLOESIM_ASSERT(pressure.size() == static_cast<std::size_t>(impl_->ops->surface));
  impl_->kicked = true;
  project(pressure, {impl_->work_modes.data(), static_cast<std::size_t>(impl_->work_modes.size())});  // kept for repeat_kick
  repeat_kick(h);
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
  impl_->ops->to_modes(eta, bank_.q(), impl_->work_surface);
  impl_->ops->to_modes(eta_t, bank_.v(), impl_->work_surface);
  invalidate();
}

void Bem3dSea::project(std::span<const double> pressure, std::span<double> s) {
  impl_->ops->to_forces(pressure, s);
}

void Bem3dSea::synthesize(std::span<const double> q, std::span<double> eta) { impl_->ops->to_surface(q, eta); }

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
