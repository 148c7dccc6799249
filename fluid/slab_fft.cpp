#include "fluid/slab_fft.hpp"

#include <algorithm>
#include <cstring>

#include <time.h>

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

double thread_cpu_seconds() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

}  // namespace

std::vector<int> SlabFft2d::equal_rows(int ny, int ranks) {
  const int blocks = (ny + RealFft2d::kRows - 1) / RealFft2d::kRows;
  std::vector<int> first;
  for (int r = 0; r < ranks; ++r) first.push_back(std::min(block_share(blocks, r, ranks).begin * RealFft2d::kRows, ny));
  first.push_back(ny);
  return first;
}

SlabFft2d::SlabFft2d(const RealFft2d& fft, int nx, int ny, int rank, int ranks, Exchange exchange, unsigned flags,
                     std::vector<int> first_row)
    : fft_(fft), nx_(nx), ny_(ny), hx_(nx / 2 + 1), rank_(rank), ranks_(ranks), exchange_(std::move(exchange)) {
  FLOESIM_ASSERT(ranks >= 1 && rank >= 0 && rank < ranks && (ranks == 1 || exchange_));
  const Span own_columns = columns();
  const int width = own_columns.end - own_columns.begin;
  // The smallest stride >= width with stride = hx (mod 4): row y of the slab
  // then starts at the alignment modulo 64 bytes of row y of the whole array.
  // And wider than a block unless the whole array is not: FFTW plans
  // columns that are contiguous (stride 1) otherwise than strided ones.
  stride_ = width + (((hx_ - width) % RealFft2d::kColumns) + RealFft2d::kColumns) % RealFft2d::kColumns;
  while (stride_ <= RealFft2d::kColumns && stride_ < hx_) stride_ += RealFft2d::kColumns;
  set_rows(first_row.empty() ? equal_rows(ny_, ranks_) : std::move(first_row));
  if (width == 0) return;
  // The column plans, made on a scratch slab (planning may overwrite it) and
  // run on the callers' slabs of the same alignment (fftw_alloc_*).
  fftw_complex* scratch = fftw_alloc_complex(column_size());
  const int counts[2] = {std::min(RealFft2d::kColumns, hx_), hx_ % RealFft2d::kColumns};
  for (int k = 0; k < 2; ++k) {
    if (counts[k] == 0 || (k == 1 && hx_ < RealFft2d::kColumns)) continue;
    columns_forward_[k] = fftw_plan_many_dft(1, &ny_, counts[k], scratch, nullptr, stride_, 1, scratch, nullptr, stride_, 1,
                                             FFTW_FORWARD, flags);
    columns_backward_[k] = fftw_plan_many_dft(1, &ny_, counts[k], scratch, nullptr, stride_, 1, scratch, nullptr, stride_,
                                              1, FFTW_BACKWARD, flags);
  }
  fftw_free(scratch);
  if (!columns_forward_[0] || !columns_backward_[0]) throw RunError("fluid: FFTW could not plan the slab transform's columns");
}

