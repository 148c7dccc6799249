#pragma once
// The modal integrator shared by every sea backend.
//
// The linearised surface equation m_sf(eta'', v) + a_sf(eta, v) = -∫ p v
// (MODEL.md §3), written in any basis that diagonalises m_sf and a_sf together
// (Fourier modes of a periodic box; the generalised eigenvectors of a BEM
// basin), is a bank of independent oscillators
//
//     q_j'' + omega_j^2 q_j = gain_j s_j(p),
//
// where q_j is the modal amplitude, s_j(p) the projection of the pressure on
// mode j (computed by the backend: an FFT, or X^T D p) and gain_j turns it into
// an acceleration. A mode has `components` real amplitudes sharing omega_j (2 for
// a complex Fourier coefficient, 1 for a real eigenvector).
//
// Two operators, each exact:
//   flow(dt): free evolution, a rotation of (q_j, q_j'/omega_j) by omega_j dt.
//             No stability limit from gravity or capillarity. A mode with
//             omega_j = 0 drifts, q += v dt.
//   kick(s, h): v_j += h gain_j s_j (the impulse of a pressure held over h).
// A forced step is their Strang composition kick(h/2) flow(h) kick(h/2):
// second order in dt and symplectic.
//
// Energy of the bank: kinetic 1/2 sum mass_j |v_j|^2 = 1/2 m_sf(eta', eta'),
// potential 1/2 sum mass_j omega_j^2 |q_j|^2 = 1/2 a_sf(eta, eta). A frozen
// mode (the mean of the surface, held at zero for volume conservation) has
// mass 0 and gain 0.

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace floesim::fluid {

class ModalBank {
public:
  ModalBank() = default;
  // omega (rad/s), mass (J per unit amplitude^2 per (rad/s)^2) and gain, one per mode.
  ModalBank(std::vector<double> omega, std::vector<double> mass, std::vector<double> gain,
            int components);

  std::size_t modes() const { return omega_.size(); }
  int components() const { return components_; }

  // Modal amplitudes and rates, contiguous: mode j, component c at j * components + c.
  std::span<double> q() { return q_; }
  std::span<double> v() { return v_; }
  std::span<const double> q() const { return q_; }
  std::span<const double> v() const { return v_; }
  std::span<const double> omega() const { return omega_; }
  std::span<const double> mass() const { return mass_; }
  std::span<const double> gain() const { return gain_; }

  // Exact free evolution over dt (any sign). The rotation coefficients are
  // cached for the last dt: a change of dt costs one sin/cos per distinct omega.
  void flow(double dt);
  // v += h * gain * s, s laid out like v.
  void kick(std::span<const double> s, double h);

  // The same operations fused in one pass over the modes (memory-bound banks):
  // the kicks, then flow(dt); if q_out is not null the new q is also written there.
  struct Kick {
    const double* s;
    double h;
  };
  void kick_flow(std::span<const Kick> kicks, double dt, double* q_out = nullptr);
  // The same on modes [first, last) only (components = 2, at most two
  // kicks); the other modes are left as they were. Each mode's arithmetic
  // is kick_flow's, so a bank stepped in ranges equals one stepped whole.
  void kick_flow(std::span<const Kick> kicks, double dt, double* q_out, std::size_t first, std::size_t last);

  // The implicit midpoint rule (for this linear bank, the trapezoidal rule)
  // over h with the load s held over the step (laid out like v; empty: none):
  //     q1 = ((1 - h^2 w^2 / 4) q0 + h v0 + h^2 / 2 g s) / (1 + h^2 w^2 / 4),
  //     v1 = v0 - h w^2 (q0 + q1) / 2 + h g s,
  // the solution of q1 - q0 = h (v0 + v1) / 2, v1 - v0 = h (-w^2 (q0 + q1) / 2 + g s).
  // Stable for every h, it conserves 1/2 mass (v^2 + w^2 q^2) exactly when
  // s = 0, and the work of s is s . (q1 - q0) exactly: the sea's share of the
  // coupled energy balance of the implicit floe–sea step (docs/coupling.md).
  // Its frequency is 2 atan(w h / 2) / h: a phase error (w h)^2 / 12.
  void midpoint(std::span<const double> s, double h);
  // q1 of midpoint() without changing the state: with no load (free), or the
  // part due to the load alone from rest, h^2 / 2 g s / (1 + h^2 w^2 / 4).
  void midpoint_free(double h, std::span<double> q_out) const;
  void midpoint_response(std::span<const double> s, double h, std::span<double> q_out) const;

  double kinetic() const;
  double potential() const;
  // Each mode's term of the sums kinetic() and potential() (before the 1/2),
  // in mode order: kinetic() == 0.5 * (0 + k_0 + k_1 + ...) to the bit, so a
  // bank split between ranks can sum its modes in the whole bank's order.
  void energy_terms(std::span<double> kinetic, std::span<double> potential) const;
  // Bytes of the arrays indexed by mode (state, parameters, rotation cache),
  // and of those indexed by distinct frequency.
  std::size_t mode_bytes() const;
  std::size_t frequency_bytes() const;

private:
  void prepare(double dt);

  int components_ = 1;
  std::vector<double> omega_, mass_, gain_;
  std::vector<double> q_, v_;
  // Rotation over cached_dt_: q' = c q + sw v, v' = -ws q + c v. Modes that
  // share a frequency (a spectral box has many: |k| is shared by symmetric wave
  // vectors) share one sin/cos evaluation: distinct_[level_[j]] = omega_[j].
  double cached_dt_ = 0.0;
  bool cache_valid_ = false;
  std::vector<double> c_, sw_, ws_;
  std::vector<double> distinct_;
  std::vector<std::uint32_t> level_;
  std::vector<double> dc_, dsw_, dws_;
};

}  // namespace floesim::fluid
