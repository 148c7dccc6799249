// The spectral sea's 2D transform in slabs over the ranks mpirun started
// (fluid/slab_fft.hpp, the transposes by parallel::Communicator::alltoall):
// each rank's slab of the spectrum, and of the inverse, equals the whole
// transform's (computed on every rank alone) to the bit. Grids with
// remainder blocks and one with fewer row blocks than ranks. Every rank
// reports; the ranks agree on the verdict (exit 0 when every rank passed).
// Run by ctest as mpi.slab_fft_ranks_N under `mpirun --oversubscribe -np N`
// (N = 1, 2, 3), and serially without MPI.
#include <cstdio>

#include "parallel/comm.hpp"
#include "tests/fluid/slab_check.hpp"

using namespace floesim;

namespace {

// Whether this rank's slabs equal the whole transform's bits on an nx x ny grid.
bool slabs_equal(const parallel::Communicator& comm, int nx, int ny) {
  const fluid::testing::WholeTransform whole(nx, ny);
  fluid::SlabFft2d slab(whole.fft, nx, ny, comm.rank(), comm.size(),
                        [&comm](std::span<const std::byte> send, const std::vector<std::size_t>& send_counts,
                                std::span<std::byte> receive, const std::vector<std::size_t>& receive_counts) {
                          comm.alltoall(send, send_counts, receive, receive_counts);
                        });
  const fluid::testing::SlabCheck check = fluid::testing::check_slab(whole, slab);
  const bool equal = check.spectrum_equal && check.inverse_equal;
  std::printf("rank %d of %d, %d x %d: rows [%d, %d), columns [%d, %d): %s\n", comm.rank(), comm.size(), nx, ny,
              check.rows.begin, check.rows.end, check.columns.begin, check.columns.end,
              equal ? "equal to the whole transform, bit for bit" : "DIFFERENT");
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
