#include "fluid/bem3d.hpp"

#include <Eigen/Dense>
#include <Eigen/SparseCore>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <functional>
#include <numbers>
#include <optional>
#include <sstream>

#include "core/error.hpp"
#include "fluid/bem3d_panels.hpp"
#include "fluid/tank.hpp"
#include "fluid/waves.hpp"

namespace floesim::fluid {

namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;

std::shared_ptr<const DenseSetup> build(const SeaParams& p, double ratio, double near) {
  const auto start = std::chrono::steady_clock::now();
  auto since = [](std::chrono::steady_clock::time_point t) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
  };
  DenseSetup::Cost cost;
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
  // K = rho g A I + sigma L (five-point finite volumes, d eta / dn = 0 at the walls).
  std::vector<Eigen::Triplet<double>> entries;
  auto face = [&](int c0, int c1, double s) {
    entries.emplace_back(c0, c0, s);
    entries.emplace_back(c1, c1, s);
    entries.emplace_back(c0, c1, -s);
    entries.emplace_back(c1, c0, -s);
  };
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      const int c = j * nx + i;
      entries.emplace_back(c, c, p.rho * p.g * area);
      if (i + 1 < nx) face(c, c + 1, p.sigma * dy / dx);
      if (j + 1 < ny) face(c, c + nx, p.sigma * dx / dy);
    }
  Eigen::SparseMatrix<double> k(ns, ns);
  k.setFromTriplets(entries.begin(), entries.end());

  auto ops = std::make_shared<DenseSetup>();
  ops->panels = n;
  reduce_to_modes(k, m, phi, area, p.bem_modes, *ops);
  cost.modes = since(modes_start);
  cost.correction = ops->cost.correction;  // within cost.modes
  cost.seconds = since(start);
  ops->cost = cost;
  return ops;
}

// The set-up of a basin, cached process-wide (four kept: dense set-ups are
// large), keyed by everything that enters it.
DenseModalSea::Cached cached(const SeaParams& p, const SeaOptions& options) {
  if (!(options.bem_panel_ratio > 0.0))
    throw InputError("[sea] cells: the BEM panel ratio must be > 0");
  if (!(options.bem_near_field >= 1.0))
    throw InputError("[sea] cells: the BEM near-field reach must be >= 1 panel diameter");
  const double ratio = options.bem_panel_ratio, near = options.bem_near_field;
  std::ostringstream key;
  key.precision(17);
  key << p.size[0] << ' ' << p.size[1] << ' ' << p.cells[0] << ' ' << p.cells[1] << ' ' << p.depth << ' '
      << p.rho << ' ' << p.g << ' ' << p.sigma << ' ' << ratio << ' ' << near << " modes " << p.bem_modes;
  for (const auto& b : p.bottom) key << ' ' << b[0] << ',' << b[1];
  key << " grid " << p.bottom_nx << ' ' << p.bottom_ny;
  for (double z : p.bottom_grid) key << ' ' << z;
  return cached_setup<Bem3dSea>(key.str(), 4, [&] { return build(p, ratio, near); });
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
  std::optional<TankZones> tank;  // relaxation zones along x (fluid/tank.hpp)
  std::vector<double> tank_eta, tank_rate;
};

Bem3dSea::Bem3dSea(const SeaParams& params, const SeaOptions& options)
    : DenseModalSea(basin_grid(params), cached(params, options), params.bem_static_correction),
      impl_(std::make_unique<Impl>()) {
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

void Bem3dSea::compute_field(Field f, std::span<double> out) {
  Eigen::Map<VectorXd> o(out.data(), static_cast<Eigen::Index>(out.size()));
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
    case Field::elevation: o = surface_elevation(); break;
    case Field::velocity_z: synthesize(bank_.v(), out); break;
    case Field::slope_x: d_dx(surface_elevation()); break;
    case Field::slope_y: d_dy(surface_elevation()); break;
    case Field::velocity_x: d_dx(surface_potential()); break;
    case Field::velocity_y: d_dy(surface_potential()); break;
  }
}

}  // namespace floesim::fluid
