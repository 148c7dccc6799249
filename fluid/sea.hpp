#pragma once
// fluid::Sea — the sea surface as the rest of floesim sees it.
//
// Linear potential flow under a capillary-gravity free surface (MODEL.md §3):
//     m_sf(eta'', v) + a_sf(eta, v) = -∫ p v   for every zero-mean v,
// where p (Pa) is the pressure that floes apply to the water on the surface grid.
// A backend (spectral: periodic box; bem: a walled basin, vertical slice or 3D) turns this into
// a ModalBank; the Sea owns it and offers the same operations for both.
//
// Step contract (Strang splitting, MODEL.md §5):
//   on entry      state (eta, eta') at time t = time();
//   kick(p, h)    eta' += h M^-1 F(p), F(p) = the load v -> -∫ p v; eta and t unchanged;
//   flow(dt)      exact free evolution over dt; t += dt (and, in a tank, the
//                 relaxation zones act over the same dt);
//   on exit       state at t + dt.
// A forced step is kick(p(t), dt/2); flow(dt); kick(p(t + dt), dt/2), where
// p(t + dt) may be computed from the surface after flow (step() does exactly that).
// The mean of p does nothing (the surface keeps zero mean: volume conservation).
//
// Fields on the grid (SurfaceGrid: cell centres, x contiguous) and point queries
// are computed lazily from the modal state and cached until the state changes.

#include <array>
#include <functional>
#include <memory>
#include <span>
#include <vector>

#include "core/error.hpp"
#include "core/params.hpp"
#include "fluid/aligned.hpp"
#include "fluid/grid.hpp"
#include "fluid/modal.hpp"
#include "fluid/ranks.hpp"
#include "fluid/tank.hpp"

namespace floesim::fluid {

// Surface fields a sea provides, all at z = 0 (linear theory).
enum class Field {
  elevation,   // eta, m
  slope_x,     // d eta / dx
  slope_y,     // d eta / dy (0 in dims = 1)
  velocity_x,  // d phi / dx, m/s (orbital velocity, horizontal)
  velocity_y,  // d phi / dy (0 in dims = 1)
  velocity_z,  // d phi / dz = eta'
};
inline constexpr int field_count = 6;

// Rows [first_row, first_row + rows) of a field on the grid (x fastest), the
// row index taken modulo ny, so that a window may cross the grid's periodic
// seam; read by global cell (row iy, column ix: cell iy nx + ix). A whole
// field is the window of every row, first_row = 0: then the window's values
// are the field in cell order. A sea in slabs keeps its slab's rows and the
// halo's (Sea::set_field_halo); docs/parallel.md, "A row window for the
// fields".
class RowWindow {
public:
  RowWindow() = default;
  RowWindow(int first_row, int rows, int nx, int ny, std::span<const double> values)
      : first_row_(first_row), rows_(rows), nx_(nx), ny_(ny),
        offset_(static_cast<std::ptrdiff_t>(first_row) * nx), cells_(static_cast<std::ptrdiff_t>(nx) * ny),
        values_(values) {}

