#include "fluid/modal.hpp"

#include <algorithm>
#include <cmath>
#include <utility>

#include "core/error.hpp"

namespace floesim::fluid {

ModalBank::ModalBank(std::vector<double> omega, std::vector<double> mass, std::vector<double> gain,
                     int components)
    : components_(components),
      omega_(std::move(omega)),
      mass_(std::move(mass)),
      gain_(std::move(gain)),
      q_(omega_.size() * static_cast<std::size_t>(components), 0.0),
      v_(q_.size(), 0.0),
      c_(omega_.size()),
      sw_(omega_.size()),
      ws_(omega_.size()) {
  FLOESIM_ASSERT(components == 1 || components == 2);
  FLOESIM_ASSERT(mass_.size() == omega_.size() && gain_.size() == omega_.size());
  distinct_ = omega_;
  std::sort(distinct_.begin(), distinct_.end());
  distinct_.erase(std::unique(distinct_.begin(), distinct_.end()), distinct_.end());
  level_.resize(omega_.size());
  for (std::size_t j = 0; j < omega_.size(); ++j)
    level_[j] = static_cast<std::uint32_t>(
        std::lower_bound(distinct_.begin(), distinct_.end(), omega_[j]) - distinct_.begin());
  dc_.resize(distinct_.size());
  dsw_.resize(distinct_.size());
  dws_.resize(distinct_.size());
}

void ModalBank::prepare(double dt) {
  if (cache_valid_ && dt == cached_dt_) return;
  for (std::size_t d = 0; d < distinct_.size(); ++d) {
    const double w = distinct_[d];
    if (w == 0.0) {
      dc_[d] = 1.0;
      dsw_[d] = dt;
      dws_[d] = 0.0;
    } else {
      const double s = std::sin(w * dt);
      dc_[d] = std::cos(w * dt);
      dsw_[d] = s / w;
      dws_[d] = w * s;
    }
  }
  for (std::size_t j = 0; j < omega_.size(); ++j) {
    const std::uint32_t d = level_[j];
    c_[j] = dc_[d];
    sw_[j] = dsw_[d];
    ws_[j] = dws_[d];
  }
  cached_dt_ = dt;
  cache_valid_ = true;
}

void ModalBank::flow(double dt) {
  prepare(dt);
  const std::size_t n = omega_.size();
  double* q = q_.data();
  double* v = v_.data();
  const double* c = c_.data();
  const double* sw = sw_.data();
  const double* ws = ws_.data();
  if (components_ == 2) {
    for (std::size_t j = 0; j < n; ++j) {
      const double q0 = q[2 * j], q1 = q[2 * j + 1];
      const double v0 = v[2 * j], v1 = v[2 * j + 1];
      q[2 * j] = c[j] * q0 + sw[j] * v0;
      q[2 * j + 1] = c[j] * q1 + sw[j] * v1;
      v[2 * j] = c[j] * v0 - ws[j] * q0;
      v[2 * j + 1] = c[j] * v1 - ws[j] * q1;
    }
  } else {
    for (std::size_t j = 0; j < n; ++j) {
      const double q0 = q[j], v0 = v[j];
      q[j] = c[j] * q0 + sw[j] * v0;
      v[j] = c[j] * v0 - ws[j] * q0;
    }
  }
}

void ModalBank::kick_flow(std::span<const Kick> kicks, double dt, double* q_out) {
  if (components_ != 2 || kicks.size() > 2) {
    for (const Kick& k : kicks) kick(std::span<const double>(k.s, v_.size()), k.h);
    flow(dt);
    if (q_out) std::copy(q_.begin(), q_.end(), q_out);
    return;
  }
  kick_flow(kicks, dt, q_out, 0, omega_.size());
}

void ModalBank::kick_flow(std::span<const Kick> kicks, double dt, double* q_out, std::size_t first, std::size_t last) {
  FLOESIM_ASSERT(components_ == 2 && kicks.size() <= 2 && first <= last && last <= omega_.size());
  prepare(dt);
  double* q = q_.data();
  double* v = v_.data();
  const double* c = c_.data();
  const double* sw = sw_.data();
  const double* ws = ws_.data();
  const double* g = gain_.data();
  // Unused kick slots read a zero impulse from the first one (h = 0).
  const double* s0 = kicks.size() > 0 ? kicks[0].s : q;
  const double* s1 = kicks.size() > 1 ? kicks[1].s : s0;
  const double h0 = kicks.size() > 0 ? kicks[0].h : 0.0;
  const double h1 = kicks.size() > 1 ? kicks[1].h : 0.0;
  for (std::size_t j = first; j < last; ++j) {
    const double a0 = h0 * g[j], a1 = h1 * g[j];
    const double q0 = q[2 * j], q1 = q[2 * j + 1];
    const double v0 = v[2 * j] + a0 * s0[2 * j] + a1 * s1[2 * j];
    const double v1 = v[2 * j + 1] + a0 * s0[2 * j + 1] + a1 * s1[2 * j + 1];
    const double nq0 = c[j] * q0 + sw[j] * v0, nq1 = c[j] * q1 + sw[j] * v1;
    q[2 * j] = nq0;
    q[2 * j + 1] = nq1;
    v[2 * j] = c[j] * v0 - ws[j] * q0;
    v[2 * j + 1] = c[j] * v1 - ws[j] * q1;
    if (q_out) {
      q_out[2 * j] = nq0;
      q_out[2 * j + 1] = nq1;
    }
  }
}

void ModalBank::kick(std::span<const double> s, double h) {
  FLOESIM_ASSERT(s.size() == v_.size());
  const std::size_t n = omega_.size();
  double* v = v_.data();
  const double* g = gain_.data();
  const double* f = s.data();
  if (components_ == 2) {
    for (std::size_t j = 0; j < n; ++j) {
      const double a = h * g[j];
      v[2 * j] += a * f[2 * j];
      v[2 * j + 1] += a * f[2 * j + 1];
    }
  } else {
    for (std::size_t j = 0; j < n; ++j) v[j] += h * g[j] * f[j];
  }
}

void ModalBank::midpoint(std::span<const double> s, double h) {
  FLOESIM_ASSERT(s.empty() || s.size() == v_.size());
  const auto m = static_cast<std::size_t>(components_);
  for (std::size_t j = 0; j < omega_.size(); ++j) {
    const double w2 = omega_[j] * omega_[j], den = 1.0 + 0.25 * h * h * w2;
    for (std::size_t c = 0; c < m; ++c) {
      const std::size_t i = j * m + c;
      const double a = s.empty() ? 0.0 : gain_[j] * s[i];
      const double q0 = q_[i];
      const double q1 = ((1.0 - 0.25 * h * h * w2) * q0 + h * v_[i] + 0.5 * h * h * a) / den;
      v_[i] += h * (a - 0.5 * w2 * (q0 + q1));
      q_[i] = q1;
    }
  }
}

void ModalBank::midpoint_free(double h, std::span<double> q_out) const {
  FLOESIM_ASSERT(q_out.size() == q_.size());
  const auto m = static_cast<std::size_t>(components_);
  for (std::size_t j = 0; j < omega_.size(); ++j) {
    const double w2 = omega_[j] * omega_[j], den = 1.0 + 0.25 * h * h * w2;
    for (std::size_t c = 0; c < m; ++c) {
      const std::size_t i = j * m + c;
      q_out[i] = ((1.0 - 0.25 * h * h * w2) * q_[i] + h * v_[i]) / den;
    }
  }
}

void ModalBank::midpoint_response(std::span<const double> s, double h, std::span<double> q_out) const {
  FLOESIM_ASSERT(s.size() == q_.size() && q_out.size() == q_.size());
  const auto m = static_cast<std::size_t>(components_);
  for (std::size_t j = 0; j < omega_.size(); ++j) {
    const double r = 0.5 * h * h * gain_[j] / (1.0 + 0.25 * h * h * omega_[j] * omega_[j]);
    for (std::size_t c = 0; c < m; ++c) q_out[j * m + c] = r * s[j * m + c];
  }
}

namespace {

// Mode j's term of 1/2 sum_j weight_j |a_j|^2 (before the 1/2): its components' squares summed from 0.
double weighted_norm2_term(const double* a, double weight, std::size_t components) {
  double a2 = 0.0;
  for (std::size_t c = 0; c < components; ++c) a2 += a[c] * a[c];
  return weight * a2;
}

// 1/2 sum_j weight_j |a_j|^2 over the components of each mode.
double half_weighted_norm2(std::span<const double> a, std::span<const double> weight, int components,
                           bool square_omega, std::span<const double> omega) {
  const auto m = static_cast<std::size_t>(components);
  double e = 0.0;
  for (std::size_t j = 0; j < weight.size(); ++j)
    e += weighted_norm2_term(&a[j * m], square_omega ? weight[j] * omega[j] * omega[j] : weight[j], m);
  return 0.5 * e;
}

}  // namespace

double ModalBank::kinetic() const {
  return half_weighted_norm2(v_, mass_, components_, false, omega_);
}

double ModalBank::potential() const {
  return half_weighted_norm2(q_, mass_, components_, true, omega_);
}

void ModalBank::energy_terms(std::span<double> kinetic, std::span<double> potential) const {
  FLOESIM_ASSERT(kinetic.size() == omega_.size() && potential.size() == omega_.size());
  const auto m = static_cast<std::size_t>(components_);
  for (std::size_t j = 0; j < omega_.size(); ++j) {
    kinetic[j] = weighted_norm2_term(&v_[j * m], mass_[j], m);
    potential[j] = weighted_norm2_term(&q_[j * m], mass_[j] * omega_[j] * omega_[j], m);
  }
}

std::size_t ModalBank::mode_bytes() const {
  return sizeof(double) * (omega_.size() + mass_.size() + gain_.size() + q_.size() + v_.size() + c_.size() +
                           sw_.size() + ws_.size()) +
         sizeof(std::uint32_t) * level_.size();
}

std::size_t ModalBank::frequency_bytes() const {
  return sizeof(double) * (distinct_.size() + dc_.size() + dsw_.size() + dws_.size());
}

}  // namespace floesim::fluid
