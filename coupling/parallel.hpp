#pragma once
// Loops of the floe–sea coupling on OpenMP threads, with results that do not
// depend on the thread count: each index's work is independent of the others.
// (The implicit step's reductions sum per body, then exactly:
// coupling/penalty_step.hpp, "Reductions".)
// Internal to coupling/ (the .cpp files that include it link OpenMP).

#include <cstddef>
#include <cstdint>
#include <span>

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

}  // namespace floesim::parallel
