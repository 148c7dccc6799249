#include "coupling/incident.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "core/error.hpp"
#include "fluid/waves.hpp"

namespace floesim {

IncidentSea::IncidentSea(std::unique_ptr<fluid::Sea> sea, double tau) : sea_(std::move(sea)), tau_(tau) {
  t0_ = t1_ = sea_->time();
  take(u1_, v1_);
  u0_ = u1_;
  v0_ = v1_;
}

double IncidentSea::interval_for(const SeaParams& params) {
  const WaveParams& w = params.waves;
  double period = 0.0;
  switch (w.kind) {
    case WaveKind::none: return 0.0;
    case WaveKind::jonswap: period = w.tp; break;
    case WaveKind::regular:
    case WaveKind::standing:
      period = w.period;
      if (!(period > 0.0) && w.wavelength > 0.0) {
        const fluid::Dispersion d = fluid::Dispersion::of(params);
        period = 2.0 * std::numbers::pi / d.omega(2.0 * std::numbers::pi / w.wavelength);
      }
      break;
  }
  return period > 0.0 ? period / 40.0 : 0.0;
}

void IncidentSea::take(std::vector<double>& u, std::vector<double>& v) {
  const std::span<const double> fu = sea_->field(fluid::Field::velocity_x).all();
  u.assign(fu.begin(), fu.end());
  const std::span<const double> fv = sea_->field(fluid::Field::velocity_y).all();
  v.assign(fv.begin(), fv.end());
}

void IncidentSea::advance_to(double t) {
  if (!(tau_ > 0.0)) {
    if (t > t1_) sea_->flow(t - t1_);
    t0_ = t1_ = std::max(t, t1_);
    take(u1_, v1_);
    return;
  }
  if (t1_ == t0_) {  // the first call: open the first interval
    sea_->flow(tau_);
    t1_ = t0_ + tau_;
    take(u1_, v1_);
  }
  while (t > t1_) {
    std::swap(u0_, u1_);
    std::swap(v0_, v1_);
    t0_ = t1_;
    sea_->flow(tau_);
    t1_ = t0_ + tau_;
    take(u1_, v1_);
  }
}

IncidentState IncidentSea::saved_state() {
  IncidentState s;
  s.present = true;
  s.sea = save_modal(*sea_);
  s.t0 = t0_;
  s.t1 = t1_;
  s.u0 = u0_;
  s.v0 = v0_;
  s.u1 = u1_;
  s.v1 = v1_;
  return s;
}

void IncidentSea::restore(const IncidentState& s) {
  if (!s.present || s.u0.size() != u0_.size() || s.u1.size() != u1_.size() || s.v0.size() != v0_.size() ||
      s.v1.size() != v1_.size())
    throw InputError("checkpoint: the incident waves' snapshots do not match this run's sea grid");
  restore_modal(*sea_, s.sea, "the incident waves");
  t0_ = s.t0;
  t1_ = s.t1;
  u0_ = s.u0;
  v0_ = s.v0;
  u1_ = s.u1;
  v1_ = s.v1;
}

ModalState save_modal(fluid::Sea& sea) {
  ModalState m;
  m.present = true;
  m.time = sea.time();
  // Every deferred kick applied; in slabs collective, and q, v on rank 0
  // only (the writer: the other ranks' saved state is not written).
  sea.gather_modal_state(m.q, m.v);
  const std::span<const double> held = sea.held_pressure();
  m.held_pressure.assign(held.begin(), held.end());
  return m;
}

void restore_modal(fluid::Sea& sea, const ModalState& m, const std::string& what) {
  if (!m.present || m.q.size() != sea.modal_size() || m.v.size() != sea.modal_size())
    throw InputError("checkpoint: the modal state of " + what + " has " + std::to_string(m.q.size()) +
                     " amplitudes, this run's sea has " + std::to_string(sea.modal_size()));
  sea.set_modal_state(m.q, m.v);  // in slabs each rank keeps its modes
  sea.set_time(m.time);
  if (!m.held_pressure.empty()) {
    if (!sea.has_static_part() || m.held_pressure.size() != sea.grid().size())
      throw InputError("checkpoint: " + what + " holds a pressure on " + std::to_string(m.held_pressure.size()) +
                       " nodes, this run's sea " +
                       (sea.has_static_part() ? "has " + std::to_string(sea.grid().size()) : std::string("has no static part")));
    sea.hold_pressure(m.held_pressure);
  }
}

double IncidentSea::weight(double t) const {
  return t1_ > t0_ ? std::clamp((t - t0_) / (t1_ - t0_), 0.0, 1.0) : 1.0;
}

}  // namespace floesim
