// Exact sums over the ranks mpirun started (Communicator::sum,
// core/exact_sum.hpp, docs/parallel.md "Exact sums"), run by ctest as
// mpi.exact_sum_ranks_N under `mpirun --oversubscribe -np N` (N = 1, 2, 3)
// and serially without MPI.
//
// 1. Values over the whole exponent range, huge ones cancelling (a plain sum
//    in another order gives other bits), owned by scattered and by
//    contiguous subsets: each rank sums its own in reverse order, the ranks
//    combine in one call, and every rank must hold the bits of one serial
//    ExactSum of all the values in a shuffled order, with the counts summed.
// 2. A periodic pack with wind and current, collisions only, stepped by a
//    distributed Simulation (each rank summing the floes it owns by place)
//    and by a serial one in the same process: the momentum budget, the
//    momentum, the energies and the state (each rank's held floes, and
//    every floe as the writer gathers it) must be the same bits, each
//    rank must own a strict, non-empty subset on 2 and 3 ranks, and there
//    must be collisions and a wind's push (so that the budget is not 0).
//    Simulation::detection(), read on every rank after the steps (each rank
//    then holds only its part: the read gathers them, collectively), must
//    be the serial detection, pair by pair; Simulation::held_floes() (the
//    band at the last detection, docs/parallel.md "The band in the
//    library") must hold the rank's own floes and both floes of every pair
//    whose floe a it owns, with the same H on every rank, and every floe
//    serially. Communicator::max must give the largest value.
// 3. Four floes blown to infinity by a 1e200 m/s wind, floe 0 in the top
//    strip (on 2 ranks, the last rank's): every rank must throw the serial
//    run's message, which names floe 0 (the ranks agree on the lowest bad
//    floe; rank 0's own first is floe 1).
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <array>
#include <filesystem>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <unistd.h>

#include "core/config.hpp"
#include "core/error.hpp"
#include "core/exact_sum.hpp"
#include "core/pack.hpp"
#include "core/pack_generator.hpp"
#include "coupling/scenario.hpp"
#include "coupling/simulation.hpp"
#include "parallel/comm.hpp"
#include "parallel/place.hpp"
#include "tests/parallel/ranks_main.hpp"

using namespace floesim;

namespace {
bool same_bits(double a, double b) { return std::bit_cast<std::uint64_t>(a) == std::bit_cast<std::uint64_t>(b); }

std::vector<double> values(std::size_t n, std::uint64_t seed) {
  // Random fractions, exponent fields over the whole range, either sign;
  // and every tenth value followed later by its negation.
  std::mt19937_64 rng(seed);
  std::uniform_int_distribution<int> field(0, 2046);
  std::vector<double> x;
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint64_t bits = (rng() & ((std::uint64_t{1} << 52) - 1)) |
                               (static_cast<std::uint64_t>(field(rng)) << 52) | (rng() & (std::uint64_t{1} << 63));
    x.push_back(std::bit_cast<double>(bits));
    if (i % 10 == 0) x.push_back(std::ldexp(1.0, 600) * static_cast<double>(i + 1));
  }
  const std::size_t m = x.size();
  for (std::size_t i = 0; i < m; ++i)
    if (std::abs(x[i]) > 1e180) x.push_back(-x[i]);
  return x;
}

void check_sums(const parallel::Communicator& comm, std::vector<std::string>& failures) {
  const std::vector<double> x = values(30000, 3);  // the same on every rank
  std::vector<double> shuffled = x;
  std::mt19937_64 rng(4);
  std::shuffle(shuffled.begin(), shuffled.end(), rng);
  ExactSum serial;
  double plain = 0.0;
  for (double v : shuffled) serial.add(v);
  for (double v : x) plain += v;
  const double reference = serial.value();
  if (same_bits(plain, reference)) failures.push_back("the values' plain sum equals the exact one: a weak test");
  const auto ranks = static_cast<std::size_t>(comm.size()), rank = static_cast<std::size_t>(comm.rank());
  const parallel::Range share = comm.share(x.size());
  for (const bool scattered : {true, false}) {
    auto mine = [&](std::size_t i) {
      return scattered ? (i * 2654435761u + 17u) % 1000003u % ranks == rank : i >= share.begin && i < share.end;
    };
    std::array<ExactSum, 2> sums;  // the values; and the values with an infinity on the last rank
    std::array<long long, 1> count{0};
    for (std::size_t i = x.size(); i-- > 0;)
      if (mine(i)) {
        sums[0].add(x[i]);
        sums[1].add(x[i]);
        ++count[0];
      }
    if (rank + 1 == ranks) sums[1].add(INFINITY);
    comm.sum(sums, count);
    const char* how = scattered ? "scattered owners" : "contiguous shares";
    if (!same_bits(sums[0].value(), reference)) {
      std::ostringstream m;
      m.precision(17);
      m << how << ": the ranks' sum " << sums[0].value() << " is not the serial " << reference;
      failures.push_back(m.str());
    }
    if (!(sums[1].value() == INFINITY)) failures.push_back(std::string(how) + ": an infinity on one rank was lost");
    if (count[0] != static_cast<long long>(x.size())) failures.push_back(std::string(how) + ": the counts' sum is wrong");
    // Every rank the same bits (the gather in rank order).
    const double v = sums[0].value();
    for (double w : comm.allgather(std::span<const double>(&v, 1)))
      if (!same_bits(w, v)) failures.push_back(std::string(how) + ": the ranks disagree");
  }
  if (comm.min(100 - comm.rank()) != 101 - comm.size()) failures.push_back("Communicator::min is not the least");
  if (!same_bits(comm.max(0.25 * comm.rank() - 3.0), 0.25 * (comm.size() - 1) - 3.0))
    failures.push_back("Communicator::max is not the largest");
}

