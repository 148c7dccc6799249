#include "fluid/spectral.hpp"

#include <fftw3.h>

#include <array>
#include <cmath>
#include <cstring>
#include <numbers>
#include <optional>

#include "core/error.hpp"
#include "fluid/fft2d.hpp"
#include "fluid/slab_fft.hpp"
#include "fluid/waves.hpp"

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

struct SpectralSea::Impl {
  int nx = 0, ny = 1, hx = 0;
  std::size_t n = 0, nc = 0;
  Dispersion disp;
  double lx = 0.0, ly = 0.0;
  // Per mode of the bank: derivative wavenumbers (0 on the Nyquist line of
  // that axis, where an odd derivative of a real field is not representable)
  // and the factor coth(|k| H) / |k| that maps eta' to the surface potential phi.
  std::vector<double> kx, ky, phi;
  // The bank's modes: every mode of the half spectrum (nc), or in slabs this
  // rank's columns [columns.begin, columns.end) of each row, row by row
  // (ny x width). Mode j of row iy is the spectrum's entry iy hx + columns.begin + j - iy width.
  std::size_t modes = 0, width = 0;
  double* real = nullptr;         // n reals, scratch
  fftw_complex* spec = nullptr;   // nc complex, scratch
  // dims = 2: the y-velocity's spectrum, made in the same pass over the modes
  // as the x-velocity's (staged_vy) and used by the next velocity_y query.
  fftw_complex* spec_vy = nullptr;
  bool staged_vy = false;
  fftw_plan r2c = nullptr, c2r = nullptr;  // dims = 1
  std::unique_ptr<RealFft2d> fft2;         // dims = 2: the same bits on any number of threads
  int threads = 1;
  // Deferred kicks: up to two (spectrum, h), applied fused with the next flow,
  // in order. kick_spec holds the FFTs of up to two pressures, laid out like
  // the bank's modes (in slabs: this rank's columns only); pending kick i
  // uses kick_spec[kick_buf[i]] (a repeated kick uses the buffer of the last
  // one again). `staged`: spec holds the current q (written by that flow), so
  // the elevation needs no copy before its c2r.
  std::array<fftw_complex*, 2> kick_spec{nullptr, nullptr};
  std::size_t kick_capacity = 0;  // complex entries of each kick buffer
  std::array<int, 2> kick_buf{0, 0};
  std::array<double, 2> kick_h{0.0, 0.0};
  int pending = 0;
  int last = -1;  // buffer holding the FFT of the last kick's pressure (-1: none yet)
  const double* kick_data(int i) const { return reinterpret_cast<const double*>(kick_spec[kick_buf[i]]); }
  bool staged = false;
  std::optional<TankZones> tank;
  AlignedVector tank_eta, tank_rate;
  // The sea in slabs (ranks.distributed(); spectral.hpp): this rank's rows
  // of the fields and columns of the modes.
  SeaRanks ranks;
  std::unique_ptr<SlabFft2d> slab;
  SlabFft2d::Span rows{0, 0}, columns{0, 0};
  std::vector<std::size_t> row_bytes;  // each rank's part of a field
  struct Halo {
    int rows = -1;                                    // the halo the lists are for
    std::vector<std::vector<int>> send, receive;      // per rank: the rows sent to it, received from it
    std::vector<std::byte> out, in;
  } halo_exchange;

  // f(first, stop, mode) for each range [first, stop) of the half spectrum
  // the bank holds, `mode` the bank's index of `first`: every mode at once
  // when not in slabs, else this rank's columns of each row.
  template <class F>
  void for_own_modes(F&& f) const {
    if (!slab) return f(std::size_t{0}, nc, std::size_t{0});
    for (int iy = 0; iy < ny; ++iy) {
      const std::size_t row = static_cast<std::size_t>(iy) * hx;
      f(row + columns.begin, row + columns.end, static_cast<std::size_t>(iy) * width);
    }
  }
  // The columns and the bank's mode count of rank r.
  std::size_t width_of(int r) const {
    const SlabFft2d::Span c = slab->columns_of(r);
    return static_cast<std::size_t>(c.end - c.begin);
  }

  ~Impl() {
    if (r2c) fftw_destroy_plan(r2c);
    if (c2r) fftw_destroy_plan(c2r);
    fftw_free(real);
    fftw_free(spec);
    fftw_free(spec_vy);
    for (auto* k : kick_spec) fftw_free(k);
  }

