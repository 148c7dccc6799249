#include "fluid/modal.hpp"

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
}

void ModalBank::prepare(double dt) {
  if (cache_valid_ && dt == cached_dt_) return;
  for (std::size_t j = 0; j < omega_.size(); ++j) {
    const double w = omega_[j];
    if (w == 0.0) {
      c_[j] = 1.0;
      sw_[j] = dt;
      ws_[j] = 0.0;
    } else {
      const double s = std::sin(w * dt);
      c_[j] = std::cos(w * dt);
      sw_[j] = s / w;
      ws_[j] = w * s;
    }
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

void ModalBank::kick(std::span<const double> s, double h) {
  FLOESIM_ASSERT(s.size() == v_.size());
  const std::size_t n = omega_.size();
  const auto m = static_cast<std::size_t>(components_);
  for (std::size_t j = 0; j < n; ++j) {
    const double a = h * gain_[j];
    for (std::size_t c = 0; c < m; ++c) v_[j * m + c] += a * s[j * m + c];
  }
}

double ModalBank::kinetic() const {
  const auto m = static_cast<std::size_t>(components_);
  double e = 0.0;
  for (std::size_t j = 0; j < omega_.size(); ++j) {
    double v2 = 0.0;
    for (std::size_t c = 0; c < m; ++c) v2 += v_[j * m + c] * v_[j * m + c];
    e += mass_[j] * v2;
  }
  return 0.5 * e;
}

double ModalBank::potential() const {
  const auto m = static_cast<std::size_t>(components_);
  double e = 0.0;
  for (std::size_t j = 0; j < omega_.size(); ++j) {
    double q2 = 0.0;
    for (std::size_t c = 0; c < m; ++c) q2 += q_[j * m + c] * q_[j * m + c];
    e += mass_[j] * omega_[j] * omega_[j] * q2;
  }
  return 0.5 * e;
}

}  // namespace floesim::fluid
