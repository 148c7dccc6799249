#include "coupling/penalty_step.hpp"

#include <algorithm>
#include <cmath>

#include "coupling/parallel.hpp"
#include "coupling/penalty_law.hpp"

namespace floesim {

using parallel::for_each_index;
using parallel::for_each_of;

namespace {

// (1, r_k) restricted to the slopes the body resists.
Eigen::Vector3d lever_basis(const Vec2& r, std::uint8_t slopes) {
  return {1.0, slopes >= 1 ? r.x() : 0.0, slopes >= 2 ? r.y() : 0.0};
}

}  // namespace

void PenaltyStepSolver::apply_g(const PenaltyStepProblem& p, const SeaResponse& sea, std::span<const double> u,
                                std::span<double> out, int threads) {
  sea(u, out);
  // Each body's pieces rise with its bottom: h^2 / 2 M^-1 of the forces'
  // resultant and moments (the inverse mass is zero on slopes it does not have).
  const double hh = 0.5 * p.step * p.step;
  for_each_of(p.bodies, threads, [&](std::uint32_t i) {
    Eigen::Vector3d F = Eigen::Vector3d::Zero();
    for (std::size_t k = p.offsets[i]; k < p.offsets[i + 1]; ++k)
      F += u[k] * Eigen::Vector3d(1.0, p.lever[k].x(), p.lever[k].y());
    const Eigen::Vector3d x = hh * (p.inertia[i].inverse_mass * F);
    for (std::size_t k = p.offsets[i]; k < p.offsets[i + 1]; ++k)
      out[k] += x[0] + x[1] * p.lever[k].x() + x[2] * p.lever[k].y();
  });
  ++responses_;
}

void PenaltyStepSolver::residual(const PenaltyStepProblem& p, const SeaResponse& sea, std::span<const double> d,
                                 std::vector<double>& force, std::vector<double>& out, int threads) {
  for_each_index(d.size(), threads,
                 [&](std::size_t k) { force[k] = step_force(p.spring[k], p.damper[k], p.start[k], d[k]).f; });
  apply_g(p, sea, force, out, threads);
  for_each_index(d.size(), threads, [&](std::size_t k) { out[k] += d[k] - p.free_end[k]; });
}

void PenaltyStepSolver::factor_preconditioner(const PenaltyStepProblem& p, int threads) {
  // Per body: C^-1 + U^T E U with C^-1 = M / (h^2 / 2), U = S Phi, E = (I + S D S)^-1.
  const double hh = 0.5 * p.step * p.step;
  small_.resize(p.inertia.size());
  for_each_of(p.bodies, threads, [&](std::uint32_t i) {
    Eigen::Matrix3d utu = Eigen::Matrix3d::Zero();
    for (std::size_t k = p.offsets[i]; k < p.offsets[i + 1]; ++k) {
      const Eigen::Vector3d u = sq_[k] * lever_basis(p.lever[k], p.inertia[i].slopes);
      utu += einv_[k] * u * u.transpose();
    }
    small_[i].compute(p.inertia[i].mass / hh + utu);
  });
}

void PenaltyStepSolver::precondition(const PenaltyStepProblem& p, std::span<const double> in, std::span<double> out,
                                     int threads) const {
  for_each_of(p.bodies, threads, [&](std::uint32_t i) {
    const std::uint8_t slopes = p.inertia[i].slopes;
    Eigen::Vector3d t = Eigen::Vector3d::Zero();
    for (std::size_t k = p.offsets[i]; k < p.offsets[i + 1]; ++k) {
      out[k] = einv_[k] * in[k];
      t += sq_[k] * out[k] * lever_basis(p.lever[k], slopes);
    }
    const Eigen::Vector3d y = small_[i].solve(t);
    for (std::size_t k = p.offsets[i]; k < p.offsets[i + 1]; ++k)
      out[k] -= einv_[k] * sq_[k] * lever_basis(p.lever[k], slopes).dot(y);
  });
}

std::array<double, 2> PenaltyStepSolver::reduce_dots(const PenaltyStepProblem& p, std::span<const double> a,
                                                     std::span<const double> b, std::span<const double> c,
                                                     std::span<const double> d, bool two) {
  // Each body's terms in its pieces' order, on any thread (the same bits);
  // then the bodies' partials exactly, in whatever order they are listed.
  const std::size_t m = p.bodies.size();
  partial_.resize(2 * m);
  for_each_index(m, threads_, [&](std::size_t j) {
    const std::uint32_t i = p.bodies[j];
    double s = 0.0, t = 0.0;
    if (two) {
      for (std::size_t k = p.offsets[i]; k < p.offsets[i + 1]; ++k) {
        s += a[k] * b[k];
        t += c[k] * d[k];
      }
    } else {
      for (std::size_t k = p.offsets[i]; k < p.offsets[i + 1]; ++k) s += a[k] * b[k];
    }
    partial_[2 * j] = s;
    partial_[2 * j + 1] = t;
  }, static_cast<std::size_t>(parallel::kFloesPerThread));
  std::array<ExactSum, 2> sums;
  for (std::size_t j = 0; j < m; ++j) {
    sums[0].add(partial_[2 * j]);
    if (two) sums[1].add(partial_[2 * j + 1]);
  }
  if (reduction_->sum) reduction_->sum(std::span<ExactSum>(sums.data(), two ? 2 : 1));
  return {sums[0].value(), sums[1].value()};
}

double PenaltyStepSolver::max_abs(const PenaltyStepProblem& p, std::span<const double> x) const {
  double m = 0.0;
  for (const std::uint32_t i : p.bodies)
    for (std::size_t k = p.offsets[i]; k < p.offsets[i + 1]; ++k) m = std::max(m, std::abs(x[k]));
  return reduction_->max ? reduction_->max(m) : m;
}

long PenaltyStepSolver::conjugate_gradients(const PenaltyStepProblem& p, const SeaResponse& sea, double eta,
                                            int max_iterations, int threads) {
  // On entry r_ holds the right-hand side b (w = 0); on exit w_ the solution
  // and gsw_ = G S w, summed from the products G S dir the iteration makes
  // anyway (the Newton step needs it: one application of G saved). r . z and
  // r . r of the same r come from one reduction: two an iteration.
  const std::size_t n = r_.size();
  std::fill(w_.begin(), w_.end(), 0.0);
  std::fill(gsw_.begin(), gsw_.end(), 0.0);
  precondition(p, r_, z_, threads);
  auto [rz, rr] = dots(p, r_, z_, r_, r_);
  const double bound = eta * std::sqrt(rr);
  dir_ = z_;
  long it = 0;
  for (; it < max_iterations && std::sqrt(rr) > bound; ++it) {
    for_each_index(n, threads, [&](std::size_t k) { tmp_[k] = sq_[k] * dir_[k]; });
    apply_g(p, sea, tmp_, gdir_, threads);
    for_each_index(n, threads, [&](std::size_t k) { Ap_[k] = dir_[k] + sq_[k] * gdir_[k]; });
    const double alpha = rz / dot(p, dir_, Ap_);
    for_each_index(n, threads, [&](std::size_t k) {
      w_[k] += alpha * dir_[k];
      gsw_[k] += alpha * gdir_[k];
      r_[k] -= alpha * Ap_[k];
    });
    precondition(p, r_, z_, threads);
    const auto [rz_new, rr_new] = dots(p, r_, z_, r_, r_);
    const double beta = rz_new / rz;
    for_each_index(n, threads, [&](std::size_t k) { dir_[k] = z_[k] + beta * dir_[k]; });
    rz = rz_new;
    rr = rr_new;
  }
  return it;
}

PenaltyStepResult PenaltyStepSolver::solve(const PenaltyStepProblem& p, const SeaResponse& sea,
                                           const PenaltyStepOptions& options) {
  const int threads = std::max(options.threads, 1);
  threads_ = threads;
  reduction_ = &options.reduction;
  const std::size_t n = p.start.size();
  for (auto* v : {&d1_, &f_, &R_, &sq_, &einv_, &w_, &r_, &z_, &dir_, &Ap_, &tmp_, &gdir_, &gsw_, &step_, &trial_, &ftrial_, &Rtrial_})
    v->assign(n, 0.0);
  responses_ = 0;
  PenaltyStepResult result;

  // The start: the forces at t held over the step, or d0.
  if (options.predictor) {
    for_each_index(n, threads, [&](std::size_t k) {
      f_[k] = step_force(p.spring[k], p.damper[k], p.start[k], p.start[k]).f;
    });
    apply_g(p, sea, f_, tmp_, threads);
    for_each_index(n, threads, [&](std::size_t k) { d1_[k] = p.free_end[k] - tmp_[k]; });
  } else if (!p.guess.empty()) {
    std::copy(p.guess.begin(), p.guess.end(), d1_.begin());
  } else {
    std::copy(p.start.begin(), p.start.end(), d1_.begin());
  }
  residual(p, sea, d1_, f_, R_, threads);
  double norm = max_abs(p, R_);
  double norm2 = -1.0;  // |R|_2 (< 0: not yet summed)

  const double self = p.self_response;
  double cap = options.forcing;  // the loosest relative tolerance allowed now
  double previous = 0.0;  // the last Newton step's starting residual
  for (; norm > p.tolerance; ++result.newton) {
    if (result.newton == options.max_newton) {
      result.status = PenaltyStepStatus::newton_limit;
      break;
    }
    for_each_index(n, threads, [&](std::size_t k) {
      const double df = step_force(p.spring[k], p.damper[k], p.start[k], d1_[k]).df;
      sq_[k] = std::sqrt(df);
      einv_[k] = 1.0 / (1.0 + df * self);
      r_[k] = -sq_[k] * R_[k];
    });
    factor_preconditioner(p, threads);
    // How tightly this Newton step is solved (the header's "Inexact Newton").
    const double by_tolerance = options.forcing_safety * p.tolerance / norm;
    const double by_decrease = previous > 0.0 ? (norm / previous) * (norm / previous) : cap;
    const bool aims_at_tolerance = by_tolerance >= by_decrease && by_tolerance < cap;
    const double eta = std::clamp(std::max(by_tolerance, by_decrease), options.cg_tolerance, std::max(cap, options.cg_tolerance));
    result.cg += conjugate_gradients(p, sea, eta, options.max_cg, threads);

    // The Newton step s = -R - G S w.
    for_each_index(n, threads, [&](std::size_t k) { step_[k] = -R_[k] - gsw_[k]; });
    // Backtracking on the residual's 2-norm (the accepted trial's is the
    // next step's: one reduction a trial).
    if (norm2 < 0.0) norm2 = std::sqrt(dot(p, R_, R_));
    double t = 1.0, norm2_new = 0.0;
    for (;;) {
      for_each_index(n, threads, [&](std::size_t k) { trial_[k] = d1_[k] + t * step_[k]; });
      residual(p, sea, trial_, ftrial_, Rtrial_, threads);
      norm2_new = std::sqrt(dot(p, Rtrial_, Rtrial_));
      if (norm2_new < (1.0 - 1e-4 * t) * norm2 || t < 1e-6) break;
      t *= 0.5;
    }
    d1_.swap(trial_);
    f_.swap(ftrial_);
    R_.swap(Rtrial_);
    previous = norm;
    norm = max_abs(p, R_);
    // An inexact step that missed the tolerance it aimed at: the scaled norm
    // did not bound the residual; solve tightly from now on. One that barely
    // reduced the residual: solve tighter.
    if (norm > p.tolerance && eta > options.cg_tolerance) {
      if (aims_at_tolerance) cap = options.cg_tolerance;
      else if (norm2_new > options.stall_ratio * norm2) cap = std::max(cap * options.forcing_cut, options.cg_tolerance);
    }
    norm2 = norm2_new;
  }
  result.residual = norm;
  result.responses = responses_;
  return result;
}

}  // namespace floesim