  bool aligned(const double* p) const {
    return fftw_alignment_of(const_cast<double*>(p)) == fftw_alignment_of(real);
  }

  // to <- FFT(field) on the bank's modes, to a kick buffer. In slabs the
  // field's rows of this rank only are read, and its columns of the
  // transform, made in spec_vy (scratch: a kick voids its staging), are
  // copied to the buffer in the bank's layout.
  void forward_kick(std::span<const double> field, fftw_complex* to) {
    if (!slab) return forward(field, to);
    const double* in = field.data();
    if (!aligned(in)) {
      std::copy(field.begin(), field.end(), real);
      in = real;
    }
    slab->forward(in, spec_vy, threads);
    for_own_modes([&](std::size_t first, std::size_t stop, std::size_t mode) {
      std::copy(spec_vy[first], spec_vy[first] + 2 * (stop - first), to[mode]);
    });
  }
  // to <- FFT(field), every mode on every rank; `to` is spec or a kick buffer (same alignment).
  void forward(std::span<const double> field, fftw_complex* to) {
    const double* in = field.data();
    if (!aligned(in)) {
      std::copy(field.begin(), field.end(), real);
      in = real;
    }
    // r2c plans preserve their input (FFTW_PRESERVE_INPUT is the default).
    if (fft2) fft2->forward(in, to, threads);
    else fftw_execute_dft_r2c(r2c, const_cast<double*>(in), to);
  }
  // out <- IFFT(from) (unnormalised; `from`, spec or spec_vy, is destroyed).
  // In slabs: from this rank's columns of `from` to its rows of out, then
  // every rank's rows gathered into out, or with halo >= 0 (Sea::
  // set_field_halo) only the halo's rows exchanged.
  void backward(std::span<double> out, fftw_complex* from, int halo = -1) {
    double* to = aligned(out.data()) ? out.data() : real;
    if (slab) {
      slab->backward(from, to, threads);
      const std::size_t begin = static_cast<std::size_t>(rows.begin) * nx, end = static_cast<std::size_t>(rows.end) * nx;
      if (to == real) std::copy(real + begin, real + end, out.begin() + static_cast<std::ptrdiff_t>(begin));
      if (halo < 0) ranks.allgather(std::as_writable_bytes(out), row_bytes);
      else exchange_halo(out, halo);
      return;
    }
    if (fft2) fft2->backward(from, to, threads);
    else fftw_execute_dft_c2r(c2r, from, to);
    if (to == real) std::copy(real, real + n, out.begin());
  }
  // spec <- (i k)^d factor * a, for a = q or v (d = 0 or 1 via `deriv`); with
  // `gain`, the deferred kicks are added to a on the way (a = v: the rates as
  // settle() would leave them, in the same order of operations); with
  // `deriv_vy`, spec_vy <- i deriv_vy factor * a in the same pass.
  void load(std::span<const double> a, const std::vector<double>* deriv,
            const std::vector<double>* factor, std::span<const double> gain = {},
            const std::vector<double>* deriv_vy = nullptr) {
    staged = false;
    staged_vy = deriv_vy != nullptr;
    const int kicks = gain.empty() ? 0 : pending;
    if (!slab && !deriv && !factor && kicks == 0) {
      std::copy(a.begin(), a.end(), reinterpret_cast<double*>(spec));
      return;
    }
    for_own_modes([&](std::size_t first, std::size_t stop, std::size_t mode) {
      for (std::size_t c = first, j = mode; c < stop; ++c, ++j) {
        double a0 = a[2 * j], a1 = a[2 * j + 1];
        for (int i = 0; i < kicks; ++i) {
          const double g = kick_h[i] * gain[j];
          const double* s = kick_data(i);
          a0 += g * s[2 * j];
          a1 += g * s[2 * j + 1];
        }
        double s = 1.0;
        if (factor) s *= (*factor)[j];
        const double re = a0 * s, im = a1 * s;
        if (deriv_vy) {
          const double k = (*deriv_vy)[j];
          spec_vy[c][0] = -k * im;
          spec_vy[c][1] = k * re;
        }
        if (deriv) {
          const double k = (*deriv)[j];
          spec[c][0] = -k * im;
          spec[c][1] = k * re;
        } else {
          spec[c][0] = re;
          spec[c][1] = im;
        }
      }
    });
  }

