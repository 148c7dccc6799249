#pragma once
// SpectralSea's state (fluid/spectral.hpp), shared by its two source files:
// spectral.cpp (the sea, serial or in slabs) and spectral_slabs.cpp (what a
// sea in slabs gathers: the energy's terms, the modal state for checkpoints,
// and its memory report). Private to fluid/.

#include <fftw3.h>

#include <array>
#include <cstring>
#include <memory>
#include <optional>
#include <vector>

#include "fluid/aligned.hpp"
#include "fluid/fft2d.hpp"
#include "fluid/ranks.hpp"
#include "fluid/slab_fft.hpp"
#include "fluid/spectral.hpp"
#include "fluid/tank.hpp"
#include "fluid/waves.hpp"

namespace floesim::fluid {

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
  // The transforms' scratch: serially the whole grid (real: n reals; spec,
  // spec_vy: the half spectrum, nc complex); in slabs this rank's rows of
  // the real side (real_size reals, from its first row) and its column slab
  // of each spectrum (spec_size complex, row iy at iy SlabFft2d::stride()).
  double* real = nullptr;
  fftw_complex* spec = nullptr;
  // dims = 2: the y-velocity's spectrum, made in the same pass over the modes
  // as the x-velocity's (staged_vy) and used by the next velocity_y query.
  fftw_complex* spec_vy = nullptr;
  std::size_t real_size = 0, spec_size = 0;
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

