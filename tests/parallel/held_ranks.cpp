// The floes a rank holds and the passes over them (docs/parallel.md, "The
// band in the library and the detect phase over the held floes") over the
// ranks mpirun started, run by ctest as mpi.held_ranks_N under `mpirun
// --oversubscribe -np N` (N = 1, 2, 3) and serially without MPI.
//
// A moored pack: 60 square floes 40 m across in 10 rows of 6 (y from 0 to
// 600 m, so that every strip holds some), every second one on a soft
// mooring (period 200 s, damping 0.1), with wind, current and Coriolis,
// started at velocities up to 0.3 m/s so that they collide (open plane).
// A distributed Simulation and a serial one in the same process step to
// 600 s: after every step the held floes' states and those the writer
// gathers must be the same bits (the moorings
// are kicked by the floes' drift owners, after the owners' update), and
// the rank's held floes (Simulation::held_floes, the band at the last
// detection) must hold its own floes and both floes of every pair whose
// floe a it owns; at the end the whole detection gathered (each rank
// sending its own floes' reaches: it writes only its held floes') must
// carry the serial run's reaches. On 2 and 3 ranks every rank must own a moored floe at
// some step and the serial run must have collisions (else the test is
// weak).
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <sstream>
#include <string>
#include <vector>

#include "core/config.hpp"
#include "core/error.hpp"
#include "coupling/scenario.hpp"
#include "coupling/simulation.hpp"
#include "parallel/comm.hpp"
#include "parallel/place.hpp"
#include "tests/parallel/ranks_main.hpp"
#include "tests/parallel/rows_pack.hpp"

using namespace floesim;

namespace {

// 60 square floes 40 m across, every second one on a soft mooring.
std::string moored_pack() {
  return test::rows_pack({.seed = 3, .rows = 10, .speed = 0.3, .t_end = 600.0, .wind = "[12.0, 4.0]",
                          .current = "[0.05, 0.1]"},
                         [](int k, double x, double y) {
                           const double w = 40.0;
                           std::ostringstream v;
                           v << "[" << x << ", " << y << "], [" << x + w << ", " << y << "], [" << x + w << ", "
                             << y + w << "], [" << x << ", " << y + w << "]";
                           return test::RowFloe{v.str(), k % 2 == 0 ? "mooring_period = 200.0\nmooring_damping = 0.1\n" : ""};
                         });
}

void check_moored(const parallel::Communicator& comm, std::vector<std::string>& failures) {
  const std::string text = moored_pack();
  Simulation ranks(build_scenario(parse_config(text, "moored.toml", ".")), comm);
  Simulation serial(build_scenario(parse_config(text, "moored.toml", ".")));
  const std::size_t n = serial.floes().size();
  bool owned_moored = comm.serial();
  int step = 0;
  while (serial.time() < 600.0) {
    ranks.step(600.0);
    serial.step(600.0);
    ++step;
    // With the state held by owner (the halo exchange, halo26) a rank's
    // copies of the floes it does not hold are stale: its held floes, and
    // every floe as the writer gathers it from the owners, are the serial
    // run's.
    const parallel::HeldFloes& held = ranks.held_floes();
    bool same = held.mask.size() == n;
    for (std::size_t i = 0; same && i < n; ++i)
      same = !held.holds(i) || std::memcmp(&ranks.floes().state[i], &serial.floes().state[i], sizeof(FloeState)) == 0;
    const std::vector<FloeState> written = ranks.writer_states();  // collective
    if (comm.writer())
      same = same && written.size() == n && std::memcmp(written.data(), serial.floes().state.data(), n * sizeof(FloeState)) == 0;
    if (!same) {
      failures.push_back("the states differ from the serial run's after step " + std::to_string(step));
      return;
    }
    const std::span<const int> owner = ranks.floe_owners().owner();
    const auto owns = [&](std::size_t i) { return comm.serial() || owner[i] == comm.rank(); };
    bool holds = held.mask.size() == n && (comm.serial() || owner.size() == n);
    for (std::size_t i = 0; holds && i < n; ++i) {
      holds = !owns(i) || held.holds(i);
      owned_moored = owned_moored || (owns(i) && i % 2 == 0);
    }
    if (!holds) {
      failures.push_back("held_floes() misses an own floe after step " + std::to_string(step));
      return;
    }
  }
  const contact::Detection& d = ranks.detection();  // collective: gathered on every rank
  const std::span<const int> owner = ranks.floe_owners().owner();
  const parallel::HeldFloes& held = ranks.held_floes();
  for (const contact::NearPair& q : d.pairs)
    if ((comm.serial() || owner[q.a] == comm.rank()) && !(held.holds(q.a) && held.holds(q.b))) {
      failures.push_back("held_floes() misses a floe of a pair the rank detected");
      break;
    }
  // Each rank writes the reaches of the floes it holds only (band18); the
  // whole detection gathered carries every floe's from its owner: the
  // serial run's, bit for bit.
  const contact::Detection& whole_serial = serial.detection();
  if (d.reach.size() != n || whole_serial.reach.size() != n ||
      std::memcmp(d.reach.data(), whole_serial.reach.data(), n * sizeof(double)) != 0)
    failures.push_back("the gathered detection's reaches differ from the serial run's");
  if (!owned_moored) failures.push_back("the rank never owned a moored floe: a weak test");
  if (serial.collision_stats().lcps == 0) failures.push_back("no collision: a weak test");
  if (comm.rank() == 0)
    std::printf("%d rank(s): %d steps, %ld LCPs, rank 0 holds %zu of %zu floes at the end\n", comm.size(), step,
                static_cast<long>(serial.collision_stats().lcps), held.index.size(), n);
}

}  // namespace

int main() {
  parallel::Session session;
  return test::run_checks(session.world(), "held floes: the moored run equals the serial run, bit for bit", check_moored);
}