// The run's config and the pack file it reads (removed once loaded).
struct PackConfig {
  std::string text, path;
};

PackConfig pack_config(const parallel::Communicator& comm) {
  PackOptions o;
  o.floes = 300;
  o.concentration = 0.55;
  o.width = o.height = 1500.0;
  o.seed = 9;
  GeneratedPack g = generate_pack(o);
  std::mt19937_64 rng(9);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (FloeState& s : g.floes.state) {
    s.vx = 0.1 * u(rng);
    s.vy = 0.1 * u(rng);
    s.yaw_rate = 1e-4 * u(rng);
  }
  // One file per process: the ranks write at once, and ctest runs the
  // test's 1-, 2- and 3-rank cases side by side (a name by rank alone was
  // written by two runs at once).
  const std::string path = (std::filesystem::temp_directory_path() /
                            ("floesim_exact_sum_ranks_" + std::to_string(comm.size()) + "_" +
                             std::to_string(comm.rank()) + "_" + std::to_string(::getpid()) + ".h5"))
                               .string();
  write_pack(path, g.floes, g.window);
  std::ostringstream t;
  t << "[run]\ndt_max = 10\nthreads = 1\n[floes]\npack = \"" << path << "\"\n"
    << "[contact]\ndomain = \"periodic\"\nrestitution = 0.4\nfriction = 0.7\n"
    << "[forcing]\nwind = [10.0, 3.0]\ncurrent = [0.0, 0.05]\nlatitude = 80.2\n";
  return {t.str(), path};
}