void SlabFft2d::set_rows(std::vector<int> first_row) {
  FLOESIM_ASSERT(first_row.size() == static_cast<std::size_t>(ranks_) + 1 && first_row.front() == 0 &&
                 first_row.back() == ny_ && std::is_sorted(first_row.begin(), first_row.end()));
  for (int r = 1; r < ranks_; ++r) FLOESIM_ASSERT(first_row[static_cast<std::size_t>(r)] % RealFft2d::kRows == 0 || first_row[static_cast<std::size_t>(r)] == ny_);
  first_row_ = std::move(first_row);
  const Span own_rows = rows(), own_columns = columns();
  fftw_free(row_spec_);
  row_entries_ = static_cast<std::size_t>(own_rows.end - own_rows.begin) * static_cast<std::size_t>(hx_);
  row_spec_ = fftw_alloc_complex(std::max<std::size_t>(row_entries_, 1));
  // The transposes' buffers at their size: the blocks of its rows and
  // others' columns, and of others' rows and its columns, each sent one
  // way and received the other.
  std::size_t to_others = 0, from_others = 0;
  for (int s = 0; s < ranks_; ++s) {
    if (s == rank_) continue;
    const Span r = rows_of(s), c = columns_of(s);
    to_others += static_cast<std::size_t>(own_rows.end - own_rows.begin) * static_cast<std::size_t>(c.end - c.begin);
    from_others += static_cast<std::size_t>(r.end - r.begin) * static_cast<std::size_t>(own_columns.end - own_columns.begin);
  }
  const std::size_t buffer = sizeof(fftw_complex) * std::max(to_others, from_others);
  std::vector<std::byte>().swap(send_);
  std::vector<std::byte>().swap(receive_);
  send_.reserve(buffer);
  receive_.reserve(buffer);
}

double SlabFft2d::take_row_seconds() {
  const double s = row_seconds_;
  row_seconds_ = 0.0;
  return s;
}

SlabFft2d::~SlabFft2d() {
  for (fftw_plan* set : {columns_forward_, columns_backward_})
    for (int k = 0; k < 2; ++k)
      if (set[k]) fftw_destroy_plan(set[k]);
  fftw_free(row_spec_);
}

SlabFft2d::Span SlabFft2d::rows_of(int rank) const {
  return {first_row_[static_cast<std::size_t>(rank)], first_row_[static_cast<std::size_t>(rank) + 1]};
}

SlabFft2d::Span SlabFft2d::columns_of(int rank) const {
  const Span b = block_share(fft_.column_blocks(), rank, ranks_);
  return {std::min(b.begin * RealFft2d::kColumns, hx_), std::min(b.end * RealFft2d::kColumns, hx_)};
}

std::size_t SlabFft2d::bytes() const {
  return sizeof(fftw_complex) * row_entries_ + send_.capacity() + receive_.capacity();
}

void SlabFft2d::forward(const double* in, fftw_complex* spec, int threads) {
  const Span r = rows();
  const double start = thread_cpu_seconds();
  fft_.forward_rows(in, row_spec_, (r.begin + RealFft2d::kRows - 1) / RealFft2d::kRows, (r.end + RealFft2d::kRows - 1) / RealFft2d::kRows, threads,
                    r.begin);
  row_seconds_ += thread_cpu_seconds() - start;
  transpose(spec, true);
  columns_pass(spec, true, threads);
}

void SlabFft2d::backward(fftw_complex* spec, double* out, int threads) {
  const Span r = rows();
  columns_pass(spec, false, threads);
  transpose(spec, false);
  const double start = thread_cpu_seconds();
  fft_.backward_rows(row_spec_, out, (r.begin + RealFft2d::kRows - 1) / RealFft2d::kRows, (r.end + RealFft2d::kRows - 1) / RealFft2d::kRows, threads,
                     r.begin);
  row_seconds_ += thread_cpu_seconds() - start;
}

void SlabFft2d::columns_pass(fftw_complex* spec, bool forward, int threads) {
  const Span c = block_share(fft_.column_blocks(), rank_, ranks_);
  const int first = columns().begin;
  const fftw_plan* plans = forward ? columns_forward_ : columns_backward_;
  const int blocks = c.end - c.begin;
#pragma omp parallel for num_threads(threads) schedule(static) if (threads > 1 && blocks > 1)
  for (int j = 0; j < blocks; ++j) {
    const int c0 = (c.begin + j) * RealFft2d::kColumns;
    const fftw_plan p = c0 + RealFft2d::kColumns <= hx_ || hx_ < RealFft2d::kColumns ? plans[0] : plans[1];
    fftw_complex* at = spec + (c0 - first);
    fftw_execute_dft(p, at, at);
  }
}

