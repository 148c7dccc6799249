// The footprints' area pieces by holder (docs/parallel.md, "The footprints'
// area pieces by holder (foot28)") over the ranks mpirun started, run by
// ctest as mpi.footprints_ranks_N under `mpirun --oversubscribe -np N`
// (N = 1, 2, 3) and serially without MPI.
//
// Forty floes (squares, pentagons, non-convex L shapes) on a 128^2
// spectral sea in a 200 m periodic box, under wind, riding the waves
// through the strong penalty law; a distributed Simulation and a serial one
// step side by side. After every step, on each rank:
// - explicit kicks (the contact by owner), footprints rebuilt at every
//   placement and moved between rebuilds (footprint_reach = 0.3): each floe
//   the coupling gives this rank (FloeSeaContact::floe_owners) has its area
//   pieces, the serial run's bytes; every other floe has none; the area
//   pieces' bytes (memory().footprints.area_pieces.whole, capacity) are
//   below what every floe's pieces take (the whole gather's: the serial
//   count of pieces times a piece's 52 bytes and one offset a floe); the
//   same with the floes' heave given (start = "given": no static problem,
//   nothing gathered at the start);
// - the implicit step, by owner on this sea in slabs since slabs30 (docs/
//   parallel.md, "The implicit step on the slabs (slabs30)"): as the
//   explicit kicks, each rank its own floes' pieces only, the serial bytes;
// - the held floes' states are the serial run's (the static start, which
//   reads every floe's pieces gathered for it, included).
// The mutations this catches: gathering at every rebuild by owner (other
// floes' pieces, and the bytes); not gathering for the static start (the
// states differ from the first step). (The implicit step's gather on a sea
// not in slabs is check_implicit_ranks.py's bem and tank cases'.)
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <sstream>
#include <string>
#include <vector>

#include "core/config.hpp"
#include "coupling/scenario.hpp"
#include "coupling/simulation.hpp"
#include "parallel/comm.hpp"
#include "tests/parallel/ranks_main.hpp"

using namespace floesim;

