// The spectral sea's 2D transform in slabs over the ranks mpirun started
// (fluid/slab_fft.hpp, the transposes by parallel::Communicator::alltoall):
// each rank's slab of the spectrum, and of the inverse, equals the whole
// transform's (computed on every rank alone) to the bit. Grids with
// remainder blocks and one with fewer row blocks than ranks. Every rank
// reports; the ranks agree on the verdict (exit 0 when every rank passed).
// Run by ctest as mpi.slab_fft_ranks_N under `mpirun --oversubscribe -np N`
// (N = 1, 2, 3), and serially without MPI.
#include <fftw3.h>

#include <cstdio>
#include <cstring>
#include <random>
#include <vector>

#include "fluid/slab_fft.hpp"
#include "parallel/comm.hpp"

using namespace floesim;

namespace {

// Whether this rank's slabs equal the whole transform's bits on an nx x ny grid.
bool slabs_equal(const parallel::Communicator& comm, int nx, int ny) {
  const int hx = nx / 2 + 1;
  const std::size_t n = static_cast<std::size_t>(nx) * ny, nc = static_cast<std::size_t>(hx) * ny;
  double* real = fftw_alloc_real(n);
  double* out = fftw_alloc_real(n);
  fftw_complex* spec = fftw_alloc_complex(nc);
  fftw_complex* mine = fftw_alloc_complex(nc);
  fluid::RealFft2d fft(nx, ny, FFTW_ESTIMATE, real, spec);
  std::mt19937_64 rng(static_cast<unsigned long>(nx) * 1000 + static_cast<unsigned long>(ny));  // the same field on every rank
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<double> field(n);
  for (double& x : field) x = u(rng);
  std::copy(field.begin(), field.end(), real);
  fft.forward(real, spec, 1);
  const std::vector<double> whole(reinterpret_cast<double*>(spec), reinterpret_cast<double*>(spec) + 2 * nc);
  fft.backward(spec, real, 1);
  const std::vector<double> inverse(real, real + n);

  fluid::SlabFft2d slab(fft, nx, ny, comm.rank(), comm.size(),
                        [&comm](std::span<const std::byte> send, const std::vector<std::size_t>& send_counts,
                                std::span<std::byte> receive, const std::vector<std::size_t>& receive_counts) {
                          comm.alltoall(send, send_counts, receive, receive_counts);
                        });
  const fluid::SlabFft2d::Span rows = slab.rows(), columns = slab.columns();
  // The input only in this rank's rows, the spectrum only in its columns.
  std::fill(real, real + n, 0.0);
  for (int y = rows.begin; y < rows.end; ++y)
    std::memcpy(real + static_cast<std::size_t>(y) * nx, &field[static_cast<std::size_t>(y) * nx], sizeof(double) * static_cast<std::size_t>(nx));
  slab.forward(real, mine, 1);
  bool equal = true;
  for (int y = 0; y < ny; ++y)
    for (int x = columns.begin; x < columns.end; ++x) {
      const std::size_t c = static_cast<std::size_t>(y) * hx + x;
      equal = equal && std::memcmp(mine[c], &whole[2 * c], sizeof(fftw_complex)) == 0;
    }
  std::fill(reinterpret_cast<double*>(mine), reinterpret_cast<double*>(mine) + 2 * nc, 0.0);
  for (int y = 0; y < ny; ++y)
    for (int x = columns.begin; x < columns.end; ++x) {
      const std::size_t c = static_cast<std::size_t>(y) * hx + x;
      mine[c][0] = whole[2 * c];
      mine[c][1] = whole[2 * c + 1];
    }
  slab.backward(mine, out, 1);
  for (int y = rows.begin; y < rows.end; ++y)
    equal = equal && std::memcmp(out + static_cast<std::size_t>(y) * nx, &inverse[static_cast<std::size_t>(y) * nx],
                                 sizeof(double) * static_cast<std::size_t>(nx)) == 0;
  std::printf("rank %d of %d, %d x %d: rows [%d, %d), columns [%d, %d): %s\n", comm.rank(), comm.size(), nx, ny, rows.begin,
              rows.end, columns.begin, columns.end, equal ? "equal to the whole transform, bit for bit" : "DIFFERENT");
  for (double* p : {real, out}) fftw_free(p);
  for (fftw_complex* p : {spec, mine}) fftw_free(p);
  return equal;
}

}  // namespace

int main() {
  parallel::Session session;
  const parallel::Communicator& comm = session.world();
  long long failed = 0;
  for (auto [nx, ny] : {std::pair{128, 100}, std::pair{30, 21}, std::pair{64, 8}})
    if (!slabs_equal(comm, nx, ny)) ++failed;
  failed = comm.sum(failed);
  if (comm.writer()) std::printf("%s on %d ranks\n", failed == 0 ? "passed" : "FAILED", comm.size());
  return failed == 0 ? 0 : 1;
}
