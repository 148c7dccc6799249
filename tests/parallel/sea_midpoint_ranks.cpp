// The implicit step's midpoint operations on a spectral sea in slabs over
// the ranks mpirun started (fluid/sea.hpp, Sea::midpoint_*; docs/parallel.md,
// "The sea's midpoint operations in slabs (slabmid30)").
//
// Answers, against the whole serial sea built from the same options on
// every rank, both given the same random modes (every mode of the whole
// bank) and the same random pressures (every cell): each rank's rows of
// the free elevation, of the response to a pressure and, after a midpoint
// step, of the next free elevation equal the serial sea's rows to the bit
// (memcmp), and so do the state after the step (gathered to rank 0), its
// time and its whole elevation field. The slab sea is given the pressures
// with NaN in every row but its slab's (a row read beyond it would spread
// NaN into the modes), and the rows beyond its slab of each result must
// keep what they held (nothing is written there). A kick left deferred
// before a free elevation checks that the bank settles it first. Grids
// with remainder blocks both ways, ranks with empty row slabs, and on 3
// ranks a rank with no columns (as mpi.sea_slab_ranks_N).
//
// Run by ctest as mpi.sea_midpoint_ranks_N under `mpirun --oversubscribe
// -np N` (N = 1, 2, 3; on one rank the sea is not in slabs and the test is
// its serial baseline). With `--bench NX [REPEATS]` it measures instead:
// the wall time and the all-to-alls (calls, bytes this rank receives) of
// one midpoint_response on an NX x NX sea in slabs (docs/parallel.md).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "fluid/spectral.hpp"
#include "parallel/comm.hpp"
#include "parallel/sea_ranks.hpp"
#include "tests/parallel/ranks_main.hpp"
#include "tests/parallel/sea_case.hpp"

using namespace floesim;

namespace {

// Rows [begin, end) of a whole-grid array a equal b's, byte for byte.
bool same_rows(std::span<const double> a, std::span<const double> b, int nx, int begin, int end) {
  const std::size_t from = static_cast<std::size_t>(begin) * static_cast<std::size_t>(nx);
  const std::size_t count = static_cast<std::size_t>(end - begin) * static_cast<std::size_t>(nx);
  return a.size() == b.size() && (count == 0 || std::memcmp(a.data() + from, b.data() + from, count * sizeof(double)) == 0);
}

bool same(std::span<const double> a, std::span<const double> b) {
  return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size_bytes()) == 0);
}

void check_grid(const parallel::Communicator& comm, int nx, int ny, test::Failures& failures) {
  const std::string where = std::to_string(nx) + " x " + std::to_string(ny) + ": ";
  auto check = [&](bool ok, const std::string& what) {
    if (!ok) failures.push_back(where + what);
  };
  const SeaParams params = test::slab_sea_params(nx, ny);
  fluid::SeaOptions options;
  options.ranks = parallel::sea_ranks(comm);
  auto whole_sea = fluid::make_sea(params, 5);
  auto slab_sea = fluid::make_sea(params, 5, options);
  fluid::Sea& whole = *whole_sea;
  fluid::Sea& slab = *slab_sea;
  check(slab.in_slabs() == (comm.size() > 1), "the sea is not in slabs on several ranks");
  const std::vector<int> cuts = slab.slab_rows();
  const int begin = cuts.empty() ? 0 : cuts[static_cast<std::size_t>(comm.rank())];
  const int end = cuts.empty() ? ny : cuts[static_cast<std::size_t>(comm.rank()) + 1];
  const std::size_t n = static_cast<std::size_t>(nx) * static_cast<std::size_t>(ny);
  const std::size_t first = static_cast<std::size_t>(begin) * static_cast<std::size_t>(nx);
  const std::size_t stop = static_cast<std::size_t>(end) * static_cast<std::size_t>(nx);

  // Random modes, the same on every rank (one generator, one seed): every
  // mode of the whole bank but the frozen mean.
  std::mt19937_64 random(static_cast<unsigned long>(nx) * 1000u + static_cast<unsigned long>(ny));
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::vector<double> q(whole.modal_size()), v(whole.modal_size());
  for (double& x : q) x = 1e-2 * unit(random);
  for (double& x : v) x = 1e-2 * unit(random);
  q[0] = q[1] = v[0] = v[1] = 0.0;
  whole.set_modal_state(q, v);
  slab.set_modal_state(q, v);

  // A random pressure on every cell (Pa); the slab sea's copy NaN beyond its rows.
  std::vector<double> pressure(n), slab_pressure(n);
  auto new_pressure = [&] {
    for (double& x : pressure) x = 2e3 * unit(random);
    std::fill(slab_pressure.begin(), slab_pressure.end(), std::numeric_limits<double>::quiet_NaN());
    std::copy(pressure.begin() + static_cast<std::ptrdiff_t>(first), pressure.begin() + static_cast<std::ptrdiff_t>(stop),
              slab_pressure.begin() + static_cast<std::ptrdiff_t>(first));
  };
  // The results: the slab sea's rows beyond its slab hold a mark that must stay.
  const double mark = -12345.0;
  std::vector<double> eta_whole(n), eta_slab(n);
  auto compare = [&](const std::string& what) {
    check(same_rows(eta_whole, eta_slab, nx, begin, end), what + ": this rank's rows differ from the serial sea's");
    bool kept = true;
    for (std::size_t c = 0; c < n; ++c)
      if ((c < first || c >= stop) && eta_slab[c] != mark) kept = false;
    check(kept, what + ": a row beyond this rank's slab was written");
    std::fill(eta_slab.begin(), eta_slab.end(), mark);
  };
  std::fill(eta_slab.begin(), eta_slab.end(), mark);

  const double h = 0.05;
  for (int step = 0; step < 3; ++step) {
    // A kick left deferred: the free elevation settles it.
    new_pressure();
    whole.kick(pressure, 0.02);
    slab.kick(slab_pressure, 0.02);
    whole.midpoint_free_elevation(h, eta_whole);
    slab.midpoint_free_elevation(h, eta_slab);
    compare("the free elevation (step " + std::to_string(step) + ")");
    for (int k = 0; k < 2; ++k) {
      new_pressure();
      whole.midpoint_response(pressure, h, eta_whole);
      slab.midpoint_response(slab_pressure, h, eta_slab);
      compare("the response to a pressure (step " + std::to_string(step) + ")");
    }
    whole.midpoint_step(pressure, h);
    slab.midpoint_step(slab_pressure, h);
    check(whole.time() == slab.time(), "the time after a midpoint step differs");
    whole.midpoint_free_elevation(h, eta_whole);
    slab.midpoint_free_elevation(h, eta_slab);
    compare("the free elevation after a midpoint step (step " + std::to_string(step) + ")");
  }
  // The state after the steps: the whole bank's on rank 0, and the
  // elevation field (every rank's rows gathered) the serial one.
  std::vector<double> qw, vw, qs, vs;
  whole.gather_modal_state(qw, vw);
  slab.gather_modal_state(qs, vs);
  if (comm.writer()) check(same(qw, qs) && same(vw, vs), "the state after the midpoint steps differs from the serial bank");
  check(same(whole.elevation(), slab.elevation()), "the elevation after the midpoint steps differs from the serial sea's");
  std::printf("rank %d of %d, %d x %d: rows [%d, %d), %zu of %zu modes held\n", comm.rank(), comm.size(), nx, ny, begin,
              end, slab.modes().modes(), whole.modes().modes());
}

