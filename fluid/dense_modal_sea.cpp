#include "fluid/dense_modal_sea.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <vector>

#include "core/error.hpp"
#include "fluid/lowest_modes.hpp"

namespace floesim::fluid {

using Eigen::MatrixXd;
using Eigen::VectorXd;

namespace {

// S -> H S H for the Householder reflection H = I - beta v v^T (S symmetric).
void reflect(MatrixXd& s, const VectorXd& v, double beta) {
  const VectorXd w = s * v;
  const double vw = v.dot(w);
  s.noalias() -= beta * (v * w.transpose() + w * v.transpose());
  s.noalias() += (beta * beta * vw) * (v * v.transpose());
}

// All the modes: H = I - beta v v^T, v = 1 + sqrt(n) e_0, maps the constants
// onto the first axis; its other columns span the zero-mean surfaces, where
// the dense generalised eigenproblem is solved.
void all_modes(MatrixXd k, MatrixXd m, DenseModes& out) {
  const Eigen::Index ns = k.rows();
  VectorXd v = VectorXd::Ones(ns);
  v(0) += std::sqrt(static_cast<double>(ns));
  const double beta = 2.0 / v.squaredNorm();
  reflect(k, v, beta);
  reflect(m, v, beta);
  Eigen::GeneralizedSelfAdjointEigenSolver<MatrixXd> eig(k.bottomRightCorner(ns - 1, ns - 1),
                                                         m.bottomRightCorner(ns - 1, ns - 1));
  if (eig.info() != Eigen::Success) throw RunError("fluid: the BEM eigenproblem (a_sf, m_sf) did not converge");
  out.x = MatrixXd::Zero(ns, ns - 1);
  out.x.bottomRows(ns - 1) = eig.eigenvectors();
  const Eigen::RowVectorXd vx = v.transpose() * out.x;
  out.x.noalias() -= beta * v * vx;
  out.omega.resize(static_cast<std::size_t>(ns - 1));
  for (Eigen::Index j = 0; j < ns - 1; ++j)
    out.omega[static_cast<std::size_t>(j)] = std::sqrt(std::max(0.0, eig.eigenvalues()(j)));
}

}  // namespace

void reduce_to_modes(const Eigen::SparseMatrix<double>& a_sf, const MatrixXd& m_sf, const MatrixXd& phi, double weight,
                     int count, DenseSetup& out) {
  out.surface = static_cast<int>(m_sf.rows());
  out.weight = weight;
  if (count == 0) {
    all_modes(MatrixXd(a_sf), m_sf, out);
  } else {
    LowestModesOptions options;
    options.count = count;
    LowestModes low = lowest_modes(m_sf, a_sf, options);
    out.omega = std::move(low.omega);
    out.x = std::move(low.x);
  }
  out.load = -weight * out.x.transpose();
  out.project = out.x.transpose() * m_sf;
  out.potential = phi * out.x;
  if (count > 0) {
    const auto start = std::chrono::steady_clock::now();
    out.correction = std::make_shared<const StaticCorrection>(a_sf, out.omega);
    out.cost.correction = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }
}

DenseModalSea::DenseModalSea(const SurfaceGrid& grid, Cached setup, bool correct)
    : Sea(grid), setup_(std::move(setup.setup)), hit_(setup.hit), correct_(correct) {
  FLOESIM_ASSERT(!correct_ || setup_->correction);
  const std::size_t nm = setup_->omega.size();
  bank_ = ModalBank(setup_->omega, std::vector<double>(nm, 1.0), std::vector<double>(nm, 1.0), 1);
  work_modes_.resize(static_cast<Eigen::Index>(nm));
  work_surface_.resize(setup_->surface);
}

void DenseModalSea::kick(std::span<const double> pressure, double h) {
  FLOESIM_ASSERT(pressure.size() == static_cast<std::size_t>(setup_->surface));
  kicked_ = true;
  project(pressure, {work_modes_.data(), static_cast<std::size_t>(work_modes_.size())});  // kept for repeat_kick
  repeat_kick(h);
}

void DenseModalSea::repeat_kick(double h) {
  FLOESIM_ASSERT(kicked_);
  bank_.kick(std::span<const double>(work_modes_.data(), bank_.modes()), h);
  invalidate_rates();
}

void DenseModalSea::set_surface(std::span<const double> eta, std::span<const double> eta_t) {
  setup_->to_modes(eta, bank_.q(), work_surface_);
  setup_->to_modes(eta_t, bank_.v(), work_surface_);
  invalidate();
}

void DenseModalSea::project(std::span<const double> pressure, std::span<double> s) { setup_->to_forces(pressure, s); }

void DenseModalSea::synthesize(std::span<const double> q, std::span<double> eta) { setup_->to_surface(q, eta); }

const VectorXd& DenseModalSea::surface_elevation() {
  const Eigen::Map<const VectorXd> q(bank_.q().data(), static_cast<Eigen::Index>(bank_.modes()));
  work_surface_.noalias() = setup_->x * q;
  if (held_) work_surface_ += held_eta_;
  return work_surface_;
}

void DenseModalSea::static_response(std::span<const double> pressure, std::span<const double> s, VectorXd& out) {
  const Eigen::Map<const VectorXd> p(pressure.data(), setup_->surface);
  load_ = -setup_->weight * p;
  setup_->correction->apply(setup_->x, load_, s, out, centred_, modal_);
}

void DenseModalSea::hold(std::span<const double> pressure, std::span<const double> s) {
  if (!correct_) return;
  static_response(pressure, s, held_eta_);
  held_pressure_.assign(pressure.begin(), pressure.end());
  held_potential_ = 0.5 * load_.dot(held_eta_);  // 1/2 F^T R F
  held_ = true;
  invalidate();
}

void DenseModalSea::add_static_response(std::span<const double> pressure, std::span<const double> s,
                                        std::span<double> eta) {
  if (!correct_) return;
  static_response(pressure, s, response_);
  Eigen::Map<VectorXd>(eta.data(), setup_->surface) += response_;
}

const VectorXd& DenseModalSea::surface_potential() {
  const Eigen::Map<const VectorXd> v(bank_.v().data(), static_cast<Eigen::Index>(bank_.modes()));
  work_surface_.noalias() = setup_->potential * v;
  return work_surface_;
}

}  // namespace floesim::fluid