void check_simulation(const parallel::Communicator& comm, std::vector<std::string>& failures) {
  const PackConfig pack = pack_config(comm);
  Simulation ranks(build_scenario(parse_config(pack.text, "pack.toml", ".")), comm);
  Simulation serial(build_scenario(parse_config(pack.text, "pack.toml", ".")));
  std::filesystem::remove(pack.path);
  const std::size_t n = serial.floes().size();
  bool strict_subset = true;
  for (int k = 0; k < 40; ++k) {
    ranks.step(400.0);
    serial.step(400.0);
    const std::size_t owned = ranks.floe_owners().mine().size();
    if (comm.size() > 1 && (owned == 0 || owned >= n)) strict_subset = false;
  }
  auto same2 = [](const Vec2& a, const Vec2& b) { return same_bits(a.x(), b.x()) && same_bits(a.y(), b.y()); };
  const Simulation::MomentumBudget &a = ranks.momentum_budget(), &b = serial.momentum_budget();
  if (!same2(a.external, b.external) || !same2(a.collisions, b.collisions)) {
    std::ostringstream m;
    m.precision(17);
    m << "the momentum budget differs: external " << a.external.transpose() << " against " << b.external.transpose()
      << ", collisions " << a.collisions.transpose() << " against " << b.collisions.transpose();
    failures.push_back(m.str());
  }
  if (!same2(ranks.momentum(), serial.momentum())) failures.push_back("momentum() differs from the serial run's");
  const Energies ea = ranks.energies(), eb = serial.energies();
  for (std::size_t j = 0; j < eb.values.size(); ++j)
    if (!same_bits(ea.values[j], eb.values[j])) failures.push_back("energy " + eb.names[j] + " differs");
  // The state: each rank's copies of the floes it holds (its band at the
  // last detection and its own floes; the others are left unwrapped across
  // the box's seam since handover25), and every floe as the writer gathers
  // it from the owners (collective).
  std::vector<std::uint8_t> kept = ranks.held_floes().mask;
  kept.resize(n, comm.serial() ? 1 : 0);
  for (const std::uint32_t i : ranks.floe_owners().mine()) kept[i] = 1;
  for (std::size_t i = 0; i < n; ++i)
    if ((comm.serial() || kept[i]) &&
        std::memcmp(&ranks.floes().state[i], &serial.floes().state[i], sizeof(FloeState)) != 0) {
      failures.push_back("held floe " + std::to_string(i) + "'s state differs");
      break;
    }
  const std::vector<FloeState> written = ranks.writer_states();
  if (comm.writer() && (written.size() != n ||
                        std::memcmp(written.data(), serial.floes().state.data(), n * sizeof(FloeState)) != 0))
    failures.push_back("the states gathered by the writer differ");
  // The whole detection when read: gathered from the parts on every rank alike.
  const contact::Detection &da = ranks.detection(), &db = serial.detection();
  bool same_detection = da.pairs.size() == db.pairs.size() && da.contacts.size() == db.contacts.size() &&
                        da.witnesses.size() == db.witnesses.size();
  for (std::size_t p = 0; same_detection && p < db.pairs.size(); ++p) {
    const contact::NearPair &x = da.pairs[p], &y = db.pairs[p];
    same_detection = x.a == y.a && x.b == y.b && same2(x.shift, y.shift) && same_bits(x.distance, y.distance) &&
                     x.first_contact == y.first_contact && x.contact_count == y.contact_count &&
                     x.first_witness == y.first_witness && x.witness_count == y.witness_count;
  }
  for (std::size_t k = 0; same_detection && k < db.contacts.size(); ++k)
    same_detection = same2(da.contacts[k].point, db.contacts[k].point) && same_bits(da.contacts[k].gap, db.contacts[k].gap);
  if (!same_detection) failures.push_back("detection() differs from the serial detection");
  // The held floes at the last detection (Simulation::held_floes): the
  // rank's own and both floes of every pair whose floe a it owns, H the
  // same on every rank; serially every floe.
  const parallel::HeldFloes& held = ranks.held_floes();
  const std::span<const int> owner = ranks.floe_owners().owner();
  bool holds = held.mask.size() == n && (comm.serial() || owner.size() == n);  // one rank assigns no owners
  const auto owns = [&](std::size_t i) { return comm.serial() || owner[i] == comm.rank(); };
  for (std::size_t i = 0; holds && i < n; ++i) holds = !owns(i) || held.holds(i);
  for (const contact::NearPair& q : da.pairs)
    if (holds && owns(q.a)) holds = held.holds(q.a) && held.holds(q.b);
  if (!holds) failures.push_back("held_floes() misses an own floe or a floe of the rank's pairs");
  for (const double h : comm.allgather(std::span<const double>(&held.largest, 1)))
    if (!same_bits(h, held.largest)) failures.push_back("the ranks' H differ");
  if (serial.held_floes().index.size() != n) failures.push_back("the serial run does not hold every floe");
  if (comm.rank() == 0)
    std::printf("%d ranks: rank 0 holds %zu of %zu floes at the last detection (H = %.3f m)\n", comm.size(),
                held.index.size(), n, held.largest);
  if (db.contacts.empty()) failures.push_back("no contact point in the detection: a weak test");
  if (!strict_subset) failures.push_back("a rank owned no floe or every floe: the sums by owner were not tried");
  if (serial.collision_stats().lcps == 0) failures.push_back("no collision: a weak test");
  if (b.external.norm() == 0.0) failures.push_back("no external momentum: a weak test");
}
void check_bad_state(const parallel::Communicator& comm, std::vector<std::string>& failures) {
  const std::string text =
      "[run]\nt_end = 2.0\ndt_max = 0.5\n[sea]\nmodel = \"none\"\n"
      "[[floes.floe]]\nvertices = [[0, 900], [20, 900], [20, 920], [0, 920]]\n"
      "[[floes.floe]]\nvertices = [[0, 0], [20, 0], [20, 20], [0, 20]]\n"
      "[[floes.floe]]\nvertices = [[100, 0], [120, 0], [120, 20], [100, 20]]\n"
      "[[floes.floe]]\nvertices = [[100, 900], [120, 900], [120, 920], [100, 920]]\n"
      "[forcing]\nwind = [1e200, 0.0]\n";
  auto message = [&](const parallel::Communicator& c) {
    Simulation sim(build_scenario(parse_config(text, "overflow.toml", ".")), c);
    try {
      while (sim.time() < 2.0) sim.step(2.0);
    } catch (const RunError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  const std::string serial = message(parallel::Communicator{}), mine = message(comm);
  if (serial.find("floe 0: x is not finite") == std::string::npos)
    failures.push_back("the serial run's message does not name floe 0: " + serial);
  if (mine != serial) failures.push_back("the message is \"" + mine + "\", not the serial run's \"" + serial + "\"");
}
}  // namespace

int main() {
  parallel::Session session;
  return test::run_checks(session.world(), "exact sums equal to the serial sums, bit for bit", check_sums,
                          check_simulation, check_bad_state);
}