  int first_row() const { return first_row_; }
  int rows() const { return rows_; }
  bool whole() const { return first_row_ == 0 && rows_ == ny_; }
  // Whether the window holds row y (any integer: taken modulo ny).
  bool holds_row(int y) const { return ny_ > 0 && (((y - first_row_) % ny_) + ny_) % ny_ < rows_; }
  // The value at a global cell of a row the window holds: the cell's offset
  // from the window's first row, wrapped once across the seam (a window has
  // at most ny rows, so one wrap is all there can be).
  double operator[](std::size_t cell) const {
    std::ptrdiff_t i = static_cast<std::ptrdiff_t>(cell) - offset_;
    if (i < 0) i += cells_;
    FLOESIM_ASSERT(i < static_cast<std::ptrdiff_t>(values_.size()));
    return values_[static_cast<std::size_t>(i)];
  }
  // The values held, the window's first row first (for a whole window, the
  // field in cell order).
  std::span<const double> values() const { return values_; }
  // The whole field (asserted whole).
  std::span<const double> all() const {
    FLOESIM_ASSERT(whole());
    return values_;
  }

private:
  int first_row_ = 0, rows_ = 0, nx_ = 0, ny_ = 0;
  std::ptrdiff_t offset_ = 0, cells_ = 0;
  std::span<const double> values_;
};

struct SurfaceSample {
  double eta = 0.0;                       // m
  double slope_x = 0.0, slope_y = 0.0;    // grad eta
  double u = 0.0, v = 0.0, w = 0.0;       // grad phi at z = 0, m/s
};

// Energies over the whole surface (dims = 1: times the width ly), J.
struct SeaEnergy {
  double kinetic = 0.0;    // 1/2 m_sf(eta', eta')
  double potential = 0.0;  // 1/2 a_sf(eta, eta)
  double total() const { return kinetic + potential; }
};

// Fluid-side options that are not part of the [sea] configuration.
struct SeaOptions {
  TankParams tank;              // relaxation zones (spectral; bem with dims = 2)
  bool measure_fft_plans = false;  // FFTW_MEASURE instead of FFTW_ESTIMATE (benchmarks)
  double bem_panel_ratio = 1.0;    // bem: wall and bottom panel length / surface panel length
  // bem, dims = 2: a panel nearer to a collocation point than this many panel
  // diameters is integrated exactly, a farther one by 2 x 2 Gauss points
  // (relative error O((1 / bem_near_field)^4); docs/sea.md). inf: all exact.
  double bem_near_field = 3.0;
  int threads = 1;                 // spectral, dims = 2: threads of the transforms (the bits do not depend on it)
  // spectral, dims = 2, no tank: on several ranks, the sea in slabs (each
  // rank transforms and steps a share; spectral.hpp). Ignored otherwise.
  SeaRanks ranks;
};

class Sea {
public:
  virtual ~Sea();
  Sea(const Sea&) = delete;
  Sea& operator=(const Sea&) = delete;

  const SurfaceGrid& grid() const { return grid_; }
  double time() const { return time_; }
  void set_time(double t) { time_ = t; }

  // The step contract is in the comment at the top of this file.
  virtual void kick(std::span<const double> pressure, double h) = 0;
  virtual void flow(double dt) = 0;
  // kick(p, h) with the pressure p of the last kick(), which the caller
  // vouches has not changed: the backend reuses its projection of p (the
  // coupling's half kicks at the end of one step and the start of the next
  // share their pressure). Needs a kick() before it.
  virtual void repeat_kick(double h) = 0;

  // The implicit step of the floe–sea coupling (coupling/floe_sea.hpp): a
  // pressure held over h, integrated by the implicit midpoint rule of the
  // modes (ModalBank::midpoint). The elevation the step would reach with no
  // pressure, and the change of elevation a pressure p alone causes (linear
  // and symmetric in p: ∫ p' midpoint_response(p) = ∫ p midpoint_response(p'));
  // neither changes the state. p and eta are grid().size() values; in
  // slabs (slab_rows(), spectral.hpp) each rank reads its slab's rows of p
  // and writes its slab's rows of eta alone (the other rows are neither
  // read nor written), the whole sea's values to the bit, and the three
  // operations are collective (every rank calls each, in the same order).
  void midpoint_free_elevation(double h, std::span<double> eta);
  void midpoint_response(std::span<const double> p, double h, std::span<double> eta);
  // Advances the state over h with p held over the step; t += h. A tank's
  // relaxation zones act over h / 2 before and after (as in flow()).
  // On a sea with a static part (below) p becomes the pressure held. In
  // slabs each rank reads its rows of p and advances its modes.
  virtual void midpoint_step(std::span<const double> p, double h);

  // The static part of a truncated BEM sea (`[sea] bem_static_correction`;
  // fluid/static_correction.hpp): the modes it drops answer the pressure
  // held over a step quasi-statically, eta = X q + R F(p). midpoint_step(p)
  // holds p; hold_pressure(p) holds p without stepping (the coupling's static
  // start). Then elevation(), the slopes and sample() include R F(p),
  // midpoint_response(p) includes it (the response of p held over the step;
  // midpoint_free_elevation, with no pressure, does not), and energy()'s
  // potential includes 1/2 F^T R F. kick(), repeat_kick() (impulses),
  // flow() and set_surface() (the kept modes' state) neither use nor change
  // the pressure held. A sea without a static part ignores all of this.
  void hold_pressure(std::span<const double> p);
  virtual bool has_static_part() const { return false; }
  // The pressure held now (grid().size() values, Pa); empty when none is
  // (no static part, or nothing held yet). A checkpoint keeps it.
  virtual std::span<const double> held_pressure() const { return {}; }

  // pressure(sea, t, p) fills p (grid().size() values, Pa) for time t; it may
  // query the sea (called with the state at t, then at t + dt).
  using PressureFn = std::function<void(Sea& sea, double t, std::span<double> p)>;
  void step(double dt, const PressureFn& pressure);

