#pragma once
// The spectral sea's 2D real transforms (FFTW's layout: ny rows of nx reals
// <-> ny rows of nx / 2 + 1 complex coefficients), done as 1D transforms in
// fixed blocks spread over threads. Internal to fluid/ (FFTW stays here).
//
// r2c = a real FFT along each row, then a complex FFT along each column of
// the half spectrum; c2r the same backwards. The blocks (8 rows, 4 columns,
// and one plan for each remainder) are fixed by the grid alone, and each
// block is always transformed by its own plan, so the bits do not depend on
// the thread count. Blocks start at multiples of 64 bytes from the arrays'
// starts, so every block has the alignment of the arrays the plans were
// made on; callers pass arrays of that alignment (fftw_alloc_*).
//
// Each pass can also be run on a range of its blocks alone ([first, last) of
// row_blocks() or column_blocks()): a block's result depends on its input
// alone, so a transform spread over ranks by blocks (fluid/slab_fft.hpp)
// gives the same bits as the whole one.

#include <fftw3.h>

namespace floesim::fluid {

class RealFft2d {
public:
  // Plans on `real` (nx ny) and `spec` (ny (nx / 2 + 1)), which planning
  // overwrites; flags as fftw_plan_* (FFTW_ESTIMATE or FFTW_MEASURE).
  RealFft2d(int nx, int ny, unsigned flags, double* real, fftw_complex* spec);
  ~RealFft2d();
  RealFft2d(const RealFft2d&) = delete;
  RealFft2d& operator=(const RealFft2d&) = delete;

  bool valid() const;
  // out <- FFT(in), unnormalised; in is preserved.
  void forward(const double* in, fftw_complex* out, int threads) const;
  // out <- IFFT(in), unnormalised; in is destroyed.
  void backward(fftw_complex* in, double* out, int threads) const;

  // The passes on blocks [first, last): forward = forward_rows then
  // forward_columns on every block; backward = backward_columns then
  // backward_rows. A row block is rows [kRows b, min(kRows (b + 1), ny)) of
  // both arrays, a column block columns [kColumns b, ...) of the half spectrum.
  // The row passes' arrays may hold rows from `origin` on only (their
  // pointers are to row `origin`; a slab of rows, fluid/slab_fft.hpp).
  static constexpr int kRows = 8, kColumns = 4;
  int row_blocks() const { return (ny_ + kRows - 1) / kRows; }
  int column_blocks() const { return (hx_ + kColumns - 1) / kColumns; }
  void forward_rows(const double* in, fftw_complex* out, int first, int last, int threads, int origin = 0) const;
  void forward_columns(fftw_complex* spec, int first, int last, int threads) const;
  void backward_columns(fftw_complex* spec, int first, int last, int threads) const;
  void backward_rows(fftw_complex* in, double* out, int first, int last, int threads, int origin = 0) const;

private:
  int nx_ = 0, ny_ = 0, hx_ = 0;
  // [0]: a full block, [1]: the remainder (nullptr when none).
  fftw_plan rows_r2c_[2] = {nullptr, nullptr}, rows_c2r_[2] = {nullptr, nullptr};
  fftw_plan columns_forward_[2] = {nullptr, nullptr}, columns_backward_[2] = {nullptr, nullptr};
};

}  // namespace floesim::fluid
