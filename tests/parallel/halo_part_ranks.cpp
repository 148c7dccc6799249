// The halo exchange's part (b) (docs/parallel.md, "The halo exchange
// (halo26)"): parallel::announce_held with a HaloPart on the ranks mpirun
// started. test_halo's dense periodic pack (tests/parallel/halo_case.hpp,
// 2 m/s) with owners by equal counts is announced once with every copy
// true (the held and announced sets of a detection). The floes then move
// 400 s at their velocities (wrapped), far beyond their reaches, so that
// floes leave their strips for ranks that did not hold them and enter bands
// they were not in; each rank's copy keeps the true moved state of the
// floes it held (as every holder moves them alike) and NaN in every other
// floe's state and step-start copy (the stale copies the exchange leaves).
// Each owner announces its floes that left its strip (with their reaches)
// and the second announce_held, given the first's announced sets, must
// leave every floe a rank holds with the true moved state, bit for bit, and
// every floe that came to it with its true step-start copy; on 2 and 3
// ranks some floe must have come to a rank that did not hold it and some
// must have entered a band (else the case tests nothing).
//
// The named mutations (builds not committed): the leave notices' states not
// written, and the band notices' states never sent: both leave NaN in a held
// floe. Run by ctest as mpi.halo_part_ranks_N (N = 1, 2, 3).
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "parallel/comm.hpp"
#include "parallel/held.hpp"
#include "parallel/place.hpp"
#include "tests/parallel/halo_case.hpp"
#include "tests/parallel/ranks_main.hpp"

using namespace floesim;

namespace {

struct Counts {
  long long came_unheld = 0, entered = 0, written = 0;
};

void check(const parallel::Communicator& comm, test::Failures& failures, Counts& counts) {
  const int ranks = comm.size(), rank = comm.rank();
  test::Pack p = test::moving_pack(3, true, 2.0);
  const std::size_t n = p.floes.size();
  const contact::Domain& d = p.detect.domain;
  parallel::FloeOwners owners(rank, ranks, d);
  owners.assign(p.floes);
  // The first detection: every copy true (a run's start).
  Floes copy = p.floes;
  contact::DetectionOptions options = p.detect;
  parallel::HaloPart first;
  first.state = &copy.state;
  const parallel::HeldFloes held0 =
      parallel::announce_held(comm, owners, copy, p.shapes, options, {}, {}, &first);
  // The true places 400 s on, wrapped into the box, and the step-start copy
  // (here: the first places).
  Floes after = p.floes;
  for (FloeState& s : after.state) {
    s.x += 400.0 * s.vx;
    s.y += 400.0 * s.vy;
    s.x = d.xmin + std::fmod(std::fmod(s.x - d.xmin, d.width()) + d.width(), d.width());
    s.y = d.ymin + std::fmod(std::fmod(s.y - d.ymin, d.height()) + d.height(), d.height());
  }
  const std::vector<FloeState>& start_true = p.floes.state;
  // This rank's copies: the floes it held true, the others NaN; the reaches
  // of its own floes (set_reach's), the others NaN (the poison tool,
  // halo_case.hpp).
  test::Held held(n), own(n);
  for (std::size_t j = 0; j < n; ++j) {
    held[j] = held0.holds(j) ? 1 : 0;
    own[j] = owners.owner()[j] == rank ? 1 : 0;
  }
  copy = after;
  copy.state = test::poisoned(after.state, held);
  std::vector<FloeState> start = test::poisoned(start_true, held);
  options.reach = test::poisoned(p.detect.reach, own);
  std::vector<parallel::LeaveNotice> leaving = owners.leaving(rank, copy);
  for (parallel::LeaveNotice& k : leaving) k.reach = options.reach[k.floe];
  const long long mine = static_cast<long long>(leaving.size());
  const std::vector<long long> leaving_counts = comm.allgather(std::span<const long long>(&mine, 1));
  const std::vector<int> owner_before(owners.owner().begin(), owners.owner().end());
  parallel::HaloPart second;
  second.last = &first.announced;
  second.state = &copy.state;
  second.start = &start;
  const parallel::HeldFloes held1 =
      parallel::announce_held(comm, owners, copy, p.shapes, options, leaving, leaving_counts, &second);
  counts.written += static_cast<long long>(second.written.size());
  std::size_t wrong_state = 0, wrong_start = 0;
  for (std::size_t j = 0; j < n; ++j) {
    if (!held1.holds(j)) continue;
    if (std::memcmp(&copy.state[j], &after.state[j], sizeof(FloeState)) != 0) ++wrong_state;
    if (!held0.holds(j)) ++counts.entered;
    if (owners.owner()[j] == rank && owner_before[j] != rank) {
      if (std::memcmp(&start[j], &start_true[j], sizeof(FloeState)) != 0) ++wrong_start;
      if (!held0.holds(j)) ++counts.came_unheld;
    }
  }
  if (wrong_state)
    failures.push_back(std::to_string(wrong_state) + " held floes' states differ from the true moved states");
  if (wrong_start)
    failures.push_back(std::to_string(wrong_start) + " floes that came to the rank lack their step-start copies");
}

}  // namespace

int main() {
  parallel::Session session;
  const parallel::Communicator& comm = session.world();
  test::Failures failures;
  Counts counts;
  try {
    check(comm, failures, counts);
  } catch (const std::exception& e) {
    failures.push_back(std::string("threw: ") + e.what());
  }
  const long long came = comm.sum(counts.came_unheld), entered = comm.sum(counts.entered),
                  written = comm.sum(counts.written);
  if (comm.size() > 1 && (came == 0 || entered == 0))
    failures.push_back("no floe came to a rank that did not hold it, or none entered a band: no test");
  if (comm.writer())
    std::printf("%d ranks: %lld floes came to a rank that did not hold them, %lld entered a band, "
                "%lld states received\n",
                comm.size(), came, entered, written);
  return test::verdict(comm, failures, "the halo exchange's part (b): every held floe its owner's state");
}