  // Replaces the state by a surface given on the grid (its mean is removed).
  virtual void set_surface(std::span<const double> eta, std::span<const double> eta_t) = 0;

  // In slabs (SeaOptions::ranks; spectral.hpp): the first row of each
  // rank's slab, then the grid's row count (ranks + 1 values): kick() on rank
  // r reads the pressure's rows [rows[r], rows[r + 1]) only. Empty when every
  // rank reads the whole pressure.
  virtual std::vector<int> slab_rows() const { return {}; }
  // In slabs, moves the row cuts (first_row as slab_rows() gives it; whole
  // blocks of the transform's rows; the same on every rank, before the next
  // collective call; issue 21 stage seven). The fields become stale (their
  // rows are the old slab's). Not in slabs: nothing.
  virtual void set_slab_rows(std::vector<int> /*first_row*/) {}
  // In slabs, the thread CPU seconds spent in the transforms' row passes
  // since the last call (the part of the sea's work that follows the rows).
  virtual double take_row_seconds() { return 0.0; }
  // In slabs, the fields computed from now on are windows of this rank's
  // slab and `halo` rows either side of it (the grid's seam crossed; fewer
  // when the slab and its halo make every row, then the whole field): an
  // exchange of those rows instead of a gather of every row, and storage for
  // those rows only. halo < 0 (the default): whole fields (every rank's rows
  // gathered to every rank). A field computed whole serves any halo. A sea
  // not in slabs ignores it (its fields are whole).
  void set_field_halo(int halo) { field_halo_ = halo < 0 ? -1 : halo; }

  // A field on the grid: the window set_field_halo asks for (whole when not
  // in slabs). Valid until the state changes or the field is computed for
  // another window. In slabs collective when it is computed: every rank asks
  // for the same fields with the same halo, in the same order.
  RowWindow field(Field f);
  // The whole elevation (a sea not in slabs, or halo < 0).
  std::span<const double> elevation() { return field(Field::elevation).all(); }
  // The whole field on rank 0 of the sea's ranks (the run's writer), every
  // rank's rows gathered there alone; an empty span on the other ranks,
  // which keep their rows only (unless the field was already whole there).
  // Collective in slabs: every rank calls it. Not in slabs: the whole field.
  // Its storage is the field's: kept until the state changes, then sized to
  // the next window asked for.
  std::span<const double> field_on_writer(Field f);
  // The rows a field computed for `halo` holds on this rank (first row,
  // rows): whole unless in slabs. halo is set_field_halo's, or
  // gather_to_writer (field_on_writer: whole on rank 0, this rank's slab on
  // the others).
  struct WindowRows {
    int first = 0, rows = 0;
  };
  virtual WindowRows field_rows(int /*halo*/) const { return {0, grid_.ny}; }
  // Whether the fields are windows that differ by rank (a sea in slabs).
  virtual bool in_slabs() const { return false; }
  // Gives back the storage of field f (it is computed again when asked for).
  void release_field(Field f);
  // The whole field on rank 0 of a window w of it (which holds this rank's
  // slab): each rank's slab rows of w sent to rank 0, which puts them in
  // `whole`; the other ranks get `whole` empty. Collective in slabs (every
  // rank calls it); not in slabs, w's values (w whole).
  virtual void gather_to_writer_rows(const RowWindow& w, std::vector<double>& whole);
  // In slabs: `values` hold the window `rows` of a field (which holds this
  // rank's slab); on exit they hold the window of `halo` rows
  // (field_rows(halo)), the rows beyond the slab from their slabs' ranks
  // (one all-to-all: the fields' halo exchange). For a window kept from an
  // earlier step whose halo has to grow (the incident waves' snapshots when
  // the coupling's floes move with the slabs). Collective in slabs: every
  // rank calls it with the same halo >= 0. Not in slabs: nothing (whole).
  virtual void widen_window(std::vector<double>& /*values*/, WindowRows& /*rows*/, int /*halo*/) {}
  // The whole fields' point values (a sea not in slabs, or halo < 0).
  SurfaceSample sample(double x, double y = 0.0);
  // Collective in slabs (the modes' terms are summed in the whole bank's
  // order on rank 0, whose sums every rank receives).
  SeaEnergy energy() {
    settle();
    SeaEnergy e = bank_energy();
    e.potential += static_potential();
    return e;
  }

