// The spectral sea's 2D transform in slabs (fluid/slab_fft.hpp) against the
// whole transform on one rank: time of a forward and a backward transform
// pair, of the rank's passes alone and of the two transposes (the time
// inside MPI_Alltoallv, waits for the other ranks included), and the bytes
// a rank receives. One CSV row per rank and grid, on stdout, rank by rank.
//
// usage: mpirun -np N floesim_bench_slab_fft [--cells N]... [--pairs K]
//   (default cells 512 and 2048, pairs 20; the least of the pairs' times)
#include <fftw3.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include "fluid/slab_fft.hpp"
#include "parallel/comm.hpp"

using namespace floesim;

namespace {

double now() { return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count(); }

}  // namespace

int main(int argc, char** argv) {
  parallel::Session session;
  const parallel::Communicator& comm = session.world();
  std::vector<int> sizes;
  int pairs = 20;
  for (int a = 1; a < argc; ++a) {
    const std::string arg = argv[a];
    if (arg == "--cells" && a + 1 < argc) sizes.push_back(std::atoi(argv[++a]));
    else if (arg == "--pairs" && a + 1 < argc) pairs = std::max(1, std::atoi(argv[++a]));
    else {
      if (comm.writer()) std::fprintf(stderr, "usage: floesim_bench_slab_fft [--cells N]... [--pairs K]\n");
      return 2;
    }
  }
  if (sizes.empty()) sizes = {512, 2048};
  if (comm.writer())
    std::printf("cells,ranks,rank,whole_pair_s,slab_pair_s,transposes_s,received_bytes_per_pair,speedup_of_passes\n");
  std::fflush(stdout);
  for (int cells : sizes) {
    const int nx = cells, ny = cells, hx = nx / 2 + 1;
    const std::size_t n = static_cast<std::size_t>(nx) * ny, nc = static_cast<std::size_t>(hx) * ny;
    double* real = fftw_alloc_real(n);
    double* field = fftw_alloc_real(n);
    fftw_complex* spec = fftw_alloc_complex(nc);
    fluid::RealFft2d fft(nx, ny, FFTW_ESTIMATE, real, spec);
    std::mt19937_64 rng(1);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    for (std::size_t k = 0; k < n; ++k) field[k] = u(rng);
    // The whole pair on this rank alone (what every rank of a replicated sea does).
    double whole = 1e300;
    for (int p = 0; p < pairs; ++p) {
      const double t0 = now();
      fft.forward(field, spec, 1);
      fft.backward(spec, real, 1);
      whole = std::min(whole, now() - t0);
    }
    fluid::SlabFft2d slab(fft, nx, ny, comm.rank(), comm.size(),
                          [&comm](std::span<const std::byte> send, const std::vector<std::size_t>& send_counts,
                                  std::span<std::byte> receive, const std::vector<std::size_t>& receive_counts) {
                            comm.alltoall(send, send_counts, receive, receive_counts);
                          });
    double best = 1e300, transposes = 0.0;
    long long received = 0;
    for (int p = 0; p < pairs; ++p) {
      const parallel::Communicator::Traffic before = comm.traffic();
      const double t0 = now();
      // Its rows of the field, its columns of the spectrum (a column slab fits in spec).
      const std::ptrdiff_t first = static_cast<std::ptrdiff_t>(slab.rows().begin) * nx;
      slab.forward(field + first, spec, 1);
      slab.backward(spec, real + first, 1);
      const double t = now() - t0;
      const parallel::Communicator::Traffic after = comm.traffic();
      if (t < best) {
        best = t;
        transposes = after.seconds - before.seconds;
        received = after.bytes - before.bytes;
      }
    }
    // Rows in rank order: each rank its line, then the next.
    for (int r = 0; r < comm.size(); ++r) {
      if (r == comm.rank())
        std::printf("%d,%d,%d,%.6f,%.6f,%.6f,%lld,%.3f\n", cells, comm.size(), r, whole, best, transposes, received,
                    whole / std::max(best - transposes, 1e-12));
      std::fflush(stdout);
      comm.sum(0);  // a barrier, so the lines come out in rank order
    }
    fftw_free(real);
    fftw_free(field);
    fftw_free(spec);
  }
  return 0;
}
