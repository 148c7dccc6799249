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

void IncidentSea::take(Snapshot& u, Snapshot& v) {
  // The sea's fields are read here only: their storage is given back once
  // copied (the y-velocity's spectrum, made with the x-velocity's, stays
  // staged in the sea).
  sea_->set_field_halo(halo_);
  for (auto [field, s] : {std::pair{fluid::Field::velocity_x, &u}, std::pair{fluid::Field::velocity_y, &v}}) {
    const fluid::RowWindow w = sea_->field(field);
    s->rows = {w.first_row(), w.rows()};
    s->halo = sea_->in_slabs() ? halo_ : -1;
    s->values.assign(w.values().begin(), w.values().end());
    sea_->release_field(field);
  }
  sea_->set_field_halo(-1);
}

void IncidentSea::cut(Snapshot& s, const fluid::Sea::WindowRows& rows, int halo) const {
  const fluid::SurfaceGrid& g = sea_->grid();
  if (s.halo >= 0 || rows.rows == g.ny) return;  // only whole ones are cut
  const auto nx = static_cast<std::size_t>(g.nx);
  std::vector<double> kept(static_cast<std::size_t>(rows.rows) * nx);
  for (int j = 0; j < rows.rows; ++j) {
    const auto y = static_cast<std::size_t>((rows.first + j) % g.ny);
    std::copy_n(s.values.begin() + static_cast<std::ptrdiff_t>(y * nx), nx,
                kept.begin() + static_cast<std::ptrdiff_t>(static_cast<std::size_t>(j) * nx));
  }
  s.values = std::move(kept);
  s.rows = rows;
  s.halo = halo;
}

void IncidentSea::advance_to(double t, int halo) {
  halo_ = halo;
  if (sea_->in_slabs() && halo >= 0) {
    const fluid::Sea::WindowRows rows = sea_->field_rows(halo);
    for (Snapshot* s : {&u0_, &v0_, &u1_, &v1_}) {
      cut(*s, rows, halo);
      // s.halo is the same on every rank: all widen, or none.
      if (s->halo >= 0 && s->halo < halo) {
        sea_->widen_window(s->values, s->rows, halo);
        s->halo = halo;
      }
    }
  }
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
  // Whole on rank 0 (in slabs each rank's slab rows gathered there).
  sea_->gather_to_writer_rows(u0(), s.u0);
  sea_->gather_to_writer_rows(v0(), s.v0);
  sea_->gather_to_writer_rows(u1(), s.u1);
  sea_->gather_to_writer_rows(v1(), s.v1);
  return s;
}

void IncidentSea::restore(const IncidentState& s) {
  const std::size_t n = sea_->grid().size();
  if (!s.present || s.u0.size() != n || s.u1.size() != n || s.v0.size() != n || s.v1.size() != n)
    throw InputError("checkpoint: the incident waves' snapshots do not match this run's sea grid");
  restore_modal(*sea_, s.sea, "the incident waves");
  t0_ = s.t0;
  t1_ = s.t1;
  const fluid::Sea::WindowRows whole{0, sea_->grid().ny};
  u0_ = {whole, s.u0};
  v0_ = {whole, s.v0};
  u1_ = {whole, s.u1};
  v1_ = {whole, s.v1};
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
