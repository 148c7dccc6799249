#pragma once
// Spectral sea: a periodic box lx (x ly) with a flat bottom at depth H (or deep
// water), dims = 1 (long-crested) or 2. Each Fourier mode k of the real-to-
// complex transform of eta is an oscillator of the ModalBank (two real
// components, re and im) with
//     omega_k^2 = (g |k| + sigma |k|^3 / rho) tanh(|k| H),
//     added-mass density mu_k = rho coth(|k| H) / |k|,
// so that a pressure p acts on mode k as eta_k'' = -omega_k^2 eta_k - p_k / mu_k.
// The k = 0 mode (the mean) is frozen at zero: volume conservation.
//
// Modal amplitudes are the normalised coefficients FFT(eta) / n of eta on the
// cell centres (n cells), so eta is the plain c2r of them. FFTW plans (r2c,
// c2r) are made once at construction and reused; a kick costs one r2c, each
// grid field one c2r. All scratch is allocated once.
//
// The modal work is memory-bound, so kicks are deferred (up to two) and applied
// in the same pass over the modes as the next flow, which also stages q for the
// elevation's c2r. Callers see no difference: velocity fields add the deferred
// kicks as they load the rates, energy() and modes() settle them first. A
// repeated kick costs no FFT: it defers the spectrum of the last kick again,
// as a kick of its own, so a query that settles in between changes no bit.
//
// On several ranks (SeaOptions::ranks; dims = 2, no tank) the sea runs in
// slabs (fluid/slab_fft.hpp): a kick transforms the rows of this rank's
// slab of the pressure (the rest of the pressure is not read) into its
// columns of modes; flow steps those modes only; a field is transformed
// from them back to this rank's rows, and every rank's rows are then
// gathered, so fields are whole on every rank; or, with a halo
// (Sea::set_field_halo, stage five), the field is a window of this rank's
// slab and the halo (Sea::field's RowWindow), whose halo rows alone are
// exchanged; or (Sea::field_on_writer, records) every rank's rows are sent
// to rank 0 alone.
// The bank, its per-mode factors and the kick spectra hold this rank's
// modes only (its columns of each row, row by row: docs/parallel.md, stage
// six), so modes() is this rank's part; energy() sums every rank's terms in
// the whole bank's order on rank 0, and gather_modal_state() brings the
// whole state to rank 0 (both collective, at records and checkpoints).
// Each mode and each block of the transforms is computed with the serial
// arithmetic, so the state and the fields are the serial ones to the bit.
// The transforms' scratch is this rank's too (its rows of the real side,
// its columns of the spectra); set_surface uses the slab transform as well
// (collective: every rank sets the surface, at set-up). The implicit
// step's midpoint operations (Sea::midpoint_*) use the slab transform too:
// project reads this rank's rows of the pressure into its modes, synthesize
// writes its modes to its rows of the elevation (no gather), each mode's
// factor the one of its place in the whole spectrum, so each rank's rows are
// the whole sea's to the bit.

#include <memory>

#include "fluid/sea.hpp"

namespace floesim::fluid {

class SpectralSea final : public Sea {
public:
  // params must have passed validate(); tank zones need a regular target wave.
  SpectralSea(const SeaParams& params, const SeaOptions& options = {});
  ~SpectralSea() override;

  void kick(std::span<const double> pressure, double h) override;
  void repeat_kick(double h) override;
  void flow(double dt) override;
  void set_surface(std::span<const double> eta, std::span<const double> eta_t) override;
  void midpoint_step(std::span<const double> p, double h) override;
  std::vector<int> slab_rows() const override;
  void set_slab_rows(std::vector<int> first_row) override;
  double take_row_seconds() override;
  std::size_t modal_size() const override;
  void gather_modal_state(std::vector<double>& q, std::vector<double>& v) override;
  void set_modal_state(std::span<const double> q, std::span<const double> v) override;
  WindowRows field_rows(int halo) const override;
  bool in_slabs() const override;
  void gather_to_writer_rows(const RowWindow& w, std::vector<double>& whole) override;
  void widen_window(std::vector<double>& values, WindowRows& rows, int halo) override;

  // What this sea allocates: `modes`, the modes its bank holds (every mode
  // of the half spectrum, or in slabs this rank's columns of each row);
  // `mode_bytes`, the arrays sized by them (the bank's state, parameters
  // and rotation cache, the derivative and potential factors, the two kick
  // spectra); `scratch_bytes`, the transforms' scratch: serially the whole
  // grid's (and a tank's fields), in slabs this rank's rows of the real
  // side, its column slab of each spectrum, and the slab transform's row
  // scratch and transposes' buffers. Not counted:
  // the fields (Sea), the bank's per-frequency cache.
  struct Memory {
    std::size_t modes = 0, mode_bytes = 0, scratch_bytes = 0;
  };
  Memory memory() const;

  // omega of the Fourier mode with wave vector 2 pi (mx / lx, my / ly).
  double omega(int mx, int my = 0) const;
  // Sea::finite_state() and the deferred kicks' loads.
  bool finite_state() const override;
  // The tank's relaxation zones, or nullptr.
  const TankZones* tank() const;

protected:
  void compute_field(Field f, std::span<double> out) override;
  void settle() override;
  void project(std::span<const double> pressure, std::span<double> s) override;
  void synthesize(std::span<const double> q, std::span<double> eta) override;
  SeaEnergy bank_energy() override;

private:
  // The tank's relaxation zones over [t0, t0 + h], in physical space.
  void relax_tank(double t0, double h);
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace floesim::fluid
