// The load balance by measured cost (parallel::FloeOwners, stage six) over
// the ranks mpirun started. 3000 floes spread along y in a periodic box, a
// floe above y = 700 m costing 20 times one below (very unequal costs, the
// equal counts of the start are far from balanced), drifting 0.7 m a step so
// that they migrate across the cuts. Each rank charges the cost of the
// floes it owns (a known cost, not a clock, so that the test is
// deterministic), and FloeOwners::update moves the cuts every 10 steps from
// the gathered charges. The ranks' charges must become equal (below); the
// ranks must agree on the cuts and owners to the bit, and own every floe
// once. Run by ctest as
// mpi.place_ranks_N under `mpirun --oversubscribe -np N` (N = 1, 2, 3), and
// serially without MPI.
//
// Then the slabs moved by the coupling's cost (issue 21, load balance;
// coupling_moves below): 32 static floes in rows 0 to 31 of 64 (blocks of 8),
// each rank charging 1 ms a step for each floe it owns as coupling seconds
// (FloeOwners::charge_coupling), on slabs starting at {0, 32, 64} (2 ranks)
// or {0, 24, 48, 64} (3 ranks). The floe cost is then the same for every
// floe, the target cuts split the floes' rows evenly ({0, 16, 64};
// {0, 8, 24, 64}), and each move goes half way in whole blocks (half a
// block rounds away from the cut), so by hand: 2 ranks {0, 24, 64} at the
// first move, {0, 16, 64} at the second and after; 3 ranks {0, 16, 32, 64},
// then {0, 8, 24, 64}. The same seconds charged as row seconds
// (charge_rows) are spread evenly over the rows and leave the first cut
// where it is: the reason the coupling's seconds are charged per floe.
//
// Then the strips moved by the fracture analyses' cost (fracture_moves
// below): 32 static floes at y = 0.5, 1.5, ..., 31.5 m in free strips (no
// sea), those below y = 8 m loaded: each rank charges 1 ms a step for each
// loaded floe it owns as fracture seconds (FloeOwners::charge_fracture), as
// Simulation's percussion phase charges the analyses of its loaded floes.
// The strips start with equal counts (cut 16 on 2 ranks, 11 and 21 on 3).
// By hand on 2 ranks: rank 0 charges 80 ms over its 16 floes (5 ms each),
// rank 1 nothing (its floes at the floor, 1 % of the mean: 0.025 ms); the
// costs' half (40.2 ms) is nearest after the 8 loaded floes, so the target
// cut is 8 (midway between 7.5 and 8.5) and the cut moves half way, to 12;
// then (80 ms over 12 floes) target 6, cut 9; then (80 ms over 9) target 5,
// cut 7. On 3 ranks: targets 4 and 7, cuts 7.5 and 14; then (rank 0 70 ms
// over 7 floes, rank 1 10 ms over 7, the floe at y = 7.5 being rank 1's)
// targets 3 and 5, cuts 5.25 and 9.5; then targets 3 and 5, cuts 4.125 and
// 7.25.
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <random>
#include <string>
#include <vector>

#include "parallel/comm.hpp"
#include "parallel/place.hpp"
#include "tests/parallel/ranks_main.hpp"

using namespace floesim;

