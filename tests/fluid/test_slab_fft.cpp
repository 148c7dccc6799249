// The 2D transform in slabs (fluid/slab_fft.hpp) against the whole one
// (fluid/fft2d.hpp): on 1 to 5 ranks, played here by threads that exchange
// through shared memory (the exchange MPI does between processes), each
// rank's slab of the spectrum and of the inverse equals the whole
// transform's to the bit, and the slabs cover the grid. Grids with
// remainder blocks, and more ranks than row or column blocks (empty slabs).
#include <doctest/doctest.h>

#include <fftw3.h>

#include <algorithm>
#include <atomic>
#include <barrier>
#include <cstring>
#include <random>
#include <thread>
#include <vector>

#include "fluid/slab_fft.hpp"

using namespace floesim::fluid;

TEST_SUITE_BEGIN("fluid");

namespace {

// An all-to-all among `ranks` threads: each posts its buffer and counts,
// waits for all, copies its parts out of every rank's buffer, waits again
// (so no buffer is reused before every rank has read it).
struct ThreadExchange {
  explicit ThreadExchange(int ranks) : posted(static_cast<std::size_t>(ranks)), counts(posted.size()), sync(ranks) {}
  SlabFft2d::Exchange of(int rank) {
    return [this, rank](std::span<const std::byte> send, const std::vector<std::size_t>& send_counts,
                        std::span<std::byte> receive, const std::vector<std::size_t>& receive_counts) {
      posted[static_cast<std::size_t>(rank)] = send;
      counts[static_cast<std::size_t>(rank)] = send_counts;
      sync.arrive_and_wait();
      std::size_t at = 0;
      for (std::size_t s = 0; s < posted.size(); ++s) {
        std::size_t offset = 0;
        for (int t = 0; t < rank; ++t) offset += counts[s][static_cast<std::size_t>(t)];
        if (counts[s][static_cast<std::size_t>(rank)] != receive_counts[s]) mismatched = true;
        if (receive_counts[s] > 0) std::memcpy(receive.data() + at, posted[s].data() + offset, receive_counts[s]);
        at += receive_counts[s];
      }
      sync.arrive_and_wait();
    };
  }
  std::vector<std::span<const std::byte>> posted;
  std::vector<std::vector<std::size_t>> counts;
  std::barrier<> sync;
  std::atomic<bool> mismatched{false};  // a rank expected another count than its sender sent (set by any thread, read after join)
};

}  // namespace

TEST_CASE("2D transform in slabs: each rank's slab equals the whole transform's bits, on 1 to 5 ranks") {
  for (auto [nx, ny] : {std::pair{64, 48}, std::pair{30, 21}, std::pair{12, 5}, std::pair{26, 40}}) {
    const int hx = nx / 2 + 1;
    const std::size_t n = static_cast<std::size_t>(nx) * ny, nc = static_cast<std::size_t>(hx) * ny;
    double* real = fftw_alloc_real(n);
    fftw_complex* spec = fftw_alloc_complex(nc);
    RealFft2d fft(nx, ny, FFTW_ESTIMATE, real, spec);
    REQUIRE(fft.valid());
    std::mt19937_64 rng(nx * 1000 + ny);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    std::vector<double> field(n);
    for (double& x : field) x = u(rng);
    // The whole transform, and its inverse.
    std::copy(field.begin(), field.end(), real);
    fft.forward(real, spec, 1);
    const std::vector<double> whole(reinterpret_cast<double*>(spec), reinterpret_cast<double*>(spec) + 2 * nc);
    fft.backward(spec, real, 1);
    const std::vector<double> inverse(real, real + n);

    for (int ranks = 1; ranks <= 5; ++ranks) {
      INFO("nx = " << nx << ", ny = " << ny << ", " << ranks << " ranks");
      ThreadExchange exchange(ranks);
      std::vector<int> rows_covered(static_cast<std::size_t>(ny), 0), columns_covered(static_cast<std::size_t>(hx), 0);
      std::vector<int> spec_equal(static_cast<std::size_t>(ranks), 0), back_equal(spec_equal.size(), 0);
      std::vector<std::thread> threads;
      for (int r = 0; r < ranks; ++r)
        threads.emplace_back([&, r] {
          SlabFft2d slab(fft, nx, ny, r, ranks, ranks > 1 ? exchange.of(r) : SlabFft2d::Exchange{});
          double* in = fftw_alloc_real(n);
          double* out = fftw_alloc_real(n);
          fftw_complex* s = fftw_alloc_complex(nc);
          // Only the rank's rows of the input are set: it reads no other.
          std::fill(in, in + n, 0.0);
          const SlabFft2d::Span rows = slab.rows(), columns = slab.columns();
          for (int y = rows.begin; y < rows.end; ++y)
            for (int x = 0; x < nx; ++x) in[static_cast<std::size_t>(y) * nx + x] = field[static_cast<std::size_t>(y) * nx + x];
          slab.forward(in, s, 1);
          bool equal = true;
          for (int y = 0; y < ny; ++y)
            for (int x = columns.begin; x < columns.end; ++x) {
              const std::size_t c = static_cast<std::size_t>(y) * hx + x;
              equal = equal && std::memcmp(s[c], &whole[2 * c], sizeof(fftw_complex)) == 0;
            }
          spec_equal[static_cast<std::size_t>(r)] = equal;
          // Only the rank's columns of the spectrum are set for the inverse.
          std::fill(reinterpret_cast<double*>(s), reinterpret_cast<double*>(s) + 2 * nc, 0.0);
          for (int y = 0; y < ny; ++y)
            for (int x = columns.begin; x < columns.end; ++x) {
              const std::size_t c = static_cast<std::size_t>(y) * hx + x;
              s[c][0] = whole[2 * c];
              s[c][1] = whole[2 * c + 1];
            }
          slab.backward(s, out, 1);
          equal = true;
          for (int y = rows.begin; y < rows.end; ++y)
            equal = equal && std::memcmp(out + static_cast<std::size_t>(y) * nx, &inverse[static_cast<std::size_t>(y) * nx],
                                         sizeof(double) * static_cast<std::size_t>(nx)) == 0;
          back_equal[static_cast<std::size_t>(r)] = equal;
          for (int y = rows.begin; y < rows.end; ++y) rows_covered[static_cast<std::size_t>(y)] += 1;
          for (int x = columns.begin; x < columns.end; ++x) columns_covered[static_cast<std::size_t>(x)] += 1;
          fftw_free(in);
          fftw_free(out);
          fftw_free(s);
        });
      for (std::thread& t : threads) t.join();
      CHECK_FALSE(exchange.mismatched);
      for (int r = 0; r < ranks; ++r) {
        INFO("rank " << r);
        CHECK(spec_equal[static_cast<std::size_t>(r)] == 1);
        CHECK(back_equal[static_cast<std::size_t>(r)] == 1);
      }
      CHECK(std::all_of(rows_covered.begin(), rows_covered.end(), [](int k) { return k == 1; }));
      CHECK(std::all_of(columns_covered.begin(), columns_covered.end(), [](int k) { return k == 1; }));
    }
    fftw_free(real);
    fftw_free(spec);
  }
}