// One midpoint_response on an nx x nx sea in slabs: the median wall time of
// `repeats` calls (after 3 not counted) and each call's all-to-alls.
int bench(const parallel::Communicator& comm, int nx, int repeats) {
  struct Count {
    long long calls = 0, bytes = 0;
    double seconds = 0.0;  // inside the all-to-alls (waiting for the other ranks included)
  } count;
  fluid::SeaOptions options;
  options.ranks = parallel::sea_ranks(comm);
  const auto alltoall = options.ranks.alltoall;
  options.ranks.alltoall = [&count, alltoall](std::span<const std::byte> send, const std::vector<std::size_t>& send_counts,
                                              std::span<std::byte> receive, const std::vector<std::size_t>& receive_counts) {
    ++count.calls;
    for (std::size_t b : receive_counts) count.bytes += static_cast<long long>(b);
    const auto t0 = std::chrono::steady_clock::now();
    alltoall(send, send_counts, receive, receive_counts);
    count.seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  };
  auto sea = fluid::make_sea(test::slab_sea_params(nx, nx), 5, options);
  const std::size_t n = static_cast<std::size_t>(nx) * static_cast<std::size_t>(nx);
  std::vector<double> p(n), eta(n);
  std::mt19937_64 random(1);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  for (double& x : p) x = unit(random);
  std::vector<double> wall, exchange, outside;
  for (int k = 0; k < repeats + 3; ++k) {
    comm.sum(0LL);  // the ranks start together
    count = {};
    const auto t0 = std::chrono::steady_clock::now();
    sea->midpoint_response(p, 0.05, eta);
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (k >= 3) {
      wall.push_back(comm.max(s));
      exchange.push_back(count.seconds);
      outside.push_back(s - count.seconds);  // this rank's own work
    }
  }
  std::sort(wall.begin(), wall.end());
  std::sort(exchange.begin(), exchange.end());
  std::sort(outside.begin(), outside.end());
  std::printf("rank %d of %d, %d x %d: midpoint_response %.2f ms (median of %d, slowest rank), %lld all-to-alls "
              "(%.2f ms in them, %.2f ms outside, medians), %lld B received\n",
              comm.rank(), comm.size(), nx, nx, 1e3 * wall[wall.size() / 2], repeats, count.calls,
              1e3 * exchange[exchange.size() / 2], 1e3 * outside[outside.size() / 2], count.bytes);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  parallel::Session session;
  const parallel::Communicator& comm = session.world();
  if (argc >= 3 && std::string(argv[1]) == "--bench")
    return bench(comm, std::atoi(argv[2]), argc >= 4 ? std::atoi(argv[3]) : 20);
  return test::run_checks(comm, "each rank's rows of the midpoint operations are the serial sea's, bit for bit",
                          [](const parallel::Communicator& c, test::Failures& f) {
                            // 64 x 48: 33 columns (the last block short), 6 row blocks;
                            // 30 x 21: remainder blocks both ways; 40 x 8: one row
                            // block (empty row slabs on 2 and 3 ranks); 12 x 8: on 3
                            // ranks rank 2 holds no mode and no row.
                            for (auto [nx, ny] : {std::pair{64, 48}, std::pair{30, 21}, std::pair{40, 8}, std::pair{12, 8}})
                              check_grid(c, nx, ny, f);
                          });
}