namespace {

// The slabs moved by coupling seconds charged per floe (the file's comment).
void coupling_moves(const parallel::Communicator& comm, std::vector<std::string>& failures) {
  const int ranks = comm.size();
  if (ranks > 3) return;
  Floes floes;
  for (int k = 0; k < 32; ++k) {
    FloeState s{};
    s.y = 0.5 + k;  // row k (dy = 1 m)
    floes.state.push_back(s);
    floes.thickness.push_back(1.0);
  }
  const contact::Domain box{true, 0.0, 64.0, 0.0, 64.0};
  const std::vector<std::vector<int>> start{{0, 64}, {0, 32, 64}, {0, 24, 48, 64}};
  const std::vector<std::vector<std::vector<int>>> expected{
      {{0, 64}, {0, 64}, {0, 64}}, {{0, 24, 64}, {0, 16, 64}, {0, 16, 64}}, {{0, 16, 32, 64}, {0, 8, 24, 64}, {0, 8, 24, 64}}};
  const auto r = static_cast<std::size_t>(ranks - 1);
  parallel::FloeOwners by_floe(comm.rank(), ranks, box), by_row(comm.rank(), ranks, box);
  by_floe.set_slabs({start[r], 1.0, 8});
  by_row.set_slabs({start[r], 1.0, 8});
  double charged = 0.0;  // this rank's coupling seconds in the closed windows
  double window = 0.0;
  for (std::size_t step = 0; step <= 30; ++step) {
    by_floe.update(comm, floes, step);
    by_row.update(comm, floes, step);
    if (step % 10 == 0 && step > 0) {
      charged += window;
      window = 0.0;
      if (by_floe.slabs().first_row != expected[r][step / 10 - 1])
        failures.push_back("coupling seconds: the slabs after move " + std::to_string(step / 10) + " are not as computed by hand");
      if (by_row.slabs().first_row[1] != start[r][1]) failures.push_back("row seconds moved the first cut");
    }
    const double seconds = 1e-3 * static_cast<double>(by_floe.mine().size());
    by_floe.charge_coupling(seconds);
    by_row.charge_rows(1e-3 * static_cast<double>(by_row.mine().size()));
    window += seconds;
  }
  const std::vector<double> all = comm.allgather<double>(std::span<const double>(&charged, 1));
  if (by_floe.coupling_seconds() != all) failures.push_back("coupling_seconds() is not each rank's charged seconds");
  if (comm.writer()) {
    std::printf("coupling seconds: %d moves, slabs", by_floe.moves());
    for (const int row : by_floe.slabs().first_row) std::printf(" %d", row);
    std::printf("; the same as row seconds: slabs");
    for (const int row : by_row.slabs().first_row) std::printf(" %d", row);
    std::printf("\n");
  }
}

// The strips moved by fracture seconds charged per loaded floe (the file's comment).
void fracture_moves(const parallel::Communicator& comm, std::vector<std::string>& failures) {
  const int ranks = comm.size();
  if (ranks > 3) return;
  Floes floes;
  for (int k = 0; k < 32; ++k) {
    FloeState s{};
    s.y = 0.5 + k;
    floes.state.push_back(s);
    floes.thickness.push_back(1.0);
  }
  const contact::Domain box{true, 0.0, 64.0, 0.0, 64.0};
  const std::vector<std::vector<std::vector<double>>> expected{
      {{}, {}, {}}, {{12.0}, {9.0}, {7.0}}, {{7.5, 14.0}, {5.25, 9.5}, {4.125, 7.25}}};
  const auto r = static_cast<std::size_t>(ranks - 1);
  parallel::FloeOwners owners(comm.rank(), ranks, box);
  double charged = 0.0;  // this rank's fracture seconds in the closed windows
  double window = 0.0;
  for (std::size_t step = 0; step <= 30; ++step) {
    owners.update(comm, floes, step);
    if (step % 10 == 0 && step > 0) {
      charged += window;
      window = 0.0;
      if (owners.cuts() != expected[r][step / 10 - 1])
        failures.push_back("fracture seconds: the cuts after move " + std::to_string(step / 10) +
                           " are not as computed by hand");
    }
    double seconds = 0.0;
    for (const std::uint32_t i : owners.mine())
      if (floes.state[i].y < 8.0) seconds += 1e-3;
    owners.charge_fracture(seconds);
    window += seconds;
  }
  const std::vector<double> all = comm.allgather<double>(std::span<const double>(&charged, 1));
  if (owners.fracture_seconds() != all) failures.push_back("fracture_seconds() is not each rank's charged seconds");
  if (ranks > 1 && !(all.back() == 0.0 && all.front() > 0.0))
    failures.push_back("fracture seconds: expected rank 0 to charge and the last rank not");
  if (comm.writer()) {
    std::printf("fracture seconds: %d moves, cuts", owners.moves());
    for (const double c : owners.cuts()) std::printf(" %g", c);
    std::printf("\n");
  }
}

}  // namespace

