#include "fluid/spectral.hpp"

#include <fftw3.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <numbers>

#include "core/error.hpp"
#include "fluid/spectral_impl.hpp"

namespace floesim::fluid {

namespace {

SurfaceGrid periodic_grid(const SeaParams& p) {
  SurfaceGrid g;
  g.dims = p.dims;
  g.nx = p.cells[0];
  g.ny = p.dims == 2 ? p.cells[1] : 1;
  g.lx = p.size[0];
  g.ly = p.size[1];
  g.edge = GridEdge::periodic;
  return g;
}

}  // namespace


SpectralSea::SpectralSea(const SeaParams& params, const SeaOptions& options)
    : Sea(periodic_grid(params)), impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  m.nx = grid_.nx;
  m.ny = grid_.ny;
  m.hx = m.nx / 2 + 1;
  m.n = grid_.size();
  m.nc = static_cast<std::size_t>(m.ny) * m.hx;
  m.disp = Dispersion::of(params);
  m.lx = grid_.lx;
  m.ly = grid_.ly;

  const unsigned flags = options.measure_fft_plans ? FFTW_MEASURE : FFTW_ESTIMATE;
  m.threads = std::max(options.threads, 1);
  const bool slabs = m.ny > 1 && options.ranks.distributed() && !options.tank.enabled;
  bool planned = false;
  if (slabs) {
    // The whole transform's plans (the slab transform runs their row
    // blocks), made on whole arrays freed after planning.
    {
      const Impl::WholeScratch whole(m.n, m.nc);
      m.fft2 = std::make_unique<RealFft2d>(m.nx, m.ny, flags, whole.real, whole.spec);
    }
    planned = m.fft2->valid();
    m.ranks = options.ranks;
    m.slab = std::make_unique<SlabFft2d>(*m.fft2, m.nx, m.ny, m.ranks.rank, m.ranks.ranks, m.ranks.alltoall, flags);
    m.columns = m.slab->columns();
    m.set_rows();
    // This rank's column slabs (fftw_alloc_*(0) may return nullptr: a rank
    // without columns holds one entry).
    m.spec_size = m.slab->column_size();
    m.spec = fftw_alloc_complex(std::max<std::size_t>(m.spec_size, 1));
    m.spec_vy = fftw_alloc_complex(std::max<std::size_t>(m.spec_size, 1));
  } else {
    m.real_size = m.n;
    m.spec_size = m.nc;
    m.real = fftw_alloc_real(m.n);
    m.spec = fftw_alloc_complex(m.nc);
    if (m.ny > 1) m.spec_vy = fftw_alloc_complex(m.nc);
    m.columns = {0, m.hx};
  }
  if (m.ny > 1 && !slabs) {
    m.fft2 = std::make_unique<RealFft2d>(m.nx, m.ny, flags, m.real, m.spec);
    planned = m.fft2->valid();
  } else if (m.ny == 1) {
    m.r2c = fftw_plan_dft_r2c_1d(m.nx, m.real, m.spec, flags);
    m.c2r = fftw_plan_dft_c2r_1d(m.nx, m.spec, m.real, flags);
    planned = m.r2c && m.c2r;
  }
  if (!planned) throw RunError("fluid: FFTW could not plan the spectral sea transforms");
  m.width = static_cast<std::size_t>(m.columns.end - m.columns.begin);
  m.modes = static_cast<std::size_t>(m.ny) * m.width;
  // fftw_alloc_complex(0) may return nullptr: a rank without columns holds one.
  m.kick_capacity = std::max<std::size_t>(m.modes, 1);
  for (auto*& k : m.kick_spec) k = fftw_alloc_complex(m.kick_capacity);

