#include "contact/fracture/response.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "core/error.hpp"

namespace floesim::fracture {

namespace {

// Impulse fraction delivered by the half-sine pulse over [t0, t1]:
// integral of pi / (2 tau) sin(pi t / tau) = (cos(pi t0 / tau) - cos(pi t1 / tau)) / 2.
double pulse_fraction(double t0, double t1, double tau) {
  t0 = std::clamp(t0, 0.0, tau);
  t1 = std::clamp(t1, 0.0, tau);
  return 0.5 * (std::cos(M_PI * t0 / tau) - std::cos(M_PI * t1 / tau));
}

// U = j^T M^-1 j / 2 (J): the energy the impulses j would give the lumped masses m at once.
double blow_energy(const Eigen::VectorXd& j, const Eigen::VectorXd& m) {
  return 0.5 * j.cwiseAbs2().cwiseQuotient(m).sum();
}

// Updates the response's peaks with the state u at time t; returns its strain energy (J).
double observe_state(const ElasticModel& model, double t, const Eigen::VectorXd& u, Response& r) {
  const std::vector<Eigen::Vector3d> s = model.nodal_stress(u);
  Snapshot now;
  now.time = t;
  for (std::size_t i = 0; i < s.size(); ++i) {
    const double value = 0.5 * (s[i][0] + s[i][1]) + std::hypot(0.5 * (s[i][0] - s[i][1]), s[i][2]);  // sigma_1
    if (value > now.max_principal) {
      now.max_principal = value;
      now.node = i;
    }
  }
  if (!s.empty()) now.angle = principal(s[now.node]).angle;  // the direction where it matters only
  now.strain_energy = model.strain_energy(u);
  const double strain = now.strain_energy;
  const bool stress = now.max_principal > r.peak_stress.max_principal;
  const bool energy = now.strain_energy > r.peak_energy.strain_energy || r.peak_energy.u.size() == 0;
  if (stress) {
    r.peak_stress = now;
    r.peak_stress.u = u;
  }
  if (energy) {
    r.peak_energy = std::move(now);
    r.peak_energy.u = u;
  }
  return strain;
}

}  // namespace

Responder::Responder(const ElasticModel& model, const ResponseOptions& options) : model_(model), options_(options) {
  if (!(options.duration > 0.0) || !(options.load_radius > 0.0) || !(options.damping >= 0.0) || options.steps_per_pulse < 1 || options.max_steps < 1)
    throw RunError("fracture: duration > 0, load radius > 0 and positive step counts are required");
  const double c = model.wave_speed();
  const double d = std::max(model.diameter(), model.mesh().size);
  const double tau = options.duration;
  t_end_ = 2.0 * tau + 1.5 * d / c;
  dt_ = std::min(tau / options.steps_per_pulse, d / (4.0 * c));
  steps_ = static_cast<int>(std::ceil(t_end_ / dt_ - 1e-9));
  if (steps_ > options.max_steps) {
    steps_ = options.max_steps;
    dt_ = t_end_ / steps_;
  }
  t_end_ = steps_ * dt_;
  beta_ = 2.0 * options.damping * model.mesh().size / (M_PI * c);
  // The smallest patch of triangles around a node (the area its nodal stress averages over).
  std::vector<double> patch(model.mesh().node_count(), 0.0);
  for (std::size_t t = 0; t < model.mesh().triangles.size(); ++t)
    for (int i : model.mesh().triangles[t]) patch[static_cast<std::size_t>(i)] += model.mesh().area(t);
  min_patch_ = *std::min_element(patch.begin(), patch.end());
  eps_ = 1e-6 * (c / d) * (c / d);
}

Responder::~Responder() = default;

double Responder::stress_bound(std::span<const PointLoad> loads) {
  // Static part: its largest sigma_1, as respond() finds it (one solve).
  double bound = 0.0;
  const Eigen::VectorXd fs = nodal_loads(loads, false);
  if (fs.squaredNorm() > 0.0) {
    double largest = -std::numeric_limits<double>::infinity();
    for (const Eigen::Vector3d& s : model_.nodal_stress(solve_static(fs)))
      largest = std::max(largest, 0.5 * (s[0] + s[1]) + std::hypot(0.5 * (s[0] - s[1]), s[2]));
    bound = largest;
  }
  // Dynamic part: the energy bound (response.hpp).
  const bool dynamic = std::any_of(loads.begin(), loads.end(), [](const PointLoad& l) { return l.impulse; });
  if (dynamic) {
    const Eigen::VectorXd j = model_.relieve(nodal_loads(loads, true));
    bound += stress_of_energy(blow_energy(j, model_.lumped_mass()));
  }
  return bound;
}

double Responder::stress_of_energy(double energy) const {
  const Material& mat = model_.material();
  return std::sqrt(2.0 * mat.young * std::max(energy, 0.0) /
                   ((1.0 - mat.poisson * mat.poisson) * mat.thickness * min_patch_));
}

Eigen::VectorXd Responder::nodal_loads(std::span<const PointLoad> loads, bool impulses) const {
  Eigen::VectorXd f = Eigen::VectorXd::Zero(model_.dofs());
  for (const PointLoad& l : loads)
    if (l.impulse == impulses) model_.add_point_load(f, l.point, l.value, options_.load_radius);
  return f;
}

const SpdFactor& Responder::static_factor() {
  if (!static_) {
    const auto begin = std::chrono::steady_clock::now();
    Eigen::SparseMatrix<double> a = model_.stiffness();
    for (Eigen::Index i = 0; i < a.rows(); ++i) a.coeffRef(i, i) += eps_ * model_.lumped_mass()[i];
    static_ = std::make_unique<SpdFactor>(a);
    factor_seconds_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - begin).count();
  }
  return *static_;
}

