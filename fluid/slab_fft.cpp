#include "fluid/slab_fft.hpp"

#include <algorithm>
#include <cstring>

#include "core/error.hpp"

namespace floesim::fluid {

namespace {

// Share `rank` of n blocks among `ranks` (as parallel::share: contiguous, in
// rank order, the first n % ranks shares one larger).
SlabFft2d::Span block_share(int n, int rank, int ranks) {
  const int base = n / ranks, extra = n % ranks;
  const int begin = rank * base + std::min(rank, extra);
  return {begin, begin + base + (rank < extra ? 1 : 0)};
}

}  // namespace

SlabFft2d::SlabFft2d(const RealFft2d& fft, int nx, int ny, int rank, int ranks, Exchange exchange)
    : fft_(fft), nx_(nx), ny_(ny), hx_(nx / 2 + 1), rank_(rank), ranks_(ranks), exchange_(std::move(exchange)) {
  FLOESIM_ASSERT(ranks >= 1 && rank >= 0 && rank < ranks && (ranks == 1 || exchange_));
}

SlabFft2d::Span SlabFft2d::rows_of(int rank) const {
  const Span b = block_share(fft_.row_blocks(), rank, ranks_);
  return {std::min(b.begin * RealFft2d::kRows, ny_), std::min(b.end * RealFft2d::kRows, ny_)};
}

SlabFft2d::Span SlabFft2d::columns_of(int rank) const {
  const Span b = block_share(fft_.column_blocks(), rank, ranks_);
  return {std::min(b.begin * RealFft2d::kColumns, hx_), std::min(b.end * RealFft2d::kColumns, hx_)};
}

void SlabFft2d::forward(const double* in, fftw_complex* spec, int threads) {
  const Span r = block_share(fft_.row_blocks(), rank_, ranks_), c = block_share(fft_.column_blocks(), rank_, ranks_);
  fft_.forward_rows(in, spec, r.begin, r.end, threads);
  transpose(spec, true);
  fft_.forward_columns(spec, c.begin, c.end, threads);
}

void SlabFft2d::backward(fftw_complex* spec, double* out, int threads) {
  const Span r = block_share(fft_.row_blocks(), rank_, ranks_), c = block_share(fft_.column_blocks(), rank_, ranks_);
  fft_.backward_columns(spec, c.begin, c.end, threads);
  transpose(spec, false);
  fft_.backward_rows(spec, out, r.begin, r.end, threads);
}

void SlabFft2d::transpose(fftw_complex* spec, bool rows_to_columns) {
  if (ranks_ == 1) return;
  // Rows to columns: this rank holds its row slab (every column) and needs
  // its column slab (every row); it sends rank s the block (its rows, s's
  // columns) and receives (s's rows, its columns). Columns to rows the
  // other way round. A block is sent row by row, each row's columns in order.
  constexpr std::size_t kComplex = sizeof(fftw_complex);
  auto block = [&](int row_owner, int column_owner) {
    return std::pair{rows_of(row_owner), columns_of(column_owner)};
  };
  auto bytes = [&](const std::pair<Span, Span>& b) {
    return static_cast<std::size_t>(b.first.end - b.first.begin) * static_cast<std::size_t>(b.second.end - b.second.begin) *
           kComplex;
  };
  std::vector<std::size_t> send_counts(static_cast<std::size_t>(ranks_)), receive_counts(send_counts.size());
  std::size_t send_total = 0, receive_total = 0;
  for (int s = 0; s < ranks_; ++s) {
    const auto out = rows_to_columns ? block(rank_, s) : block(s, rank_);
    const auto in = rows_to_columns ? block(s, rank_) : block(rank_, s);
    if (s == rank_) continue;  // its own block stays in place
    send_counts[static_cast<std::size_t>(s)] = bytes(out);
    receive_counts[static_cast<std::size_t>(s)] = bytes(in);
    send_total += bytes(out);
    receive_total += bytes(in);
  }
  send_.resize(send_total);
  receive_.resize(receive_total);
  // Copies block b between spec and a packed buffer at `at`; returns the end.
  auto copy = [&](const std::pair<Span, Span>& b, std::byte* at, bool to_buffer) {
    const std::size_t row_bytes = static_cast<std::size_t>(b.second.end - b.second.begin) * kComplex;
    if (row_bytes == 0) return at;
    for (int y = b.first.begin; y < b.first.end; ++y) {
      auto* row = reinterpret_cast<std::byte*>(spec + static_cast<std::ptrdiff_t>(y) * hx_ + b.second.begin);
      if (to_buffer) std::memcpy(at, row, row_bytes);
      else std::memcpy(row, at, row_bytes);
      at += row_bytes;
    }
    return at;
  };
  std::byte* at = send_.data();
  for (int s = 0; s < ranks_; ++s)
    if (s != rank_) at = copy(rows_to_columns ? block(rank_, s) : block(s, rank_), at, true);
  exchange_(send_, send_counts, receive_, receive_counts);
  at = receive_.data();
  for (int s = 0; s < ranks_; ++s)
    if (s != rank_) at = copy(rows_to_columns ? block(s, rank_) : block(rank_, s), at, false);
}

}  // namespace floesim::fluid