  // Oscillator bank on the normalised coefficients eta_k = FFT(eta) / n, so that
  // a field is the plain c2r of its coefficients. Parseval on the half spectrum:
  // ∫ f g = dA n sum_full f_k conj(g_k), and a coefficient with 0 < ix < nx/2
  // stands for itself and its conjugate (weight 2). A kick receives the
  // unnormalised FFT of p, hence gain = -1 / (mu n).
  // In slabs only this rank's modes (Impl::modes).
  std::vector<double> omega(m.modes), mass(m.modes), gain(m.modes);
  m.kx.assign(m.modes, 0.0);
  m.ky.assign(m.modes, 0.0);
  m.phi.assign(m.modes, 0.0);
  const double da_n = grid_.cell_area() * static_cast<double>(m.n);
  const double inv_n = 1.0 / static_cast<double>(m.n);
  const double two_pi = 2.0 * std::numbers::pi;
  for (int iy = 0; iy < m.ny; ++iy) {
    const int my = iy <= m.ny / 2 ? iy : iy - m.ny;
    for (int ix = m.columns.begin; ix < m.columns.end; ++ix) {
      const std::size_t c = static_cast<std::size_t>(iy) * m.width + static_cast<std::size_t>(ix - m.columns.begin);
      const double kx = two_pi * ix / m.lx;
      const double ky = m.ny > 1 ? two_pi * my / m.ly : 0.0;
      const double k = std::hypot(kx, ky);
      if (k == 0.0) {  // the mean: frozen
        omega[c] = mass[c] = gain[c] = 0.0;
        continue;
      }
      const double weight = (ix > 0 && 2 * ix != m.nx) ? 2.0 : 1.0;
      const double mu = m.disp.mass_density(k);
      omega[c] = m.disp.omega(k);
      mass[c] = weight * mu * da_n;
      gain[c] = -inv_n / mu;
      m.kx[c] = 2 * ix == m.nx ? 0.0 : kx;
      m.ky[c] = (m.ny > 1 && 2 * iy == m.ny) ? 0.0 : ky;
      m.phi[c] = 1.0 / (k * std::tanh(k * m.disp.depth));
    }
  }
  bank_ = ModalBank(std::move(omega), std::move(mass), std::move(gain), 2);

  if (options.tank.enabled) {
    FLOESIM_ASSERT(params.waves.kind == WaveKind::regular);  // refused at load (core/config.cpp)
    m.tank.emplace(grid_, options.tank, plane_wave(params, grid_));
    m.tank_eta.assign(m.n, 0.0);
    m.tank_rate.assign(m.n, 0.0);
  }
}

SpectralSea::~SpectralSea() = default;

double SpectralSea::omega(int mx, int my) const {
  const double two_pi = 2.0 * std::numbers::pi;
  return impl_->disp.omega(std::hypot(two_pi * mx / impl_->lx, two_pi * my / impl_->ly));
}

std::vector<int> SpectralSea::slab_rows() const {
  const Impl& m = *impl_;
  if (!m.slab) return {};
  std::vector<int> rows;
  for (int r = 0; r < m.ranks.ranks; ++r) rows.push_back(m.slab->rows_of(r).begin);
  rows.push_back(m.ny);
  return rows;
}

void SpectralSea::set_slab_rows(std::vector<int> first_row) {
  Impl& m = *impl_;
  if (!m.slab || first_row == m.slab->first_rows()) return;
  m.slab->set_rows(std::move(first_row));
  m.set_rows();
  invalidate();  // the fields' present rows were the old slab's and halo's
}

Sea::WindowRows SpectralSea::field_rows(int halo) const { return impl_->window(halo); }

bool SpectralSea::in_slabs() const { return impl_->slab != nullptr; }

void SpectralSea::gather_to_writer_rows(const RowWindow& w, std::vector<double>& whole) {
  Impl& m = *impl_;
  if (!m.slab) return Sea::gather_to_writer_rows(w, whole);
  FLOESIM_ASSERT(m.rows.begin == m.rows.end || (w.holds_row(m.rows.begin) && w.holds_row(m.rows.end - 1)));
  // This rank's slab rows are consecutive in w (a window's rows are, the
  // seam crossed, and a slab does not cross it).
  const std::span<const double> values = w.values();
  const double* own = m.rows.begin < m.rows.end
                          ? values.data() + m.at_row({w.first_row(), w.rows()}, m.rows.begin)
                          : nullptr;
  whole.clear();
  if (m.ranks.rank == 0) whole.resize(m.n);
  m.gather_rows(own, m.ranks.rank == 0 ? whole.data() : nullptr);
}

void SpectralSea::widen_window(std::vector<double>& values, WindowRows& rows, int halo) {
  Impl& m = *impl_;
  if (!m.slab) return;
  FLOESIM_ASSERT(halo >= 0);
  // This rank's slab rows into the new window, then its halo from the
  // slabs' ranks, as a field computed for that halo gets it.
  const WindowRows w = m.window(halo);
  std::vector<double> out(static_cast<std::size_t>(w.rows) * static_cast<std::size_t>(m.nx), 0.0);
  const std::size_t row = static_cast<std::size_t>(m.nx);
  for (int y = m.rows.begin; y < m.rows.end; ++y)
    std::copy_n(values.begin() + static_cast<std::ptrdiff_t>(m.at_row(rows, y)), row,
                out.begin() + static_cast<std::ptrdiff_t>(m.at_row(w, y)));
  m.exchange_halo(out, halo, w);
  values = std::move(out);
  rows = w;
}

