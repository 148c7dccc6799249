// The drift's owners from their own floes (docs/parallel.md, "The drift's
// owners from their own floes (update25)"): FloeOwners::update on the ranks
// mpirun started, each rank given a copy of the floes in which every floe it
// does not own is NaN (the stale copies the halo exchange will leave), at
// every step (a move of the cuts gathers each floe's row or place from its
// owner).
// 2000 floes drift at random speeds along y (many cross a cut each step),
// and every third step one floe in ten is put exactly on a cut (where
// round-off would show); the ranks charge each floe's known cost (a floe
// above the box's middle costs 20 times one below), so the cuts move every
// 10 steps. After each update every rank's owner array and own floes must
// equal FloeOwners::assign's over the whole, true floes with the same cuts,
// entry for entry, and the cuts must be those of a twin FloeOwners updated
// with the true floes on every rank (the reading of every floe it
// replaces: FloeOwners::assign then the move over every floe's copy), to
// the bit. Two layouts: free cuts in a periodic box from ymin = -250 m
// (the wrap rounds there: the box from 0 is the easy case), and the sea's
// slabs (rows of 1.25 m, blocks of 8) in a periodic box from 0.
//
// The named mutation: the notices not gathered (each rank applies only its
// own, FloeOwners::take_leaving(leaving(...)) on a copy of the owners before
// the update): it must give other owners than assign at some step on some
// rank (a floe that came to a rank is then unknown to it). Run by ctest as
// mpi.owners_update_ranks_N (N = 1, 2, 3).
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "parallel/comm.hpp"
#include "parallel/place.hpp"
#include "tests/parallel/halo_case.hpp"
#include "tests/parallel/ranks_main.hpp"

using namespace floesim;

namespace {

struct Counts {
  long long steps = 0, migrations = 0, moves = 0, lossy_differs = 0;
};

void run_layout(const parallel::Communicator& comm, bool slabs, test::Failures& failures, Counts& counts) {
  const int ranks = comm.size(), rank = comm.rank();
  const double ymin = slabs ? 0.0 : -250.0, height = 1000.0;
  const contact::Domain box{true, 0.0, 1000.0, ymin, ymin + height};
  const std::size_t n = 2000;
  Floes truth;
  std::vector<double> speed;
  std::mt19937_64 rng(11);  // the same floes on every rank
  std::uniform_real_distribution<double> at(ymin, ymin + height), v(-3.0, 3.0);
  for (std::size_t i = 0; i < n; ++i) {
    FloeState s{};
    s.y = at(rng);
    truth.state.push_back(s);
    truth.thickness.push_back(1.0);
    speed.push_back(v(rng));
  }
  parallel::FloeOwners owners(rank, ranks, box);
  const auto twin = [&] {  // the same strips, assigned over the true floes
    parallel::FloeOwners out(rank, ranks, box);
    if (owners.has_slabs()) out.set_slabs(owners.slabs());
    else if (!owners.cuts().empty() || ranks == 1) out.set_cuts(owners.cuts());
    out.assign(truth);
    return out;
  };
  if (slabs) {
    std::vector<int> first{0};
    for (int r = 1; r < ranks; ++r) first.push_back(8 * ((100 * r) / ranks));
    first.push_back(800);
    owners.set_slabs({first, 1.25, 8});
  }
  owners.assign(truth);
  parallel::FloeOwners reference = owners;  // updated with the true floes
  for (std::size_t step = 1; step <= 60; ++step) {
    for (std::size_t i = 0; i < n; ++i) truth.state[i].y += speed[i];  // unwrapped: place() wraps
    if (step % 3 == 0 && !owners.cuts().empty())
      for (std::size_t i = step % 10; i < n; i += 10) truth.state[i].y = owners.cuts()[(i / 10) % owners.cuts().size()];
    const bool moving = owners.may_move(step);
    // This rank's copy: every floe poisoned (at a move too) but those it
    // owned and those that come to it at the present cuts (in a run, its
    // band's: a floe that crosses a cut was in the band, docs/parallel.md,
    // "Migration across cuts").
    const parallel::FloeOwners arriving = twin();
    test::Held kept(n);
    for (std::size_t i = 0; i < n; ++i) kept[i] = owners.owner()[i] == rank || arriving.owner()[i] == rank ? 1 : 0;
    Floes copy = truth;
    copy.state = test::poisoned(truth.state, kept);  // the poison tool (halo_case.hpp): every column NaN
    parallel::FloeOwners lossy = owners;
    owners.update(comm, copy, step);
    reference.update(comm, truth, step);
    const auto bits = [](double x) { return std::bit_cast<std::uint64_t>(x); };
    if (!std::equal(owners.cuts().begin(), owners.cuts().end(), reference.cuts().begin(), reference.cuts().end(),
                    [&](double a, double b) { return bits(a) == bits(b); }) ||
        owners.slabs().first_row != reference.slabs().first_row)
      failures.push_back(std::string(slabs ? "slabs" : "free cuts") + ": step " + std::to_string(step) +
                         ": the cuts differ from those updated with the true floes");
    const parallel::FloeOwners whole = twin();
    const bool same = std::equal(owners.owner().begin(), owners.owner().end(), whole.owner().begin(),
                                 whole.owner().end()) &&
                      owners.mine() == whole.mine();
    if (!same) failures.push_back(std::string(slabs ? "slabs" : "free cuts") + ": step " + std::to_string(step) +
                                  ": the owners differ from assign's over the true floes");
    ++counts.steps;
    if (!moving) {  // the mutation where the cuts stay
      const std::vector<parallel::LeaveNotice> mine = lossy.leaving(rank, copy);
      counts.migrations += static_cast<long long>(mine.size());
      lossy.take_leaving(mine);
      counts.lossy_differs += std::equal(lossy.owner().begin(), lossy.owner().end(), whole.owner().begin(),
                                         whole.owner().end()) ? 0 : 1;
    }
    // Each rank charges its floes' known costs (the cuts move every 10 steps).
    double charged = 0.0;
    for (const std::uint32_t i : owners.mine()) charged += owners.place(truth.state[i]) >= ymin + 0.5 * height ? 20e-6 : 1e-6;
    if (owners.has_slabs()) {
      owners.charge_coupling(charged);
      reference.charge_coupling(charged);
    } else {
      owners.charge(charged);
      reference.charge(charged);
    }
  }
  counts.moves += owners.moves();
}

}  // namespace

int main() {
  parallel::Session session;
  const parallel::Communicator& comm = session.world();
  test::Failures failures;
  Counts counts;
  try {
    run_layout(comm, false, failures, counts);
    run_layout(comm, true, failures, counts);
  } catch (const std::exception& e) {
    failures.push_back(std::string("threw: ") + e.what());
  }
  const long long migrations = comm.sum(counts.migrations), differs = comm.sum(counts.lossy_differs);
  if (comm.size() > 1) {
    if (migrations < 1000) failures.push_back("fewer than 1000 floes migrated: no test");
    if (counts.moves < 2) failures.push_back("the cuts moved fewer than twice in a layout: no test");
    if (differs == 0) failures.push_back("the mutation (notices not gathered) gave assign's owners: not caught");
  }
  if (comm.writer())
    std::printf("%d ranks: %lld steps a rank, %lld floes migrated by notice, %lld moves of the cuts (rank 0); "
                "the mutation differs at %lld rank-steps\n",
                comm.size(), counts.steps, migrations, counts.moves, differs);
  return test::verdict(comm, failures, "the drift's owners from the own floes are assign's, step by step");
}
