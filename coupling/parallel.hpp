#pragma once
// Loops of the floe–sea coupling on OpenMP threads, with results that do not
// depend on the thread count: each index's work is independent of the others,
// and reductions are summed in fixed blocks, then the blocks in order.
// Internal to coupling/ (the .cpp files that include it link OpenMP).

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace floesim::parallel {

// Loops over fewer floes (or pieces, for_each_index) than this stay on one
// thread: a parallel region costs a fork and a barrier, ruinous for short
// loops when the cores are shared (each barrier may wait a scheduler slice).
inline constexpr std::ptrdiff_t kFloesPerThread = 64;

// f(k) for k < n on `threads` threads; on one thread when n is at most
// `grain` (not worth a fork).
template <class F>
void for_each_index(std::size_t n, int threads, F&& f, std::size_t grain = 4096) {
  const auto count = static_cast<std::ptrdiff_t>(n);
#pragma omp parallel for num_threads(threads) schedule(static) if (n > grain)
  for (std::ptrdiff_t k = 0; k < count; ++k) f(static_cast<std::size_t>(k));
}

// f(i) for the floes (or groups) listed in `order`, on threads.
template <class F>
void for_each_of(std::span<const std::uint32_t> order, int threads, F&& f) {
  const auto count = static_cast<std::ptrdiff_t>(order.size());
#pragma omp parallel for num_threads(threads) schedule(dynamic, 16) if (count > kFloesPerThread)
  for (std::ptrdiff_t j = 0; j < count; ++j) f(order[static_cast<std::size_t>(j)]);
}

// a . b: the same bits whatever the thread count.
inline double dot(std::span<const double> a, std::span<const double> b, int threads) {
  constexpr std::size_t kBlock = 2048;
  const std::size_t blocks = (a.size() + kBlock - 1) / kBlock;
  std::vector<double> partial(blocks, 0.0);
  for_each_index(blocks, threads, [&](std::size_t block) {
    double s = 0.0;
    for (std::size_t k = block * kBlock; k < std::min(a.size(), (block + 1) * kBlock); ++k) s += a[k] * b[k];
    partial[block] = s;
  }, 2);
  double s = 0.0;
  for (double x : partial) s += x;
  return s;
}

inline double max_abs(std::span<const double> x) {
  double m = 0.0;
  for (double v : x) m = std::max(m, v < 0.0 ? -v : v);
  return m;
}

}  // namespace floesim::parallel