double SpectralSea::take_row_seconds() { return impl_->slab ? impl_->slab->take_row_seconds() : 0.0; }

const TankZones* SpectralSea::tank() const { return impl_->tank ? &*impl_->tank : nullptr; }

void SpectralSea::kick(std::span<const double> pressure, double h) {
  Impl& m = *impl_;
  FLOESIM_ASSERT(pressure.size() == m.n);
  if (m.pending == 2) settle();
  const int buf = m.pending == 1 ? 1 - m.kick_buf[0] : 0;  // one not in use
  m.forward_kick(pressure, m.kick_spec[buf]);
  m.kick_buf[m.pending] = buf;
  m.kick_h[m.pending] = h;
  m.last = buf;
  ++m.pending;
  m.staged_vy = false;
  invalidate_rates();
}

void SpectralSea::repeat_kick(double h) {
  Impl& m = *impl_;
  FLOESIM_ASSERT(m.last >= 0);
  // A kick of its own (not h added to a deferred one), so that the
  // arithmetic, and the result to the bit, does not depend on whether a
  // query settled the first one in between.
  if (m.pending == 2) settle();
  m.kick_buf[m.pending] = m.last;
  m.kick_h[m.pending] = h;
  ++m.pending;
  m.staged_vy = false;
  invalidate_rates();
}

bool SpectralSea::finite_state() const {
  if (!Sea::finite_state()) return false;
  // A deferred kick's load (the pressure's spectrum) is applied at the
  // next flow: a NaN pressure waits there until then.
  const Impl& m = *impl_;
  for (int i = 0; i < m.pending; ++i) {
    const double* s = m.kick_data(i);
    if (!std::all_of(s, s + 2 * m.modes, [](double x) { return std::isfinite(x); })) return false;
  }
  return true;
}

void SpectralSea::settle() {
  Impl& m = *impl_;
  for (int i = 0; i < m.pending; ++i) bank_.kick(std::span<const double>(m.kick_data(i), 2 * m.modes), m.kick_h[i]);
  m.pending = 0;
  // Base::modes() settles before handing out the state to be changed: the
  // staged spectra may not outlive that.
  m.staged = false;
  m.staged_vy = false;
}

void SpectralSea::set_surface(std::span<const double> eta, std::span<const double> eta_t) {
  Impl& m = *impl_;
  FLOESIM_ASSERT(eta.size() == m.n && eta_t.size() == m.n);
  m.pending = 0;  // the state is replaced: deferred kicks are void
  m.staged = false;
  m.staged_vy = false;
  // Serially the whole transform. In slabs the slab transform (collective:
  // every rank sets the surface, at set-up): its rows of the surface to its
  // columns of the modes, the serial transform's bits.
  auto copy_in = [&](std::span<const double> f, std::span<double> a) {
    if (m.slab) m.forward_slab(f, m.spec);
    else m.forward(f, m.spec);
    const double* s = reinterpret_cast<const double*>(m.spec);
    const double inv_n = 1.0 / static_cast<double>(m.n);
    m.for_own_modes([&](std::size_t first, std::size_t last, std::size_t mode, std::size_t at) {
      for (std::size_t c = at, j = mode; j < mode + (last - first); ++c, ++j) {
        a[2 * j] = s[2 * c] * inv_n;
        a[2 * j + 1] = s[2 * c + 1] * inv_n;
      }
    });
    if (m.columns.begin == 0 && m.modes > 0) a[0] = a[1] = 0.0;  // zero mean (mode 0, if this rank holds it)
  };
  copy_in(eta, bank_.q());
  copy_in(eta_t, bank_.v());
  invalidate();
}

void SpectralSea::flow(double dt) {
  Impl& m = *impl_;
  if (!m.tank) {
    // One pass: deferred kicks, rotation, and q staged in spec for the elevation.
    std::array<ModalBank::Kick, 2> kicks{};
    for (int i = 0; i < m.pending; ++i)
      kicks[i] = {m.kick_data(i), m.kick_h[i]};
    const std::span<const ModalBank::Kick> pending(kicks.data(), static_cast<std::size_t>(m.pending));
    if (m.slab) {
      // Row by row: the bank's modes [mode, mode + last - first) are spec's
      // [at, at + last - first), so q_out is spec shifted by at - mode (>= 0).
      m.for_own_modes([&](std::size_t first, std::size_t last, std::size_t mode, std::size_t at) {
        bank_.kick_flow(pending, dt, reinterpret_cast<double*>(m.spec + (at - mode)), mode, mode + (last - first));
      });
    } else {
      bank_.kick_flow(pending, dt, reinterpret_cast<double*>(m.spec));
    }
    m.pending = 0;
    m.staged = true;
  } else {
    settle();
    // Strang: relax(dt/2) flow(dt) relax(dt/2).
    relax_tank(time_, 0.5 * dt);
    bank_.flow(dt);
    relax_tank(time_ + 0.5 * dt, 0.5 * dt);
  }
  time_ += dt;
  m.staged_vy = false;
  invalidate();
}