void SlabFft2d::transpose(fftw_complex* spec, bool rows_to_columns) {
  // Rows to columns: this rank holds its row slab (every column) in
  // row_spec_ and needs its column slab (every row) in spec; it sends rank s
  // the block (its rows, s's columns) and receives (s's rows, its columns).
  // Columns to rows the other way round. A block is sent row by row, each
  // row's columns in order; its own block is copied.
  constexpr std::size_t kComplex = sizeof(fftw_complex);
  const Span own_rows = rows(), own_columns = columns();
  auto block = [&](int row_owner, int column_owner) { return std::pair{rows_of(row_owner), columns_of(column_owner)}; };
  auto bytes = [&](const std::pair<Span, Span>& b) {
    return static_cast<std::size_t>(b.first.end - b.first.begin) * static_cast<std::size_t>(b.second.end - b.second.begin) *
           kComplex;
  };
  // Row y, column x of block b: in row_spec_ when the block is this rank's
  // rows, else in spec (this rank's columns).
  auto entry = [&](int y, int x, bool in_rows) -> fftw_complex* {
    if (in_rows) return row_spec_ + static_cast<std::ptrdiff_t>(y - own_rows.begin) * hx_ + x;
    return spec + static_cast<std::ptrdiff_t>(y) * stride_ + (x - own_columns.begin);
  };
  // Copies block b between an array (row_spec_ or spec) and a packed buffer.
  auto copy = [&](const std::pair<Span, Span>& b, bool in_rows, std::byte* at, bool to_buffer) {
    const std::size_t row_bytes = static_cast<std::size_t>(b.second.end - b.second.begin) * kComplex;
    if (row_bytes == 0) return at;
    for (int y = b.first.begin; y < b.first.end; ++y) {
      auto* row = reinterpret_cast<std::byte*>(entry(y, b.second.begin, in_rows));
      if (to_buffer) std::memcpy(at, row, row_bytes);
      else std::memcpy(row, at, row_bytes);
      at += row_bytes;
    }
    return at;
  };
  // This rank's own block, between the two arrays.
  {
    const auto own = block(rank_, rank_);
    const std::size_t row_bytes = static_cast<std::size_t>(own.second.end - own.second.begin) * kComplex;
    if (row_bytes > 0)
      for (int y = own.first.begin; y < own.first.end; ++y) {
        fftw_complex* r = entry(y, own.second.begin, true);
        fftw_complex* c = entry(y, own.second.begin, false);
        if (rows_to_columns) std::memcpy(c, r, row_bytes);
        else std::memcpy(r, c, row_bytes);
      }
  }
  if (ranks_ == 1) return;
  std::vector<std::size_t> send_counts(static_cast<std::size_t>(ranks_)), receive_counts(send_counts.size());
  std::size_t send_total = 0, receive_total = 0;
  for (int s = 0; s < ranks_; ++s) {
    if (s == rank_) continue;
    const auto out = rows_to_columns ? block(rank_, s) : block(s, rank_);
    const auto in = rows_to_columns ? block(s, rank_) : block(rank_, s);
    send_counts[static_cast<std::size_t>(s)] = bytes(out);
    receive_counts[static_cast<std::size_t>(s)] = bytes(in);
    send_total += bytes(out);
    receive_total += bytes(in);
  }
  send_.resize(send_total);
  receive_.resize(receive_total);
  // Forward: sent from the rows, received into the columns; backward the reverse.
  std::byte* at = send_.data();
  for (int s = 0; s < ranks_; ++s)
    if (s != rank_) at = copy(rows_to_columns ? block(rank_, s) : block(s, rank_), rows_to_columns, at, true);
  exchange_(send_, send_counts, receive_, receive_counts);
  at = receive_.data();
  for (int s = 0; s < ranks_; ++s)
    if (s != rank_) at = copy(rows_to_columns ? block(s, rank_) : block(rank_, s), !rows_to_columns, at, false);
}

}  // namespace floesim::fluid