  // f(first, stop, mode, at) for each range [first, stop) of the half
  // spectrum the bank holds, `mode` the bank's index of `first` and `at` its
  // index in spec and spec_vy: every mode at once when not in slabs (at =
  // first), else this rank's columns of each row (at = iy stride).
  template <class F>
  void for_own_modes(F&& f) const {
    if (!slab) return f(std::size_t{0}, nc, std::size_t{0}, std::size_t{0});
    const auto stride = static_cast<std::size_t>(slab->stride());
    for (int iy = 0; iy < ny; ++iy) {
      const std::size_t row = static_cast<std::size_t>(iy) * hx;
      f(row + columns.begin, row + columns.end, static_cast<std::size_t>(iy) * width, static_cast<std::size_t>(iy) * stride);
    }
  }
  // In slabs, after the slab transform's row cuts were set: this rank's
  // rows, each rank's part of a field, the row scratch `real` (its rows),
  // and the halo's lists (remade at the next exchange).
  void set_rows() {
    rows = slab->rows();
    row_bytes.clear();
    for (int r = 0; r < ranks.ranks; ++r) {
      const SlabFft2d::Span s = slab->rows_of(r);
      row_bytes.push_back(sizeof(double) * static_cast<std::size_t>(s.end - s.begin) * nx);
    }
    fftw_free(real);
    real_size = static_cast<std::size_t>(rows.end - rows.begin) * static_cast<std::size_t>(nx);
    real = fftw_alloc_real(std::max<std::size_t>(real_size, 1));  // fftw_alloc_*(0) may return nullptr
    halo_exchange.rows = -1;
  }
  // The first value of this rank's rows in a whole field (0 when not in slabs).
  std::size_t row_offset() const { return static_cast<std::size_t>(rows.begin) * static_cast<std::size_t>(nx); }
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
  // Whole arrays for planning the whole transform of a sea in slabs, freed
  // after (with FFTW_ESTIMATE the planner does not touch them).
  struct WholeScratch {
    WholeScratch(std::size_t n, std::size_t nc) : real(fftw_alloc_real(n)), spec(fftw_alloc_complex(nc)) {}
    WholeScratch(const WholeScratch&) = delete;
    WholeScratch& operator=(const WholeScratch&) = delete;
    ~WholeScratch() {
      fftw_free(real);
      fftw_free(spec);
    }
    double* real;
    fftw_complex* spec;
  };
  // to <- FFT(field) on the bank's modes, to a kick buffer. In slabs its
  // columns of the transform, made in spec_vy (scratch: a kick voids its
  // staging), are copied to the buffer in the bank's layout.
  void forward_kick(std::span<const double> field, fftw_complex* to) {
    if (!slab) return forward(field, to);
    forward_slab(field, spec_vy);
    for_own_modes([&](std::size_t first, std::size_t stop, std::size_t mode, std::size_t at) {
      std::copy(spec_vy[at], spec_vy[at] + 2 * (stop - first), to[mode]);
    });
  }
  // In slabs: to (spec or spec_vy, a column slab) <- FFT(field) on this
  // rank's columns, reading the field's rows of this rank only (collective).
  void forward_slab(std::span<const double> field, fftw_complex* to) {
    const double* in = field.data() + row_offset();
    if (!aligned(in)) {
      std::copy(in, in + real_size, real);
      in = real;
    }
    slab->forward(in, to, threads);
  }
  // Not in slabs: to <- FFT(field), the whole transform; `to` is spec or a
  // kick buffer (same alignment).
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
  // The rows this rank's fields hold for a halo (Sea::field_rows): in slabs
  // its slab and `halo` rows either side (a first row before the seam is
  // taken modulo ny), the whole grid when that makes every row; with
  // gather_to_writer the whole grid on rank 0 and its slab on the others;
  // halo < 0 or not in slabs, the whole grid.
  Sea::WindowRows window(int halo) const {
    const Sea::WindowRows whole{0, ny};
    if (!slab || halo == -1 || (halo == Sea::gather_to_writer && ranks.rank == 0)) return whole;
    const int h = halo == Sea::gather_to_writer ? 0 : halo;
    if (rows.begin == rows.end) return {rows.begin, 0};
    const int count = rows.end - rows.begin + 2 * h;
    if (count >= ny) return whole;
    return {((rows.begin - h) % ny + ny) % ny, count};
  }
  // The offset in a window of `w`'s rows of row y (which it holds).
  std::size_t at_row(const Sea::WindowRows& w, int y) const {
    return static_cast<std::size_t>(((y - w.first) % ny + ny) % ny) * static_cast<std::size_t>(nx);
  }
  // out <- IFFT(from) (unnormalised; `from`, spec or spec_vy, is destroyed).
  // In slabs: from this rank's columns of `from` to its rows of out, the
  // window of `halo` (window() above; out holds its rows x nx values), then
  // every rank's rows gathered into out (halo < 0: a whole field), or only
  // the halo's rows exchanged (halo >= 0: Sea::set_field_halo), or every
  // rank's rows sent to rank 0 (gather_to_writer).
  void backward(std::span<double> out, fftw_complex* from, int halo = -1) {
    if (slab) {
      const Sea::WindowRows w = window(halo);
      FLOESIM_ASSERT(out.size() == static_cast<std::size_t>(w.rows) * static_cast<std::size_t>(nx));
      backward_own(rows.begin < rows.end ? out.data() + at_row(w, rows.begin) : nullptr, from);
      if (halo == -1) ranks.allgather(std::as_writable_bytes(out), row_bytes);
      else if (halo == Sea::gather_to_writer) gather_rows(out);
      else exchange_halo(out, halo, w);
      return;
    }
    double* to = aligned(out.data()) ? out.data() : real;
    if (fft2) fft2->backward(from, to, threads);
    else fftw_execute_dft_c2r(c2r, from, to);
    if (to == real) std::copy(real, real + n, out.begin());
  }
  // In slabs: this rank's rows of `out`, a whole field (n values), <-
  // IFFT(from) there (collective: the transposes); the other rows are
  // neither read nor written.
  void backward_rows(std::span<double> out, fftw_complex* from) {
    FLOESIM_ASSERT(slab && out.size() == n);
    backward_own(rows.begin < rows.end ? out.data() + row_offset() : nullptr, from);
  }
  // In slabs: `own` (this rank's rows, consecutive; nullptr for an empty
  // slab) <- IFFT(from) there, through `real` when `own` lacks the plans'
  // alignment.
  void backward_own(double* own, fftw_complex* from) {
    double* to = own && aligned(own) ? own : real;
    slab->backward(from, to, threads);
    if (own && to == real) std::copy(real, real + real_size, own);
  }
  // Every rank's rows to rank 0, whose whole window `out` receives them in
  // place (the slabs are consecutive, rank 0's first); the other ranks send
  // theirs (out: their slab's window) and receive nothing.
  void gather_rows(std::span<double> out) {
    gather_rows(out.data(), ranks.rank == 0 ? out.data() : nullptr);
  }
  // `own`: this rank's slab rows; on rank 0, `whole` (n values) receives
  // every rank's (rank 0's own copied unless already in place): one
  // all-to-all to rank 0.
  void gather_rows(const double* own, double* whole) {
    const auto size = static_cast<std::size_t>(ranks.ranks);
    std::vector<std::size_t> send_counts(size, 0), receive_counts(size, 0);
    std::span<const std::byte> send;
    std::span<std::byte> receive;
    if (ranks.rank == 0) {
      FLOESIM_ASSERT(slab->rows_of(0).begin == 0);
      const std::size_t first = static_cast<std::size_t>(rows.end) * static_cast<std::size_t>(nx);
      if (own != whole && first > 0) std::copy(own, own + first, whole);
      for (std::size_t r = 1; r < size; ++r) receive_counts[r] = row_bytes[r];
      receive = std::as_writable_bytes(std::span<double>(whole + first, n - first));
    } else {
      send_counts[0] = row_bytes[static_cast<std::size_t>(ranks.rank)];
      if (send_counts[0] > 0) send = std::as_bytes(std::span<const double>(own, send_counts[0] / sizeof(double)));
    }
    ranks.alltoall(send, send_counts, receive, receive_counts);
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
    for_own_modes([&](std::size_t first, std::size_t stop, std::size_t mode, std::size_t at) {
      for (std::size_t c = at, j = mode; j < mode + (stop - first); ++c, ++j) {
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
  // receiver's halo_rows that lie in the sender's slab, in that order). out
  // is the window w of the slab and that halo (window(h)).
  void exchange_halo(std::span<double> out, int h, const Sea::WindowRows& w) {
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
        std::memcpy(at, out.data() + at_row(w, y), row);
        at += row;
      }
    ranks.alltoall(halo_exchange.out, send_counts, halo_exchange.in, receive_counts);
    const std::byte* in = halo_exchange.in.data();
    for (const std::vector<int>& rows_from : halo_exchange.receive)
      for (int y : rows_from) {
        std::memcpy(out.data() + at_row(w, y), in, row);
        in += row;
      }
  }

};

}  // namespace floesim::fluid
