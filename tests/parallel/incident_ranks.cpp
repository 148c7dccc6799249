// The incident waves' snapshots on a sea in slabs (coupling/incident.hpp,
// docs/parallel.md "A row window for the fields"), over the ranks mpirun
// started, against the same incident sea serially on every rank.
//
// Memory: advanced with a halo of h rows, each snapshot holds this rank's
// slab and h rows either side and nothing more (a whole snapshot on a rank
// whose slab and halo lack rows fails), the constructor's whole ones cut to
// that window too. Answers: each held row equals the serial snapshot's
// (memcmp), read by global cell across the seam; a checkpoint's snapshots
// (saved_state) are the serial ones on rank 0 and empty elsewhere; a
// restore from the serial state and one more interval give the serial
// snapshots again. Run by ctest as mpi.incident_ranks_N (N = 1, 2, 3).
#include <algorithm>
#include <cstdio>
#include <cstring>
#include <vector>

#include "coupling/incident.hpp"
#include "fluid/sea.hpp"
#include "parallel/comm.hpp"
#include "parallel/sea_ranks.hpp"
#include "tests/parallel/sea_case.hpp"

using namespace floesim;

namespace {

using parallel::sea_ranks;

SeaParams params(int nx, int ny) { return test::slab_sea_params(nx, ny); }

bool same(std::span<const double> a, std::span<const double> b) {
  return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size_bytes()) == 0);
}

int check_grid(const parallel::Communicator& comm, int nx, int ny, int halo) {
  int failed = 0;
  auto check = [&](bool ok, const char* what) {
    if (ok) return;
    ++failed;
    std::printf("rank %d of %d, %d x %d, halo %d: %s\n", comm.rank(), comm.size(), nx, ny, halo, what);
  };
  const SeaParams p = params(nx, ny);
  fluid::SeaOptions options;
  options.ranks = sea_ranks(comm);
  const double tau = IncidentSea::interval_for(p);
  IncidentSea whole(fluid::make_sea(p, 5), tau);
  auto slab_sea = fluid::make_sea(p, 5, options);
  const std::vector<int> rows = slab_sea->slab_rows();
  IncidentSea slab(std::move(slab_sea), tau);
  const int begin = comm.size() > 1 ? rows[static_cast<std::size_t>(comm.rank())] : 0;
  const int end = comm.size() > 1 ? rows[static_cast<std::size_t>(comm.rank()) + 1] : ny;
  const int held = comm.size() == 1 ? ny : begin == end ? 0 : std::min(end - begin + 2 * halo, ny);

  auto compare = [&](const char* what) {
    const std::vector<std::pair<fluid::RowWindow, fluid::RowWindow>> pairs{
        {whole.u0(), slab.u0()}, {whole.v0(), slab.v0()}, {whole.u1(), slab.u1()}, {whole.v1(), slab.v1()}};
    for (const auto& [a, b] : pairs) {
      check(b.rows() == held && b.values().size() == static_cast<std::size_t>(held) * static_cast<std::size_t>(nx),
            "a snapshot holds other rows than its slab's and the halo's");
      if (begin == end) continue;
      for (int y = begin - halo; y < end + halo; ++y) {
        const int gy = ((y % ny) + ny) % ny;
        const std::size_t row = static_cast<std::size_t>(gy) * static_cast<std::size_t>(nx);
        bool equal = b.holds_row(y);
        for (int x = 0; equal && x < nx; ++x) {
          const double u = a[row + static_cast<std::size_t>(x)], v = b[row + static_cast<std::size_t>(x)];
          equal = std::memcmp(&u, &v, sizeof(double)) == 0;
        }
        check(equal, what);
      }
    }
  };
  // Steps that do not divide tau: several intervals, each a new snapshot.
  double t = 0.0;
  for (int step = 0; step < 12; ++step) {
    t += 0.37 * tau;
    whole.advance_to(t, halo);
    slab.advance_to(t, halo);
    compare("a snapshot differs from the serial one");
  }
  // A checkpoint's snapshots: the serial ones on rank 0 alone.
  const IncidentState sw = whole.saved_state(), ss = slab.saved_state();
  if (comm.writer()) {
    check(same(sw.u0, ss.u0) && same(sw.v0, ss.v0) && same(sw.u1, ss.u1) && same(sw.v1, ss.v1) &&
              same(sw.sea.q, ss.sea.q) && same(sw.sea.v, ss.sea.v),
          "a checkpoint's snapshots differ from the serial ones");
  } else {
    check(ss.u0.empty() && ss.v0.empty() && ss.u1.empty() && ss.v1.empty(),
          "a rank other than 0 received a checkpoint's whole snapshots");
  }
  // A restart: every rank restores the serial (whole) state, cut at the
  // next advance.
  slab.restore(sw);
  t += 1.3 * tau;
  whole.advance_to(t, halo);
  slab.advance_to(t, halo);
  compare("a snapshot after a restore differs from the serial one");
  return failed;
}

}  // namespace

int main() {
  parallel::Session session;
  const parallel::Communicator& comm = session.world();
  long long failed = 0;
  // 32 x 48 with halos of 2 (windows crossing the seam) and 30 (whole on 2
  // ranks); 40 x 8: one row block, so other ranks' slabs are empty.
  for (auto [nx, ny, halo] : {std::tuple{32, 48, 2}, std::tuple{32, 48, 30}, std::tuple{40, 8, 1}})
    failed += check_grid(comm, nx, ny, halo);
  failed = comm.sum(failed);
  if (comm.writer()) std::printf("%s on %d ranks\n", failed == 0 ? "passed" : "FAILED", comm.size());
  return failed == 0 ? 0 : 1;
}
