#pragma once
// The spectral sea's 2D real transform spread over ranks in slabs
// (docs/parallel.md, stage four): rank r of N transforms a share of the row
// blocks and a share of the column blocks of RealFft2d, with one transpose
// between the passes each way.
//
//   forward:  rows of its row slab (r2c)  ->  transpose  ->  columns of its column slab
//   backward: columns of its column slab  ->  transpose  ->  rows of its row slab (c2r)
//
// The shares are contiguous blocks in rank order (RealFft2d's blocks of 8
// rows and 4 columns, shared as parallel::share shares items). Every block
// is transformed by the plan and the alignment the whole transform uses, so
// a rank's slab of the result equals the serial transform's to the bit,
// whatever N. The arrays are full size on every rank (only the rank's slab
// is read or written, plus the received blocks): this splits the work of
// the transforms, not their memory.
//
// The transpose is an all-to-all of the blocks where a rank's row slab
// meets another's column slab. fluid/ knows nothing of MPI: the caller
// gives the exchange (parallel::Communicator::alltoall, or nothing when
// serial).

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
  // callers use); rank `rank` of `ranks`; `exchange` may be empty when ranks = 1.
  SlabFft2d(const RealFft2d& fft, int nx, int ny, int rank, int ranks, Exchange exchange);

  // This rank's slabs: rows [begin, end) of the real field (and of the half
  // spectrum after the row pass), columns [begin, end) of the half spectrum.
  struct Span {
    int begin = 0, end = 0;
  };
  Span rows() const { return rows_of(rank_); }
  Span columns() const { return columns_of(rank_); }
  Span rows_of(int rank) const;
  Span columns_of(int rank) const;

  // spec's columns() <- FFT(in) there, unnormalised, reading in's rows()
  // only (in is preserved). spec's other entries are scratch.
  void forward(const double* in, fftw_complex* spec, int threads);
  // out's rows() <- IFFT(spec) there, unnormalised, reading spec's columns()
  // only (spec is destroyed). out's other rows are left as they were.
  void backward(fftw_complex* spec, double* out, int threads);

private:
  // Row slab of `from` x column slab of `to`: packed row by row, from spec.
  void transpose(fftw_complex* spec, bool rows_to_columns);

  const RealFft2d& fft_;
  int nx_ = 0, ny_ = 0, hx_ = 0, rank_ = 0, ranks_ = 1;
  Exchange exchange_;
  std::vector<std::byte> send_, receive_;
};

}  // namespace floesim::fluid
