#pragma once
// The incident waves, for the floes' drag (docs/coupling.md, "Drag is
// relative to the incident waves"): the same sea as the run's (same [sea]
// and seed), never kicked by the floes. The sea is linear, so this is the
// run's sea minus what the floes displace and radiate.
//
// Its orbital velocity is kept as two snapshots, at t0 and t1 = t0 + tau, and
// read in between as (1 - w) u(t0) + w u(t1), w = (t - t0) / tau. Linear
// interpolation of a wave of frequency omega errs by at most
// (omega tau)^2 / 8 of its amplitude, so tau = T / 40 for the waves' period
// T (the peak period of a JONSWAP sea) gives 0.3% at omega = 2 pi / T. The
// incident sea then moves once per tau instead of once per step. A tau of 0
// takes the fields at every time asked.

#include <memory>
#include <string>
#include <span>
#include <vector>

#include "core/checkpoint.hpp"
#include "core/params.hpp"
#include "fluid/sea.hpp"

namespace floesim {

class IncidentSea {
public:
  // tau in seconds (0: no interpolation).
  IncidentSea(std::unique_ptr<fluid::Sea> sea, double tau);

  // The interval for the waves of `params`: a fortieth of their period (the
  // regular or standing wave's, from its wavelength if need be, or JONSWAP's
  // peak period); 0 when there is none.
  static double interval_for(const SeaParams& params);

  // Brings the snapshots to t0 <= t <= t1. t may not decrease from one call
  // to the next. With a sea in slabs, `halo` is as fluid::Sea::
  // set_field_halo: the snapshots taken from now on are windows of this
  // rank's slab of the incident sea and `halo` rows either side, and whole
  // ones (taken at construction or restored) are cut to that window (a
  // copy of its rows), and windows taken for a smaller halo are widened to
  // it from the other ranks' rows (fluid::Sea::widen_window: the halo grows
  // when the coupling's floes follow the run's sea's slabs away from this
  // sea's); halo < 0, whole snapshots. Collective in slabs: every rank
  // calls it with the same t and halo.
  void advance_to(double t, int halo = -1);
  // The weight w of the t1 snapshot at time t.
  double weight(double t) const;
  // The snapshots, read by global cell (fluid::RowWindow).
  fluid::RowWindow u0() const { return u0_.window(*sea_); }
  fluid::RowWindow v0() const { return v0_.window(*sea_); }
  fluid::RowWindow u1() const { return u1_.window(*sea_); }
  fluid::RowWindow v1() const { return v1_.window(*sea_); }

  // Restart (core/checkpoint.hpp): the sea's modal state and the snapshots.
  // In slabs saved_state() is collective and the snapshots are whole on
  // rank 0 alone (each rank's slab rows gathered there), empty elsewhere;
  // restore() takes whole ones on every rank (cut at the next advance_to).
  // restore() throws InputError if the state is not of this sea's size.
  IncidentState saved_state();
  void restore(const IncidentState& state);

private:
  // A field's rows [rows.first, rows.first + rows.rows) (modulo ny), x fastest.
  struct Snapshot {
    fluid::Sea::WindowRows rows;
    std::vector<double> values;
    int halo = -1;  // the halo its window was taken or widened for; -1: whole
    fluid::RowWindow window(const fluid::Sea& sea) const {
      return fluid::RowWindow(rows.first, rows.rows, sea.grid().nx, sea.grid().ny, values);
    }
  };
  void take(Snapshot& u, Snapshot& v);
  // A whole snapshot cut to `rows` (a copy of those rows).
  void cut(Snapshot& s, const fluid::Sea::WindowRows& rows, int halo) const;

  std::unique_ptr<fluid::Sea> sea_;
  double tau_ = 0.0;
  double t0_ = 0.0, t1_ = 0.0;
  int halo_ = -1;
  Snapshot u0_, v0_, u1_, v1_;
};

// A sea's modal state (every deferred kick applied) and back; restore_modal
// throws InputError naming `what` if the sizes differ (another grid).
ModalState save_modal(fluid::Sea& sea);
void restore_modal(fluid::Sea& sea, const ModalState& state, const std::string& what);

}  // namespace floesim