  // The rows rank r's fields hold beyond its slab for a halo of h rows: the
  // h rows before its slab and the h after it, the grid's seam crossed, in
  // that order, without its own rows or repeats; none for an empty slab.
  std::vector<int> halo_rows(int r, int h) const {
    const SlabFft2d::Span own = slab->rows_of(r);
    std::vector<int> list;
    if (own.begin == own.end) return list;
    std::vector<std::uint8_t> seen(static_cast<std::size_t>(ny), 0);
    for (int y = own.begin; y < own.end; ++y) seen[static_cast<std::size_t>(y)] = 1;
    auto add = [&](int y) {
      y = ((y % ny) + ny) % ny;
      if (!seen[static_cast<std::size_t>(y)]) {
        seen[static_cast<std::size_t>(y)] = 1;
        list.push_back(y);
      }
    };
    for (int d = h; d >= 1; --d) add(own.begin - d);
    for (int d = 0; d < h; ++d) add(own.end + d);
    return list;
  }
  // out's rows in this rank's halo of h rows <- their slabs' owners' (one
  // all-to-all; each side knows what the other sends: the rows of the
  // receiver's halo_rows that lie in the sender's slab, in that order).
  void exchange_halo(std::span<double> out, int h) {
    if (h != halo_exchange.rows) {
      halo_exchange.rows = h;
      halo_exchange.send.assign(static_cast<std::size_t>(ranks.ranks), {});
      halo_exchange.receive.assign(static_cast<std::size_t>(ranks.ranks), {});
      std::vector<int> owner(static_cast<std::size_t>(ny), 0);
      for (int r = 0; r < ranks.ranks; ++r)
        for (int y = slab->rows_of(r).begin; y < slab->rows_of(r).end; ++y) owner[static_cast<std::size_t>(y)] = r;
      for (int r = 0; r < ranks.ranks; ++r)
        for (int y : halo_rows(r, h)) {
          const int from = owner[static_cast<std::size_t>(y)];
          if (r == ranks.rank) halo_exchange.receive[static_cast<std::size_t>(from)].push_back(y);
          if (from == ranks.rank) halo_exchange.send[static_cast<std::size_t>(r)].push_back(y);
        }
    }
    const std::size_t row = sizeof(double) * static_cast<std::size_t>(nx);
    std::vector<std::size_t> send_counts(halo_exchange.send.size()), receive_counts(halo_exchange.receive.size());
    std::size_t sent = 0, received = 0;
    for (std::size_t r = 0; r < halo_exchange.send.size(); ++r) {
      send_counts[r] = halo_exchange.send[r].size() * row;
      receive_counts[r] = halo_exchange.receive[r].size() * row;
      sent += send_counts[r];
      received += receive_counts[r];
    }
    halo_exchange.out.resize(sent);
    halo_exchange.in.resize(received);
    std::byte* at = halo_exchange.out.data();
    for (const std::vector<int>& rows_to : halo_exchange.send)
      for (int y : rows_to) {
        std::memcpy(at, out.data() + static_cast<std::size_t>(y) * nx, row);
        at += row;
      }
    ranks.alltoall(halo_exchange.out, send_counts, halo_exchange.in, receive_counts);
    const std::byte* in = halo_exchange.in.data();
    for (const std::vector<int>& rows_from : halo_exchange.receive)
      for (int y : rows_from) {
        std::memcpy(out.data() + static_cast<std::size_t>(y) * nx, in, row);
        in += row;
      }
  }

};

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

  m.real = fftw_alloc_real(m.n);
  m.spec = fftw_alloc_complex(m.nc);
  if (m.ny > 1) m.spec_vy = fftw_alloc_complex(m.nc);
  const unsigned flags = options.measure_fft_plans ? FFTW_MEASURE : FFTW_ESTIMATE;
  m.threads = std::max(options.threads, 1);
  bool planned = false;
  if (m.ny > 1) {
    m.fft2 = std::make_unique<RealFft2d>(m.nx, m.ny, flags, m.real, m.spec);
    planned = m.fft2->valid();
  } else {
    m.r2c = fftw_plan_dft_r2c_1d(m.nx, m.real, m.spec, flags);
    m.c2r = fftw_plan_dft_c2r_1d(m.nx, m.spec, m.real, flags);
    planned = m.r2c && m.c2r;
  }
  if (!planned) throw RunError("fluid: FFTW could not plan the spectral sea transforms");
  if (m.fft2 && options.ranks.distributed() && !options.tank.enabled) {
    m.ranks = options.ranks;
    m.slab = std::make_unique<SlabFft2d>(*m.fft2, m.nx, m.ny, m.ranks.rank, m.ranks.ranks, m.ranks.alltoall);
    m.rows = m.slab->rows();
    m.columns = m.slab->columns();
    for (int r = 0; r < m.ranks.ranks; ++r) {
      const SlabFft2d::Span rows = m.slab->rows_of(r);
      m.row_bytes.push_back(sizeof(double) * static_cast<std::size_t>(rows.end - rows.begin) * m.nx);
    }
  } else {
    m.columns = {0, m.hx};
  }
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
  // The whole transform on every rank; each keeps the bank's modes.
  auto copy_in = [&](std::span<const double> f, std::span<double> a) {
    m.forward(f, m.spec);
    const double* s = reinterpret_cast<const double*>(m.spec);
    const double inv_n = 1.0 / static_cast<double>(m.n);
    m.for_own_modes([&](std::size_t first, std::size_t last, std::size_t mode) {
      for (std::size_t c = first, j = mode; c < last; ++c, ++j) {
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
      // Row by row: the bank's modes [mode, mode + last - first) are the
      // spectrum's [first, last), so q_out is spec shifted by first - mode (>= 0).
      m.for_own_modes([&](std::size_t first, std::size_t last, std::size_t mode) {
        bank_.kick_flow(pending, dt, reinterpret_cast<double*>(m.spec + (first - mode)), mode, mode + (last - first));
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
  FLOESIM_ASSERT(!m.slab &&pressure.size() == m.n && s.size() == 2 * m.nc);
  m.forward(pressure, m.spec);
  m.staged = false;
  const double* f = reinterpret_cast<const double*>(m.spec);
  std::copy(f, f + 2 * m.nc, s.begin());
}

void SpectralSea::synthesize(std::span<const double> q, std::span<double> eta) {
  Impl& m = *impl_;
  FLOESIM_ASSERT(!m.slab &&q.size() == 2 * m.nc && eta.size() == m.n);
  std::copy(q.begin(), q.end(), reinterpret_cast<double*>(m.spec));
  m.staged = false;
  m.backward(eta, m.spec);
}

std::size_t SpectralSea::modal_size() const { return 2 * impl_->nc; }

void SpectralSea::gather_modal_state(std::vector<double>& q, std::vector<double>& v) {
  Impl& m = *impl_;
  if (!m.slab) return Sea::gather_modal_state(q, v);
  settle();
  // Each rank's q then v (its modes, row by row) to rank 0 alone, which puts
  // them at their place in the whole bank's layout.
  const auto size = static_cast<std::size_t>(m.ranks.ranks);
  const auto rank = static_cast<std::size_t>(m.ranks.rank);
  auto part_bytes = [&](int r) { return 2 * 2 * sizeof(double) * static_cast<std::size_t>(m.ny) * m.width_of(r); };
  std::vector<std::size_t> send_counts(size, 0), receive_counts(size, 0);
  std::vector<std::byte> send, receive;
  if (rank != 0) {
    send_counts[0] = part_bytes(m.ranks.rank);
    send.resize(send_counts[0]);
    const std::size_t half = send.size() / 2;
    if (half > 0) {
      std::memcpy(send.data(), bank_.q().data(), half);
      std::memcpy(send.data() + half, bank_.v().data(), half);
    }
  } else {
    std::size_t total = 0;
    for (std::size_t r = 1; r < size; ++r) total += receive_counts[r] = part_bytes(static_cast<int>(r));
    receive.resize(total);
  }
  m.ranks.alltoall(send, send_counts, receive, receive_counts);
  q.clear();
  v.clear();
  if (rank != 0) return;
  q.assign(2 * m.nc, 0.0);
  v.assign(2 * m.nc, 0.0);
  const std::byte* at = receive.data();
  for (int r = 0; r < m.ranks.ranks; ++r) {
    const SlabFft2d::Span cols = m.slab->columns_of(r);
    const std::size_t width = m.width_of(r), values = 2 * width * static_cast<std::size_t>(m.ny);
    const double* from_q = r == 0 ? bank_.q().data() : reinterpret_cast<const double*>(at);
    const double* from_v = r == 0 ? bank_.v().data() : from_q + values;
    for (int iy = 0; iy < m.ny; ++iy) {
      const std::size_t to = 2 * (static_cast<std::size_t>(iy) * m.hx + static_cast<std::size_t>(cols.begin));
      const std::size_t from = 2 * static_cast<std::size_t>(iy) * width;
      std::copy(from_q + from, from_q + from + 2 * width, q.begin() + static_cast<std::ptrdiff_t>(to));
      std::copy(from_v + from, from_v + from + 2 * width, v.begin() + static_cast<std::ptrdiff_t>(to));
    }
    if (r != 0) at += part_bytes(r);
  }
}

void SpectralSea::set_modal_state(std::span<const double> q, std::span<const double> v) {
  Impl& m = *impl_;
  if (!m.slab) return Sea::set_modal_state(q, v);
  FLOESIM_ASSERT(q.size() == 2 * m.nc && v.size() == 2 * m.nc);
  settle();  // the state is replaced: the deferred kicks are applied, then overwritten
  m.for_own_modes([&](std::size_t first, std::size_t last, std::size_t mode) {
    std::copy(q.begin() + static_cast<std::ptrdiff_t>(2 * first), q.begin() + static_cast<std::ptrdiff_t>(2 * last),
              bank_.q().begin() + static_cast<std::ptrdiff_t>(2 * mode));
    std::copy(v.begin() + static_cast<std::ptrdiff_t>(2 * first), v.begin() + static_cast<std::ptrdiff_t>(2 * last),
              bank_.v().begin() + static_cast<std::ptrdiff_t>(2 * mode));
  });
  invalidate();
}

SeaEnergy SpectralSea::bank_energy() {
  Impl& m = *impl_;
  if (!m.slab) return Sea::bank_energy();
  // Each mode's terms to rank 0, which sums them in the whole bank's order
  // (row by row, each row's columns in rank order): ModalBank::kinetic() and
  // potential() of the whole bank, to the bit. Then its two sums to every rank.
  const auto size = static_cast<std::size_t>(m.ranks.ranks);
  const auto rank = static_cast<std::size_t>(m.ranks.rank);
  std::vector<double> own(2 * m.modes);
  bank_.energy_terms(std::span<double>(own.data(), m.modes), std::span<double>(own.data() + m.modes, m.modes));
  std::vector<std::size_t> send_counts(size, 0), receive_counts(size, 0);
  std::vector<double> receive;
  if (rank != 0) {
    send_counts[0] = sizeof(double) * own.size();
  } else {
    std::size_t total = 0;
    for (std::size_t r = 1; r < size; ++r) {
      receive_counts[r] = 2 * sizeof(double) * static_cast<std::size_t>(m.ny) * m.width_of(static_cast<int>(r));
      total += receive_counts[r] / sizeof(double);
    }
    receive.resize(total);
  }
  const std::span<const double> send = rank != 0 ? std::span<const double>(own) : std::span<const double>();
  m.ranks.alltoall(std::as_bytes(send), send_counts, std::as_writable_bytes(std::span<double>(receive)), receive_counts);
  std::array<double, 2> sums{0.0, 0.0};
  if (rank == 0) {
    std::vector<const double*> parts(size);
    parts[0] = own.data();
    const double* at = receive.data();
    for (std::size_t r = 1; r < size; ++r) {
      parts[r] = at;
      at += 2 * static_cast<std::size_t>(m.ny) * m.width_of(static_cast<int>(r));
    }
    for (int iy = 0; iy < m.ny; ++iy)
      for (std::size_t r = 0; r < size; ++r) {
        const std::size_t width = m.width_of(static_cast<int>(r)), modes = width * static_cast<std::size_t>(m.ny);
        const double* kinetic = parts[r] + static_cast<std::size_t>(iy) * width;
        const double* potential = kinetic + modes;
        for (std::size_t k = 0; k < width; ++k) {
          sums[0] += kinetic[k];
          sums[1] += potential[k];
        }
      }
  }
  std::vector<std::size_t> counts(size, 0);
  counts[0] = sizeof(sums);
  m.ranks.allgather(std::as_writable_bytes(std::span<double>(sums)), counts);
  return {0.5 * sums[0], 0.5 * sums[1]};
}

SpectralSea::Memory SpectralSea::memory() const {
  const Impl& m = *impl_;
  Memory r;
  r.modes = bank_.modes();
  r.mode_bytes = bank_.mode_bytes() + sizeof(double) * (m.kx.size() + m.ky.size() + m.phi.size()) +
                 m.kick_spec.size() * sizeof(fftw_complex) * m.kick_capacity;
  r.grid_bytes = sizeof(double) * m.n + sizeof(fftw_complex) * m.nc * (m.spec_vy ? 2 : 1) +
                 sizeof(double) * (m.tank_eta.size() + m.tank_rate.size());
  return r;
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