Eigen::VectorXd Responder::solve_static(const Eigen::VectorXd& f) {
  const Eigen::VectorXd fr = model_.relieve(f);
  const SpdFactor& factor = static_factor();
  Eigen::VectorXd u = factor.solve(fr);
  u += factor.solve(fr - model_.stiffness() * u);  // refinement: K u = f_r, not (K + eps M) u
  model_.remove_rigid(u);
  return u;
}

Response Responder::respond(std::span<const PointLoad> loads, const Observer& observe, double level) {
  Response r;
  const Eigen::VectorXd fs = nodal_loads(loads, false);
  Eigen::VectorXd us = Eigen::VectorXd::Zero(model_.dofs());
  const bool statics = fs.squaredNorm() > 0.0;
  if (statics) us = solve_static(fs);
  const bool dynamic = std::any_of(loads.begin(), loads.end(), [](const PointLoad& l) { return l.impulse; });
  observe_state(model_, 0.0, us, r);
  if (observe) observe(0.0, us);
  if (!dynamic) return r;

  const double static_peak = r.peak_stress.max_principal;  // Pa, the static forces' largest nodal sigma_1
  const Eigen::VectorXd j = model_.relieve(nodal_loads(loads, true));
  const Eigen::VectorXd& m = model_.lumped_mass();
  const double root_blow = std::sqrt(blow_energy(j, m));  // sqrt(U), sqrt(J)
  const auto begin = std::chrono::steady_clock::now();
  const Eigen::SparseMatrix<double>& k = model_.stiffness();
  const double dt = dt_, tau = options_.duration;
  if (!dynamic_) {
    Eigen::SparseMatrix<double> a = (1.0 + 2.0 * beta_ / dt) * k;
    for (Eigen::Index i = 0; i < a.rows(); ++i) a.coeffRef(i, i) += 4.0 / (dt * dt) * m[i];
    dynamic_ = std::make_unique<SpdFactor>(a);
  }
  factor_seconds_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - begin).count();
  const Eigen::Index n = model_.dofs();
  Eigen::VectorXd u = Eigen::VectorXd::Zero(n), v = u, acc = u, rhs(n);
  r.steps = steps_;
  r.dt = dt;
  for (int step = 1; step <= steps_; ++step) {
    const double t = step * dt;
    // Force at t_{n+1}: the pulse's mean over the step (its impulse exactly).
    const double f_scale = pulse_fraction(t - dt, t, tau) / dt;
    rhs = f_scale * j + m.cwiseProduct(4.0 / (dt * dt) * u + 4.0 / dt * v + acc) + beta_ * (k * (2.0 / dt * u + v));
    const Eigen::VectorXd next = dynamic_->solve(rhs);
    const Eigen::VectorXd acc_next = 4.0 / (dt * dt) * (next - u) - 4.0 / dt * v - acc;
    v += 0.5 * dt * (acc + acc_next);
    acc = acc_next;
    u = next;
    if (!u.allFinite()) throw RunError("fracture: the percussion response is not finite");
    const Eigen::VectorXd total = us + u;
    const double strain = observe_state(model_, t, total, r);
    if (observe) observe(t, total);
    if (step < steps_ && r.peak_stress.max_principal < level) {
      // The energy bound of every later step (response.hpp).
      const double energy = 0.5 * v.dot(m.cwiseProduct(v)) + (statics ? model_.strain_energy(u) : strain);
      const double to_come = 0.5 * pulse_fraction(t - dt, t, tau) + pulse_fraction(t, tau, tau);
      const double root = std::sqrt(std::max(energy, 0.0)) + root_blow * to_come;
      const double later = static_peak + stress_of_energy(root * root);
      if (later + 1e-6 * std::abs(later) < level) {
        r.steps = step;
        r.cut_short = true;
        r.later_bound = later;
        return r;
      }
    }
  }
  return r;
}

}  // namespace floesim::fracture
