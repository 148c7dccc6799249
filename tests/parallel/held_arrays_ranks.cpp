// The drift's quadrature and the collision shapes held by band
// (docs/parallel.md, "The arrays held by band: measured (mem27)", "The
// collision shapes held by band (shapes28)") over the ranks mpirun started, run by ctest
// as mpi.held_arrays_ranks_N under `mpirun --oversubscribe -np N` (N = 1,
// 2, 3) and serially without MPI.
//
// A moving pack: 120 floes (squares, pentagons and non-convex L shapes) in
// 20 rows of 6 (y from 0 to 1200 m), started at velocities up to 0.4 m/s
// with wind, current and Coriolis, so that they collide and cross the
// strips' cuts and the bands' edges. A distributed Simulation and a serial
// one step to 900 s; after every step, on each rank: every floe it holds
// (its band at the last detection and its own floes, held_floes() and
// floe_owners().mine()) has its quadrature points and its collision
// shape's parts, the same bytes as the serial run's whole build; every
// other floe has neither; every floe's radius is the serial one; and the
// held floes' states are the serial run's. On 2 and 3 ranks some floe must
// enter and some leave a rank's held set during the run (else the test is
// weak), and the serial run must have collisions.
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
#include "parallel/place.hpp"
#include "tests/parallel/ranks_main.hpp"
#include "tests/parallel/rows_pack.hpp"

using namespace floesim;