namespace {

constexpr double kEnd = 1.5;  // s, 30 steps of dt_max

std::string floes_on_sea(const std::string& coupling) {
  std::ostringstream t;
  t << "[run]\nt_end = " << kEnd << "\ndt_max = 0.05\nseed = 2\nthreads = 1\n"
    << "[sea]\nmodel = \"spectral\"\ndims = 2\nsize = [200.0, 200.0]\ncells = [128, 128]\ndepth = 50.0\n"
    << "[sea.waves]\nkind = \"jonswap\"\nhs = 1.0\ntp = 6.0\n"
    << "[contact]\ndomain = \"periodic\"\nbox = [0.0, 200.0, 0.0, 200.0]\n"
    << "[forcing]\nwind = [15.0, 5.0]\n"
    << "[coupling]\nlaw = \"strong\"\nstiffness = 100.0\n"
    << coupling;
  // 8 rows of 5 floes, 25 m apart in x and y, sizes 12 to 18 m.
  int k = 0;
  for (int row = 0; row < 8; ++row)
    for (int col = 0; col < 5; ++col, ++k) {
      const double x = 40.0 * col + 3.0 + (row % 2) * 6.0, y = 25.0 * row + 2.0, s = 12.0 + (k % 4) * 2.0;
      t << "[[floes.floe]]\nvertices = [";
      if (k % 3 == 0)
        t << "[" << x << ", " << y << "], [" << x + s << ", " << y << "], [" << x + s << ", " << y + s << "], [" << x
          << ", " << y + s << "]";
      else if (k % 3 == 1)
        t << "[" << x + 0.1 * s << ", " << y << "], [" << x + 0.85 * s << ", " << y << "], [" << x + s << ", "
          << y + 0.6 * s << "], [" << x + 0.5 * s << ", " << y + s << "], [" << x << ", " << y + 0.6 * s << "]";
      else
        t << "[" << x << ", " << y << "], [" << x + s << ", " << y << "], [" << x + s << ", " << y + 0.35 * s
          << "], [" << x + 0.35 * s << ", " << y + 0.35 * s << "], [" << x + 0.35 * s << ", " << y + s << "], [" << x
          << ", " << y + s << "]";
      t << "]\n";
    }
  return t.str();
}

// Floe i's area pieces in a and b: the same bytes.
bool same_pieces(const Footprints& a, const Footprints& b, std::size_t i) {
  const std::size_t ka = a.offsets[i], kb = b.offsets[i], m = a.offsets[i + 1] - ka;
  return m == b.offsets[i + 1] - kb && std::memcmp(a.cell.data() + ka, b.cell.data() + kb, m * sizeof(std::uint32_t)) == 0 &&
         std::memcmp(a.area.data() + ka, b.area.data() + kb, m * sizeof(double)) == 0 &&
         std::memcmp(a.centroid.data() + ka, b.centroid.data() + kb, m * sizeof(Vec2)) == 0;
}

// Whether every placement of the run's footprints rebuilt them (the static
// start's build is a rebuild without a placement).
bool rebuilt_always(const Simulation& sim) {
  return sim.floe_sea()->footprint_rebuilds() >= sim.floe_sea()->footprint_placements();
}

// One variant: `by_owner` (this rank's floes' pieces only) or not (every floe's pieces on every rank).
void check_variant(const parallel::Communicator& comm, const std::string& name, const std::string& coupling,
                   bool by_owner, std::vector<std::string>& failures) {
  const std::string text = floes_on_sea(coupling);
  Simulation ranks(build_scenario(parse_config(text, name + ".toml", ".")), comm);
  Simulation serial(build_scenario(parse_config(text, name + ".toml", ".")));
  const std::size_t n = serial.floes().size();
  // A piece's bytes as MovingFootprints holds it: cell, area, centroid, and
  // its reference area and moment.
  constexpr std::size_t kPieceBytes = sizeof(std::uint32_t) + sizeof(double) + sizeof(Vec2) + sizeof(double) + sizeof(Vec2);
  int step = 0;
  long own_pieces = 0, other_floes = 0;
  std::size_t largest_bytes = 0, whole_bytes = 0;
  while (serial.time() < kEnd) {
    ranks.step(kEnd);
    serial.step(kEnd);
    ++step;
    const FloeSeaContact& r = *ranks.floe_sea();
    const FloeSeaContact& s = *serial.floe_sea();
    const Footprints& fp = r.footprints();
    const Footprints& whole = s.footprints();
    std::string wrong;
    if (fp.floes() != n || whole.floes() != n) wrong = "the footprints do not cover every floe";
    const std::span<const int> owner = r.floe_owners();
    for (std::size_t i = 0; i < n && wrong.empty(); ++i) {
      const bool mine = comm.serial() || !by_owner || owner[i] == comm.rank();
      if (mine && !same_pieces(fp, whole, i)) wrong = "floe " + std::to_string(i) + "'s area pieces differ from the serial run's";
      else if (!mine && fp.offsets[i + 1] != fp.offsets[i]) wrong = "floe " + std::to_string(i) + ", another rank's, has area pieces here";
      if (mine) own_pieces += static_cast<long>(fp.offsets[i + 1] - fp.offsets[i]);
      else ++other_floes;
    }
    std::vector<std::uint8_t> held(n, 1);
    if (!comm.serial()) {
      held = ranks.held_floes().mask;
      for (const std::uint32_t i : ranks.floe_owners().mine()) held[i] = 1;
    }
    for (std::size_t i = 0; i < n && wrong.empty(); ++i)
      if (held[i] && std::memcmp(&ranks.floes().state[i], &serial.floes().state[i], sizeof(FloeState)) != 0)
        wrong = "held floe " + std::to_string(i) + "'s state differs from the serial run's";
    // Below the whole gather's bytes: every floe's pieces on this rank.
    const std::size_t bytes = r.memory({}).footprints.area_pieces.whole;
    const std::size_t gathered = whole.cell.size() * kPieceBytes + (n + 1) * sizeof(std::size_t);
    largest_bytes = std::max(largest_bytes, bytes);
    whole_bytes = std::max(whole_bytes, gathered);
    if (wrong.empty() && by_owner && comm.size() > 1 && bytes >= gathered)
      wrong = "the area pieces take " + std::to_string(bytes) + " bytes, the whole gather's " + std::to_string(gathered);
    if (!wrong.empty()) failures.push_back(name + ": " + wrong + " after step " + std::to_string(step));
    // Every rank stops at the first step where one failed (the steps are collective).
    if (comm.any(!wrong.empty())) return;
  }
  if (by_owner && comm.size() > 1 && comm.sum(other_floes) == 0)
    failures.push_back(name + ": every floe on every rank: a weak test");
  if (rebuilt_always(serial) != (coupling.find("footprint_reach") == std::string::npos))
    failures.push_back(name + ": the footprints were " + (rebuilt_always(serial) ? "rebuilt at every placement" : "moved") +
                       ", not as the variant asks");
  if (comm.rank() == 0)
    std::printf("%s, %d rank(s): %d steps; rank 0's area pieces at most %zu bytes, every floe's %zu; rank 0 held %ld "
                "pieces over the steps\n",
                name.c_str(), comm.size(), step, largest_bytes, whole_bytes, own_pieces);
}

}  // namespace

int main() {
  parallel::Session session;
  return test::run_checks(
      session.world(), "the footprints' area pieces by holder: each rank its own floes', the serial bytes",
      [](const parallel::Communicator& comm, test::Failures& f) { check_variant(comm, "rebuilt", "", true, f); },
      [](const parallel::Communicator& comm, test::Failures& f) {
        check_variant(comm, "moved", "footprint_reach = 0.3\n", true, f);
      },
      [](const parallel::Communicator& comm, test::Failures& f) {
        check_variant(comm, "given", "start = \"given\"\n", true, f);
      },
      [](const parallel::Communicator& comm, test::Failures& f) {
        check_variant(comm, "implicit", "integrator = \"implicit\"\n", true, f);
      });
}