int main() {
  parallel::Session session;
  const parallel::Communicator& comm = session.world();
  const int ranks = comm.size();
  std::vector<std::string> failures;
  const std::size_t n = 3000;
  Floes floes;
  std::mt19937_64 rng(5);  // the same floes on every rank
  std::uniform_real_distribution<double> u(0.0, 1000.0);
  for (std::size_t i = 0; i < n; ++i) {
    FloeState s{};
    s.y = u(rng);
    floes.state.push_back(s);
    floes.thickness.push_back(1.0);
  }
  const contact::Domain box{true, 0.0, 1000.0, 0.0, 1000.0};
  parallel::FloeOwners owners(comm.rank(), ranks, box);
  auto cost = [&](std::size_t i) { return owners.place(floes.state[i]) >= 700.0 ? 20e-6 : 1e-6; };
  std::vector<std::vector<double>> windows;  // each window's charges, by rank
  for (std::size_t step = 0; step < 300; ++step) {
    owners.update(comm, floes, step);
    if (step % 10 == 0 && step > 0) windows.push_back(owners.window_seconds());  // the window just closed
    if (step == 150) owners.update(comm, floes, step);  // a step redone: no second move
    double charged = 0.0;
    for (const std::uint32_t i : owners.mine()) charged += cost(i);
    owners.charge(charged);
    for (FloeState& s : floes.state) s.y += 0.7;  // not wrapped: place() wraps
  }
  // The strips start with equal counts: the first window is far from
  // balanced (its costliest rank charges 3 times the mean or more). From
  // step 100 on, the ranks' mean charges are equal within 2 %, and every
  // window's within 10 % (a strip's cost varies as the random floes drift
  // through it: some 25 costly floes make a strip's cost).
  auto spread = [](const std::vector<double>& x) {
    const double mean = std::accumulate(x.begin(), x.end(), 0.0) / static_cast<double>(x.size());
    return *std::max_element(x.begin(), x.end()) / mean - 1.0;
  };
  std::vector<double> late(static_cast<std::size_t>(ranks), 0.0);
  double worst = 0.0;
  for (std::size_t k = 9; k < windows.size(); ++k) {
    for (int r = 0; r < ranks; ++r) late[static_cast<std::size_t>(r)] += windows[k][static_cast<std::size_t>(r)];
    worst = std::max(worst, spread(windows[k]));
  }
  if (ranks > 1 && !(spread(windows.front()) > 0.5)) failures.push_back("the first window was balanced: no test");
  if (!(spread(late) <= 0.02)) failures.push_back("the mean charges from step 100 differ by more than 2 %");
  if (!(worst <= 0.10)) failures.push_back("a window's charges from step 100 differ by more than 10 %");
  if (ranks > 1 && owners.moves() != 29) failures.push_back("expected 29 moves in 300 steps");
  // Every rank the same cuts and owners, to the bit; every floe owned once.
  const std::vector<double> cuts = comm.allgather<double>(owners.cuts());
  // Compared as bytes (to the bit), with std::equal on the bit patterns: on
  // one rank there is no cut, and memcmp may not be given the empty lists'
  // null pointers.
  const auto bits = [](double x) { return std::bit_cast<std::uint64_t>(x); };
  for (int r = 0; r < ranks; ++r)
    if (!std::equal(owners.cuts().begin(), owners.cuts().end(), cuts.begin() + r * (ranks - 1),
                    [&](double a, double b) { return bits(a) == bits(b); }))
      failures.push_back("the ranks' cuts differ");
  const std::vector<int> owner = comm.allgather<int>(owners.owner());
  for (int r = 0; r < ranks; ++r)
    if (!std::equal(owners.owner().begin(), owners.owner().end(), owner.begin() + r * static_cast<long>(n)))
      failures.push_back("the ranks' owners differ");
  std::vector<std::uint32_t> all = comm.allgather<std::uint32_t>(owners.mine());
  std::sort(all.begin(), all.end());
  for (std::size_t i = 0; i < n; ++i)
    if (all.size() != n || all[i] != i) {
      failures.push_back("the floes are not owned once each");
      break;
    }
  if (comm.writer()) {
    std::printf("%d ranks, %d moves; the first window's charges exceed their mean by %.3f, from step 100 on "
                "the worst window's by %.3f, the mean charges by %.4f; cuts:",
                ranks, owners.moves(), spread(windows.front()), worst, spread(late));
    for (const double c : owners.cuts()) std::printf(" %.3f", c);
    std::printf("\n");
  }
  coupling_moves(comm, failures);
  fracture_moves(comm, failures);
  return test::verdict(comm, failures, "the strips balanced by measured cost, the same cuts and owners on every rank");
}
