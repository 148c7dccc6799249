#pragma once
// The check shared by the slab transform's tests (tests/fluid/test_slab_fft.cpp,
// ranks played by threads; tests/parallel/slab_fft_ranks.cpp, ranks started by
// mpirun): a seeded field's whole 2D transform and inverse (fluid/fft2d.hpp),
// and one rank's slab transform (fluid/slab_fft.hpp) compared with them bit
// for bit. Each rank is given its rows of the field only (it reads no other)
// and, for the inverse, its columns of the spectrum only.
#include <fftw3.h>

#include <algorithm>
#include <cstring>
#include <random>
#include <vector>

#include "fluid/slab_fft.hpp"

namespace floesim::fluid::testing {

// A buffer from FFTW's allocator (aligned as the plans expect).
template <class T>
struct FftwBuffer {
  explicit FftwBuffer(std::size_t n) : data(static_cast<T*>(fftw_malloc(n * sizeof(T)))) {}
  FftwBuffer(const FftwBuffer&) = delete;
  FftwBuffer& operator=(const FftwBuffer&) = delete;
  ~FftwBuffer() { fftw_free(data); }
  T* data;
};

// An nx x ny field of uniform values in [-1, 1) seeded by the grid (the same
// field on every rank), its whole transform and the inverse of that. The plan
// is made here, once: FFTW's planner is not thread-safe, its plans' execution
// on other arrays is.
struct WholeTransform {
  WholeTransform(int nx_, int ny_)
      : nx(nx_), ny(ny_), hx(nx_ / 2 + 1), n(static_cast<std::size_t>(nx_) * ny_), nc(static_cast<std::size_t>(hx) * ny_),
        real(n), spec(nc), fft(nx_, ny_, FFTW_ESTIMATE, real.data, spec.data), field(n) {
    std::mt19937_64 rng(static_cast<unsigned long>(nx) * 1000 + static_cast<unsigned long>(ny));
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    for (double& x : field) x = u(rng);
    std::copy(field.begin(), field.end(), real.data);
    fft.forward(real.data, spec.data, 1);
    spectrum.assign(reinterpret_cast<double*>(spec.data), reinterpret_cast<double*>(spec.data) + 2 * nc);
    fft.backward(spec.data, real.data, 1);
    inverse.assign(real.data, real.data + n);
  }
  int nx, ny, hx;
  std::size_t n, nc;  // real values, complex values of the half spectrum
  FftwBuffer<double> real;
  FftwBuffer<fftw_complex> spec;
  RealFft2d fft;
  std::vector<double> field, spectrum, inverse;  // spectrum: (re, im) pairs
};

struct SlabCheck {
  SlabFft2d::Span rows, columns;
  bool spectrum_equal = false;  // the rank's columns of the forward transform
  bool inverse_equal = false;   // the rank's rows of the backward transform
};

// One rank's forward and backward slab transforms of `whole`'s field and
// spectrum (every rank must call it together, through the slab's exchange).
// The rank holds its rows of the field only (a buffer of its rows) and its
// columns of the spectrum only (a column slab, SlabFft2d::column_size()).
inline SlabCheck check_slab(const WholeTransform& whole, SlabFft2d& slab) {
  const int nx = whole.nx, ny = whole.ny;
  SlabCheck check{slab.rows(), slab.columns()};
  const std::size_t rows = static_cast<std::size_t>(check.rows.end - check.rows.begin);
  const std::size_t values = rows * static_cast<std::size_t>(nx);
  FftwBuffer<double> in(std::max<std::size_t>(values, 1)), out(std::max<std::size_t>(values, 1));
  FftwBuffer<fftw_complex> s(std::max<std::size_t>(slab.column_size(), 1));
  std::memcpy(in.data, whole.field.data() + static_cast<std::size_t>(check.rows.begin) * nx, sizeof(double) * values);
  slab.forward(in.data, s.data, 1);
  auto at = [&](int y, int x) { return static_cast<std::size_t>(y) * slab.stride() + (x - check.columns.begin); };
  bool equal = true;
  for (int y = 0; y < ny; ++y)
    for (int x = check.columns.begin; x < check.columns.end; ++x) {
      const std::size_t c = static_cast<std::size_t>(y) * whole.hx + x;
      equal = equal && std::memcmp(s.data[at(y, x)], &whole.spectrum[2 * c], sizeof(fftw_complex)) == 0;
    }
  check.spectrum_equal = equal;
  std::fill(reinterpret_cast<double*>(s.data), reinterpret_cast<double*>(s.data) + 2 * slab.column_size(), 0.0);
  for (int y = 0; y < ny; ++y)
    for (int x = check.columns.begin; x < check.columns.end; ++x) {
      const std::size_t c = static_cast<std::size_t>(y) * whole.hx + x;
      s.data[at(y, x)][0] = whole.spectrum[2 * c];
      s.data[at(y, x)][1] = whole.spectrum[2 * c + 1];
    }
  slab.backward(s.data, out.data, 1);
  check.inverse_equal = values == 0 || std::memcmp(out.data, whole.inverse.data() + static_cast<std::size_t>(check.rows.begin) * nx,
                                                   sizeof(double) * values) == 0;
  return check;
}

}  // namespace floesim::fluid::testing
