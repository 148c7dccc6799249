// The kick by its holders (docs/parallel.md, "The kick by owner (kick29)")
// over the ranks mpirun started, run by ctest as mpi.kick_ranks_N under
// `mpirun --oversubscribe -np N` (N = 1, 2, 3) and serially without MPI.
//
// 24 square floes 14 m across, 4 rows of 6 in a 200 m x 200 m periodic box,
// 2 m apart in a row, neighbours closing at about 1 m/s (they collide), on
// a 64 x 64 spectral sea in slabs with a regular wave, riding on it through
// the penalty law: once strong (s = 1), once the blend (s = 0.5: the
// explicit damper, whose evaluation at each first half kick reads the rates
// the kicks wrote). The strong case must have collisions (its rows' floes
// meet within the run; the blend's damper keeps them apart). A distributed Simulation and a serial one in the same
// process step to 3 s. After every step every floe a rank holds
// (held_floes(): its band and own floes at the last detection) must have the
// serial run's bits, rates and vertical DOFs included: a holder that does
// not kick a floe, or kicks it with loads other than its coupling owner's,
// differs there at once, before any exchange could hide it. On 2 and 3
// ranks each rank must hold floes it does not drift (else the test is
// weak), and rank 0 must have taken loads by request at every step and
// fewer than every floe's (FloeSeaContact::shared_loads).
#include <cstdio>
#include <cstring>
#include <sstream>
#include <string>
#include <vector>

#include "core/config.hpp"
#include "coupling/floe_sea.hpp"
#include "coupling/scenario.hpp"
#include "coupling/simulation.hpp"
#include "parallel/comm.hpp"
#include "parallel/place.hpp"
#include "tests/parallel/ranks_main.hpp"

using namespace floesim;

namespace {

constexpr double kEnd = 3.0;  // s

std::string sea_pack(double strong_share) {
  std::ostringstream t;
  t << "[run]\ndt_max = 0.05\nt_end = " << kEnd << "\nthreads = 1\n"
    << "[sea]\nmodel = \"spectral\"\ndims = 2\nsize = [200.0, 200.0]\ncells = [64, 64]\ndepth = 50.0\n"
    << "[sea.waves]\nkind = \"regular\"\namplitude = 0.4\nwavelength = 50.0\ndirection = 20.0\n"
    << "[contact]\ndomain = \"periodic\"\nbox = [0.0, 200.0, 0.0, 200.0]\nrestitution = 0.4\nfriction = 0.5\n"
    << "[forcing]\nwind = [10.0, 6.0]\n"
    << "[coupling]\nstiffness = 100.0\n";
  if (strong_share < 1.0) t << "law = \"blend\"\nblend = " << strong_share << "\n";
  else t << "law = \"strong\"\n";
  // 4 rows of 6 floes, every row's velocities alternating in sign so that
  // neighbours close on each other.
  int k = 0;
  for (int row = 0; row < 4; ++row)
    for (int col = 0; col < 6; ++col, ++k) {
      const double x = 5.0 + 16.0 * col + 3.0 * (row % 2), y = 10.0 + 50.0 * row + 1.0 * (col % 3), w = 14.0;
      const double vx = (k % 2 ? -0.6 : 0.6) * (0.7 + 0.1 * (k % 4)), vy = (k % 3 - 1) * 0.3;
      t << "[[floes.floe]]\nvertices = [[" << x << ", " << y << "], [" << x + w << ", " << y << "], [" << x + w
        << ", " << y + w << "], [" << x << ", " << y + w << "]]\nvelocity = [" << vx << ", " << vy << "]\n";
    }
  return t.str();
}

void check_case(const parallel::Communicator& comm, double strong_share, std::vector<std::string>& failures) {
  const std::string name = strong_share < 1.0 ? "blend" : "strong";
  const std::string text = sea_pack(strong_share);
  Simulation ranks(build_scenario(parse_config(text, name + ".toml", ".")), comm);
  Simulation serial(build_scenario(parse_config(text, name + ".toml", ".")));
  const std::size_t n = serial.floes().size();
  long held_not_drifted = 0;
  std::string first_difference;
  int step = 0;
  while (serial.time() < kEnd) {
    ranks.step(kEnd);
    serial.step(kEnd);
    ++step;
    const parallel::HeldFloes& held = ranks.held_floes();
    const std::span<const int> owner = ranks.floe_owners().owner();
    if (held.mask.size() != n) {
      if (first_difference.empty()) first_difference = name + ": no held set after step " + std::to_string(step);
      continue;
    }
    for (std::size_t i = 0; i < n; ++i) {
      if (!held.holds(i)) continue;
      // The first difference noted; the ranks step on together (a rank
      // that stopped would leave the others in a collective call).
      if (first_difference.empty() &&
          std::memcmp(&ranks.floes().state[i], &serial.floes().state[i], sizeof(FloeState)) != 0)
        first_difference = name + ": held floe " + std::to_string(i) + " (owner " +
                           std::to_string(comm.serial() ? 0 : owner[i]) + ") differs from the serial run after step " +
                           std::to_string(step);
      if (!comm.serial() && owner[i] != comm.rank()) ++held_not_drifted;
    }
  }
  if (!first_difference.empty()) failures.push_back(first_difference);
  const std::vector<FloeState> written = ranks.writer_states();  // collective
  if (comm.writer() && (written.size() != n || std::memcmp(written.data(), serial.floes().state.data(),
                                                           n * sizeof(FloeState)) != 0))
    failures.push_back(name + ": the written states differ from the serial run's at the end");
  const FloeSeaContact::SharedLoads loads = ranks.floe_sea()->shared_loads();
  if (!comm.serial()) {
    if (held_not_drifted == 0) failures.push_back(name + ": the rank held no floe it does not drift: a weak test");
    if (comm.rank() == 0 && (loads.asked < step || !(loads.asked_floes < static_cast<long>(n) * loads.asked)))
      failures.push_back(name + ": rank 0's loads not by request at every step, or every floe's (" +
                         std::to_string(loads.asked) + " requests, " + std::to_string(loads.asked_floes) +
                         " floes, in " + std::to_string(step) + " steps)");
  }
  if (strong_share == 1.0 && serial.collision_stats().lcps == 0) failures.push_back(name + ": no collision: a weak test");
  if (comm.rank() == 0)
    std::printf("%s, %d rank(s): %d steps, %ld LCPs, %ld held-not-drifted floe-steps on rank 0, loads: %ld requests "
                "(%ld floes), %ld to every rank (%ld floes)\n",
                name.c_str(), comm.size(), step, static_cast<long>(serial.collision_stats().lcps), held_not_drifted,
                loads.asked, loads.asked_floes, loads.whole, loads.whole_floes);
}

void check_kicks(const parallel::Communicator& comm, std::vector<std::string>& failures) {
  check_case(comm, 1.0, failures);
  check_case(comm, 0.5, failures);
}

}  // namespace

int main() {
  parallel::Session session;
  return test::run_checks(session.world(), "the kick by its holders: every held floe is the serial run's after every step",
                          check_kicks);
}
