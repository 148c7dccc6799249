// The spectral sea's 2D real transforms in blocks (fluid/fft2d.hpp): against
// FFTW's own 2D plans (the same transform: equal to round-off), their
// inverse (c2r of r2c is n times the field), and the same bits whatever the
// thread count, on grids whose rows and half-spectrum columns leave
// remainder blocks.
#include <doctest/doctest.h>

#include <fftw3.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "fluid/fft2d.hpp"

using namespace floesim::fluid;

TEST_SUITE_BEGIN("fluid");

TEST_CASE("2D real transforms in blocks: FFTW's 2D transform to round-off, the same bits on 1 to 4 threads") {
  for (auto [nx, ny] : {std::pair{64, 48}, std::pair{30, 21}, std::pair{12, 5}, std::pair{128, 100}}) {
    INFO("nx = " << nx << ", ny = " << ny);
    const int hx = nx / 2 + 1;
    const std::size_t n = static_cast<std::size_t>(nx) * ny, nc = static_cast<std::size_t>(hx) * ny;
    double* real = fftw_alloc_real(n);
    double* field = fftw_alloc_real(n);
    double* back = fftw_alloc_real(n);
    fftw_complex* spec = fftw_alloc_complex(nc);
    fftw_complex* ref = fftw_alloc_complex(nc);
    fftw_complex* out = fftw_alloc_complex(nc);
    RealFft2d fft(nx, ny, FFTW_ESTIMATE, real, spec);
    REQUIRE(fft.valid());
    std::mt19937_64 rng(nx * 1000 + ny);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    for (std::size_t k = 0; k < n; ++k) field[k] = u(rng);

    fftw_plan plan = fftw_plan_dft_r2c_2d(ny, nx, real, ref, FFTW_ESTIMATE);
    std::copy(field, field + n, real);
    fftw_execute(plan);
    fftw_destroy_plan(plan);
    double scale = 0.0;
    for (std::size_t c = 0; c < nc; ++c) scale = std::max(scale, std::hypot(ref[c][0], ref[c][1]));

    std::vector<double> first;
    for (int threads : {1, 2, 3, 4}) {
      INFO(threads << " threads");
      fft.forward(field, out, threads);
      double err = 0.0;
      for (std::size_t c = 0; c < nc; ++c) err = std::max(err, std::hypot(out[c][0] - ref[c][0], out[c][1] - ref[c][1]));
      CHECK(err < 1e-13 * scale);
      std::vector<double> bits(reinterpret_cast<double*>(out), reinterpret_cast<double*>(out) + 2 * nc);
      fft.backward(out, back, threads);  // destroys out
      double inverse = 0.0;
      for (std::size_t k = 0; k < n; ++k) inverse = std::max(inverse, std::abs(back[k] / static_cast<double>(n) - field[k]));
      CHECK(inverse < 1e-13);
      bits.insert(bits.end(), back, back + n);
      if (first.empty()) first = bits;
      else CHECK(bits == first);  // bit for bit
    }
    for (double* p : {real, field, back}) fftw_free(p);
    for (fftw_complex* p : {spec, ref, out}) fftw_free(p);
  }
}
