#include "fluid/fft2d.hpp"

#include <algorithm>
#include <cstddef>

namespace floesim::fluid {

namespace {

// f(b) for each of the `blocks` blocks, on threads (the blocks' work is independent).
template <class F>
void for_each_block(int blocks, int threads, F&& f) {
#pragma omp parallel for num_threads(threads) schedule(static) if (threads > 1 && blocks > 1)
  for (int b = 0; b < blocks; ++b) f(b);
}

}  // namespace

RealFft2d::RealFft2d(int nx, int ny, unsigned flags, double* real, fftw_complex* spec)
    : nx_(nx), ny_(ny), hx_(nx / 2 + 1) {
  const int row_counts[2] = {std::min(kRows, ny), ny % kRows};
  const int column_counts[2] = {std::min(kColumns, hx_), hx_ % kColumns};
  for (int k = 0; k < 2; ++k) {
    if (row_counts[k] == 0 || (k == 1 && ny < kRows)) continue;
    const int howmany = row_counts[k];
    // Rows: n = nx, consecutive rows nx reals / hx complex apart.
    rows_r2c_[k] = fftw_plan_many_dft_r2c(1, &nx_, howmany, real, nullptr, 1, nx_, spec, nullptr, 1, hx_, flags);
    rows_c2r_[k] = fftw_plan_many_dft_c2r(1, &nx_, howmany, spec, nullptr, 1, hx_, real, nullptr, 1, nx_, flags);
  }
  for (int k = 0; k < 2; ++k) {
    if (column_counts[k] == 0 || (k == 1 && hx_ < kColumns)) continue;
    const int howmany = column_counts[k];
    // Columns of the half spectrum, in place: n = ny, stride hx, neighbours 1 apart.
    columns_forward_[k] =
        fftw_plan_many_dft(1, &ny_, howmany, spec, nullptr, hx_, 1, spec, nullptr, hx_, 1, FFTW_FORWARD, flags);
    columns_backward_[k] =
        fftw_plan_many_dft(1, &ny_, howmany, spec, nullptr, hx_, 1, spec, nullptr, hx_, 1, FFTW_BACKWARD, flags);
  }
}

RealFft2d::~RealFft2d() {
  for (fftw_plan* set : {rows_r2c_, rows_c2r_, columns_forward_, columns_backward_})
    for (int k = 0; k < 2; ++k)
      if (set[k]) fftw_destroy_plan(set[k]);
}

bool RealFft2d::valid() const {
  const bool row_rest = ny_ >= kRows && ny_ % kRows != 0, column_rest = hx_ >= kColumns && hx_ % kColumns != 0;
  return rows_r2c_[0] && rows_c2r_[0] && columns_forward_[0] && columns_backward_[0] &&
         (!row_rest || (rows_r2c_[1] && rows_c2r_[1])) && (!column_rest || (columns_forward_[1] && columns_backward_[1]));
}

void RealFft2d::forward(const double* in, fftw_complex* out, int threads) const {
  forward_rows(in, out, 0, row_blocks(), threads);
  forward_columns(out, 0, column_blocks(), threads);
}

void RealFft2d::backward(fftw_complex* in, double* out, int threads) const {
  backward_columns(in, 0, column_blocks(), threads);
  backward_rows(in, out, 0, row_blocks(), threads);
}

void RealFft2d::forward_rows(const double* in, fftw_complex* out, int first, int last, int threads, int origin) const {
  for_each_block(last - first, threads, [&](int j) {
    const int r0 = (first + j) * kRows;
    const fftw_plan p = r0 + kRows <= ny_ || ny_ < kRows ? rows_r2c_[0] : rows_r2c_[1];
    const std::ptrdiff_t row = r0 - origin;
    fftw_execute_dft_r2c(p, const_cast<double*>(in) + row * nx_, out + row * hx_);
  });
}

void RealFft2d::forward_columns(fftw_complex* spec, int first, int last, int threads) const {
  for_each_block(last - first, threads, [&](int j) {
    const int c0 = (first + j) * kColumns;
    const fftw_plan p = c0 + kColumns <= hx_ || hx_ < kColumns ? columns_forward_[0] : columns_forward_[1];
    fftw_execute_dft(p, spec + c0, spec + c0);
  });
}

void RealFft2d::backward_columns(fftw_complex* spec, int first, int last, int threads) const {
  for_each_block(last - first, threads, [&](int j) {
    const int c0 = (first + j) * kColumns;
    const fftw_plan p = c0 + kColumns <= hx_ || hx_ < kColumns ? columns_backward_[0] : columns_backward_[1];
    fftw_execute_dft(p, spec + c0, spec + c0);
  });
}

void RealFft2d::backward_rows(fftw_complex* in, double* out, int first, int last, int threads, int origin) const {
  for_each_block(last - first, threads, [&](int j) {
    const int r0 = (first + j) * kRows;
    const fftw_plan p = r0 + kRows <= ny_ || ny_ < kRows ? rows_c2r_[0] : rows_c2r_[1];
    const std::ptrdiff_t row = r0 - origin;
    fftw_execute_dft_c2r(p, in + row * hx_, out + row * nx_);
  });
}

}  // namespace floesim::fluid