void SpectralSea::relax_tank(double t0, double h) {
  Impl& m = *impl_;
  m.load(bank_.q(), nullptr, nullptr);
  m.backward(m.tank_eta, m.spec);
  m.load(bank_.v(), nullptr, nullptr);
  m.backward(m.tank_rate, m.spec);
  m.tank->relax(t0, h, m.tank_eta, m.tank_rate);
  set_surface(m.tank_eta, m.tank_rate);
}

void SpectralSea::midpoint_step(std::span<const double> p, double h) {
  Impl& m = *impl_;
  if (!m.tank) return Sea::midpoint_step(p, h);
  settle();
  // Strang, as flow(): relax(h/2), the midpoint step, relax(h/2).
  relax_tank(time_, 0.5 * h);
  Sea::midpoint_step(p, h);  // advances time_ by h
  relax_tank(time_ - 0.5 * h, 0.5 * h);
  m.staged = false;
  m.staged_vy = false;
  invalidate();
}

void SpectralSea::project(std::span<const double> pressure, std::span<double> s) {
  Impl& m = *impl_;
  FLOESIM_ASSERT(pressure.size() == m.n && s.size() == 2 * m.modes);
  // In slabs the slab transform (collective): this rank's rows of the
  // pressure to its columns of the spectrum, each block the serial plan's.
  if (m.slab) m.forward_slab(pressure, m.spec);
  else m.forward(pressure, m.spec);
  m.staged = false;
  // spec's layout to the bank's (one copy when not in slabs; else each
  // row's columns, spec's row iy at iy stride, the bank's at iy width).
  const double* f = reinterpret_cast<const double*>(m.spec);
  m.for_own_modes([&](std::size_t first, std::size_t stop, std::size_t mode, std::size_t at) {
    std::copy(f + 2 * at, f + 2 * (at + stop - first), s.begin() + static_cast<std::ptrdiff_t>(2 * mode));
  });
}

void SpectralSea::synthesize(std::span<const double> q, std::span<double> eta) {
  Impl& m = *impl_;
  FLOESIM_ASSERT(q.size() == 2 * m.modes && eta.size() == m.n);
  double* to = reinterpret_cast<double*>(m.spec);
  m.for_own_modes([&](std::size_t first, std::size_t stop, std::size_t mode, std::size_t at) {
    std::copy(q.begin() + static_cast<std::ptrdiff_t>(2 * mode), q.begin() + static_cast<std::ptrdiff_t>(2 * (mode + stop - first)),
              to + 2 * at);
  });
  m.staged = false;
  // In slabs this rank's rows of eta alone (no gather: the implicit step's
  // products read the rows of their own slab).
  if (m.slab) m.backward_rows(eta, m.spec);
  else m.backward(eta, m.spec);
}

void SpectralSea::compute_field(Field f, std::span<double> out) {
  Impl& m = *impl_;
  const bool one_d = m.ny == 1;
  // Rate fields see the deferred kicks without settling them (they stay
  // fused with the next flow).
  const std::span<const double> gain = bank_.gain();
  switch (f) {
    case Field::elevation:
      if (!m.staged) m.load(bank_.q(), nullptr, nullptr);
      break;
    case Field::slope_x: m.load(bank_.q(), &m.kx, nullptr); break;
    case Field::slope_y:
      if (one_d) return std::fill(out.begin(), out.end(), 0.0);
      m.load(bank_.q(), &m.ky, nullptr);
      break;
    case Field::velocity_x:  // and, in 2-D, the y-velocity's spectrum
      m.load(bank_.v(), &m.kx, &m.phi, gain, one_d ? nullptr : &m.ky);
      break;
    case Field::velocity_y:
      if (one_d) return std::fill(out.begin(), out.end(), 0.0);
      if (m.staged_vy) {
        m.backward(out, m.spec_vy, field_halo());
        m.staged_vy = false;
        return;
      }
      m.load(bank_.v(), &m.ky, &m.phi, gain);
      break;
    case Field::velocity_z: m.load(bank_.v(), nullptr, nullptr, gain); break;
  }
  m.backward(out, m.spec, field_halo());  // destroys spec
  m.staged = false;
}

}  // namespace floesim::fluid