namespace {

// Squares, pentagons and L shapes in turn, 40 m across.
std::string moving_pack() {
  return test::rows_pack(
      {.seed = 7, .rows = 20, .speed = 0.4, .t_end = 900.0, .wind = "[8.0, -6.0]", .current = "[0.02, 0.05]"},
      [](int k, double x, double y) {
        std::ostringstream v;
        if (k % 3 == 0)
          v << "[" << x << ", " << y << "], [" << x + 40 << ", " << y << "], [" << x + 40 << ", " << y + 40 << "], ["
            << x << ", " << y + 40 << "]";
        else if (k % 3 == 1)
          v << "[" << x + 4 << ", " << y << "], [" << x + 34 << ", " << y << "], [" << x + 40 << ", " << y + 24
            << "], [" << x + 19 << ", " << y + 40 << "], [" << x << ", " << y + 24 << "]";
        else
          v << "[" << x << ", " << y << "], [" << x + 40 << ", " << y << "], [" << x + 40 << ", " << y + 14 << "], ["
            << x + 14 << ", " << y + 14 << "], [" << x + 14 << ", " << y + 40 << "], [" << x << ", " << y + 40 << "]";
        return test::RowFloe{v.str(), ""};
      });
}

// Why floe i's shape on this rank (`s`) is not the serial build's (`whole`),
// or empty when it is: its parts one by one, vertex bytes and count.
std::string shape_differs(const contact::CollisionShapes& s, const contact::CollisionShapes& whole, std::size_t i) {
  if (!s.has(i)) return "has no shape";
  if (s.parts_of(i) != whole.parts_of(i)) return "has another count of parts";
  for (std::size_t k = 0; k < s.parts_of(i); ++k) {
    const std::span<const Vec2> v = s.part(s.parts_begin(i) + k), w = whole.part(whole.parts_begin(i) + k);
    if (v.size() != w.size() || std::memcmp(v.data(), w.data(), v.size_bytes()) != 0)
      return "has part " + std::to_string(k) + " unlike the serial build";
  }
  return {};
}

void check_held(const parallel::Communicator& comm, std::vector<std::string>& failures) {
  const std::string text = moving_pack();
  Simulation ranks(build_scenario(parse_config(text, "moving.toml", ".")), comm);
  Simulation serial(build_scenario(parse_config(text, "moving.toml", ".")));
  const std::size_t n = serial.floes().size();
  const FootprintQuadrature& whole = serial.quadrature();
  const contact::CollisionShapes& whole_shapes = serial.shapes();
  long entered = 0, left = 0, shapes_entered = 0, shapes_left = 0;
  std::vector<std::uint8_t> had(n, 0), had_shape(n, 0);
  for (std::size_t i = 0; i < n; ++i) {
    had[i] = ranks.quadrature().has(i);
    had_shape[i] = ranks.shapes().has(i);
  }
  int step = 0;
  while (serial.time() < 900.0) {
    ranks.step(900.0);
    serial.step(900.0);
    ++step;
    // What this rank holds: its band at the last detection and its own floes.
    std::vector<std::uint8_t> held(n, 1);
    if (!comm.serial()) {
      held = ranks.held_floes().mask;
      for (const std::uint32_t i : ranks.floe_owners().mine()) held[i] = 1;
    }
    const FootprintQuadrature& q = ranks.quadrature();
    const contact::CollisionShapes& shapes = ranks.shapes();
    std::string wrong;
    if (shapes.radius.size() != n ||
        std::memcmp(shapes.radius.data(), whole_shapes.radius.data(), n * sizeof(double)) != 0)
      wrong = "the radii differ from the serial build's";
    for (std::size_t i = 0; i < n && wrong.empty(); ++i) {
      if (!held[i]) {
        if (q.has(i)) wrong = "floe " + std::to_string(i) + " is not held but has quadrature points";
        else if (shapes.has(i)) wrong = "floe " + std::to_string(i) + " is not held but has a collision shape";
        continue;
      }
      if (const std::string why = shape_differs(shapes, whole_shapes, i); !why.empty()) {
        wrong = "held floe " + std::to_string(i) + " " + why;
        continue;
      }
      const std::span<const Vec2> p = q.points(i), pw = whole.points(i);
      const std::span<const double> w = q.weights(i), ww = whole.weights(i);
      if (!q.has(i) || p.size() != pw.size() || w.size() != ww.size() ||
          std::memcmp(p.data(), pw.data(), p.size_bytes()) != 0 || std::memcmp(w.data(), ww.data(), w.size_bytes()) != 0)
        wrong = "held floe " + std::to_string(i) + "'s quadrature differs from the serial build";
      else if (std::memcmp(&ranks.floes().state[i], &serial.floes().state[i], sizeof(FloeState)) != 0)
        wrong = "held floe " + std::to_string(i) + "'s state differs from the serial run's";
    }
    if (!wrong.empty()) failures.push_back(wrong + " after step " + std::to_string(step));
    // Every rank stops at the first step where one failed (the steps are collective).
    if (comm.any(!wrong.empty())) return;
    for (std::size_t i = 0; i < n; ++i) {
      const std::uint8_t now = q.has(i);
      entered += now && !had[i];
      left += !now && had[i];
      had[i] = now;
      const std::uint8_t shaped = shapes.has(i);
      shapes_entered += shaped && !had_shape[i];
      shapes_left += !shaped && had_shape[i];
      had_shape[i] = shaped;
    }
  }
  const std::vector<FloeState> written = ranks.writer_states();  // collective
  if (comm.writer() && (written.size() != n || std::memcmp(written.data(), serial.floes().state.data(),
                                                           n * sizeof(FloeState)) != 0))
    failures.push_back("the gathered states differ from the serial run's at the end");
  const long entered_all = comm.sum(entered), left_all = comm.sum(left);
  const long shapes_entered_all = comm.sum(shapes_entered), shapes_left_all = comm.sum(shapes_left);
  if (!comm.serial() && (entered_all == 0 || left_all == 0 || shapes_entered_all == 0 || shapes_left_all == 0))
    failures.push_back("no floe entered or left a held set: a weak test");
  if (serial.collision_stats().lcps == 0) failures.push_back("no collision: a weak test");
  if (comm.rank() == 0)
    std::printf("%d rank(s): %d steps, %ld LCPs; floes entering a held set %ld, leaving %ld (all ranks; shapes: "
                "%ld, %ld); rank 0 holds the points of %zu of %zu floes, the shapes of %zu\n",
                comm.size(), step, static_cast<long>(serial.collision_stats().lcps), entered_all, left_all,
                shapes_entered_all, shapes_left_all, static_cast<std::size_t>(std::count(had.begin(), had.end(), 1)),
                n, static_cast<std::size_t>(std::count(had_shape.begin(), had_shape.end(), 1)));
}

}  // namespace

int main() {
  parallel::Session session;
  return test::run_checks(session.world(),
                          "the quadrature and collision shapes held by band: held floes' as the serial build, no other",
                          check_held);
}