  // The modal state (settled: every kick applied). In slabs (spectral.hpp)
  // this rank's modes only: its columns of the half spectrum, row by row.
  ModalBank& modes() {
    settle();
    invalidate();
    return bank_;
  }
  // Whether this rank's part of the sea's state is finite: the modes'
  // amplitudes and rates it steps (in slabs its columns only; else every
  // mode), the loads of the kicks a backend deferred, and the pressure
  // held. Reads no field and settles nothing (the state and its bits are
  // left as they are); no communication. For the poison mode of the run
  // (coupling/poison_mode.hpp): a NaN that a phase carried into the sea
  // stays in these values (the fields are made from them).
  virtual bool finite_state() const;
  // The whole modal state in the whole bank's layout, for checkpoints:
  // modal_size() amplitudes q and as many rates v (settled). In slabs,
  // collective: every rank's modes are gathered to rank 0, which alone
  // receives them (q and v are left empty on the other ranks).
  virtual std::size_t modal_size() const { return bank_.q().size(); }
  virtual void gather_modal_state(std::vector<double>& q, std::vector<double>& v);
  // Replaces the modal state by a whole one (modal_size() values each, on
  // every rank; in slabs each rank keeps its modes).
  virtual void set_modal_state(std::span<const double> q, std::span<const double> v);

protected:
  explicit Sea(const SurfaceGrid& grid);
  // out <- field f in the window field_rows(field_halo()) (rows x nx values,
  // the window's first row first).
  virtual void compute_field(Field f, std::span<double> out) = 0;
  // The halo value of field_on_writer's fields (set_field_halo keeps
  // halos < 0 as -1, a whole field, so this one is never asked for by it).
  static constexpr int gather_to_writer = -2;
  // A backend may defer kicks (to fuse them into the next flow); settle()
  // applies the deferred ones. The state seen through the public API is always
  // the settled one.
  virtual void settle() {}
  // The modal load s of a pressure (kick(p, h) is v += h gain s), and the
  // elevation on the grid of modal amplitudes q; both laid out like the
  // bank's q. In slabs: this rank's rows of the pressure to its modes, its
  // modes to its rows of the elevation (collective).
  virtual void project(std::span<const double> pressure, std::span<double> s) = 0;
  virtual void synthesize(std::span<const double> q, std::span<double> eta) = 0;
  // The static part (see hold_pressure), s = project(pressure): hold the
  // pressure; add its static response to eta; the energy of the held one.
  virtual void hold(std::span<const double> /*pressure*/, std::span<const double> /*s*/) {}
  virtual void add_static_response(std::span<const double> /*pressure*/, std::span<const double> /*s*/,
                                   std::span<double> /*eta*/) {}
  virtual double static_potential() const { return 0.0; }
  // The bank's energies (kinetic, potential without the static part).
  virtual SeaEnergy bank_energy() { return {bank_.kinetic(), bank_.potential()}; }
  void invalidate() { valid_.fill(false); }
  // The rows the field being computed must hold (set_field_halo).
  int field_halo() const { return field_halo_; }
  void invalidate_rates();  // only the fields that depend on eta' (after a kick)

  SurfaceGrid grid_;
  ModalBank bank_;
  double time_ = 0.0;

private:
  std::array<AlignedVector, field_count> fields_;
  std::array<bool, field_count> valid_{};
  std::array<int, field_count> computed_halo_{};  // the halo each valid field was computed for
  std::array<WindowRows, field_count> windows_{};  // the rows each valid field holds
  int field_halo_ = -1;
  AlignedVector p_scratch_;
  AlignedVector modal_a_, modal_b_;  // scratch for the midpoint operations
};

// Checks a [sea] section; throws InputError naming the key ("[sea] cells: ...").
// Preconditions, checked once at load with the file and line (core/config.cpp)
// and only asserted here: a bottom polyline only with model = "bem", below the
// surface, x increasing, spanning [0, size x].
void validate(const SeaParams& params);

// The sea of a configuration, with its initial waves ([sea.waves]; `seed` draws
// the random phases of an irregular sea). Returns nullptr for model = "none".
// A tank run (options.tank.enabled) starts calm and generates its target wave.
// Preconditions (checked at load, core/config.cpp; asserted here): tank zones
// only on the spectral sea and the 3D BEM basin, with a regular [sea.waves] wave.
std::unique_ptr<Sea> make_sea(const SeaParams& params, unsigned long seed,
                              const SeaOptions& options = {});

}  // namespace floesim::fluid
