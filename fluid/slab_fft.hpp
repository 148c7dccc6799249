#pragma once
// The spectral sea's 2D real transform spread over ranks in slabs
// (docs/parallel.md, stages four and six): rank r of N transforms a share of
// the row blocks and a share of the column blocks of RealFft2d, with one
// transpose between the passes each way.
//
//   forward:  its rows of the field (r2c)  ->  transpose  ->  its columns of the spectrum
//   backward: its columns of the spectrum  ->  transpose  ->  its rows of the field (c2r)
//
// The shares are contiguous blocks in rank order (RealFft2d's blocks of 8
// rows and 4 columns). The columns are equal shares (parallel::share's
// rule), fixed for the run: the modes the sea's bank holds are its columns,
// so moving them would move the sea's state between ranks. The rows are
// given by their cuts (first_row, whole blocks; by default equal shares) and
// may move during a run (set_rows, issue 21 stage seven): a row slab holds
// no state between two transforms, only scratch, and each row block is
// transformed by the whole transform's plans wherever it lies, so the bits
// do not depend on the cuts. Each rank holds its slabs only:
//  - the real side is its rows, nx reals apart (the callers give a pointer to
//    its first row: the rest of a whole field is neither read nor written);
//  - the row pass's half spectrum is its rows, in a scratch of its own
//    (rows x (nx/2 + 1) complex);
//  - the column slab is a spectrum of ny rows of its columns, stride()
//    complex apart (the callers' arrays, column_size() entries).
// The row pass uses the whole transform's plans (the same strides); the
// column pass has plans of its own for the stride of the column slab, which
// is the slab's width rounded up so that stride = nx/2 + 1 modulo 4: every
// entry then has the alignment modulo 64 bytes it has in the whole array, so
// FFTW picks the same codelets and each block's bits are the serial ones,
// whatever N (tests/fluid/test_slab_fft.cpp, mpi.slab_fft_ranks_*).
//
// The transpose is an all-to-all of the blocks where a rank's row slab
// meets another's column slab. fluid/ knows nothing of MPI: the caller
// gives the exchange (parallel::Communicator::alltoall, or nothing when
// serial).

#include <fftw3.h>

#include <cstddef>
#include <functional>
#include <span>
#include <vector>

#include "fluid/fft2d.hpp"
#include "fluid/ranks.hpp"

namespace floesim::fluid {

class SlabFft2d {
public:
  // The transposes' all-to-all (fluid/ranks.hpp); collective.
  using Exchange = decltype(SeaRanks::alltoall);

  // `fft` is the whole transform (planned on arrays of the alignment the
  // callers use); rank `rank` of `ranks`; `exchange` may be empty when
  // ranks = 1; `flags` the column plans' (FFTW_ESTIMATE or FFTW_MEASURE).
  // `first_row`: the row cuts (ranks + 1 values, rank r's rows
  // [first_row[r], first_row[r + 1]), each a multiple of RealFft2d::kRows
  // but the last, ny); empty: equal shares of the row blocks.
  SlabFft2d(const RealFft2d& fft, int nx, int ny, int rank, int ranks, Exchange exchange,
            unsigned flags = FFTW_ESTIMATE, std::vector<int> first_row = {});
  ~SlabFft2d();
  SlabFft2d(const SlabFft2d&) = delete;
  SlabFft2d& operator=(const SlabFft2d&) = delete;

  // This rank's slabs: rows [begin, end) of the real field (and of the half
  // spectrum after the row pass), columns [begin, end) of the half spectrum.
  struct Span {
    int begin = 0, end = 0;
  };
  Span rows() const { return rows_of(rank_); }
  Span columns() const { return columns_of(rank_); }
  Span rows_of(int rank) const;
  Span columns_of(int rank) const;
  // The column slab's layout: column c of row y at y stride() + c - columns().begin.
  int stride() const { return stride_; }
  std::size_t column_size() const { return static_cast<std::size_t>(ny_) * static_cast<std::size_t>(stride_); }

  // spec <- FFT(in) on this rank's columns, unnormalised; `in` points to
  // its first row (in is preserved); spec is a column slab (column_size()).
  void forward(const double* in, fftw_complex* spec, int threads);
  // out's rows <- IFFT(spec) there, unnormalised, `out` pointing to its
  // first row; spec (a column slab) is destroyed.
  void backward(fftw_complex* spec, double* out, int threads);

  // Moves the row cuts (as the constructor's first_row; not collective,
  // but every rank must give the same cuts before the next transform): the
  // row pass's scratch and the transposes' buffers are remade for them.
  void set_rows(std::vector<int> first_row);
  // The row cuts (ranks + 1 values) and the equal shares of the row blocks.
  const std::vector<int>& first_rows() const { return first_row_; }
  static std::vector<int> equal_rows(int ny, int ranks);
  // The thread CPU seconds spent in the row passes since the last call
  // (the rows' share of the transforms' work, for the load balance).
  double take_row_seconds();

  // The bytes this transform holds: the row pass's scratch and the
  // transposes' buffers.
  std::size_t bytes() const;

private:
  // Between the row scratch and the column slab `spec`.
  void transpose(fftw_complex* spec, bool rows_to_columns);
  // The column pass on this rank's column blocks of `spec`.
  void columns_pass(fftw_complex* spec, bool forward, int threads);

  const RealFft2d& fft_;
  int nx_ = 0, ny_ = 0, hx_ = 0, rank_ = 0, ranks_ = 1, stride_ = 0;
  Exchange exchange_;
  fftw_complex* row_spec_ = nullptr;  // this rank's rows of the half spectrum
  std::size_t row_entries_ = 0;
  // [0]: a full block of columns, [1]: the remainder (nullptr when none).
  fftw_plan columns_forward_[2] = {nullptr, nullptr}, columns_backward_[2] = {nullptr, nullptr};
  std::vector<std::byte> send_, receive_;
  std::vector<int> first_row_;  // the row cuts, ranks + 1 values
  double row_seconds_ = 0.0;
};

}  // namespace floesim::fluid
