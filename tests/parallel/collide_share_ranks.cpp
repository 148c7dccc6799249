// The collisions at the step's start by owner (parallel::collide_by_owner,
// stage seven) over the ranks mpirun starts: the rows of four floes of
// collide_case.hpp (each row one step group: two contact components that a
// speculative contact joins), owned by place (FloeOwners, equal strips), solved by
// each rank's share and one exchange. Every rank's floes and counts must
// equal the serial solve (resolve_step_collisions on every rank's own copy)
// bit for bit: first kept (on several ranks: tried once, no fallback, groups
// solved on every rank), then with every LCP on the warm store (warm_min =
// 0): kept too, each share on a copy of the store and every rank's store
// left as the serial solve leaves its own, entry by entry; then the same
// under the test hook (CollideShareOptions::warm_conflict), which falls back
// on every rank alike and is the serial solve and store again.
// Both from the whole detection (collide_by_owner) and from each rank's
// part of it, the pairs whose floe a it owns (parallel::collide_on_part:
// the edges gathered, the groups' pairs sent to their owners, the whole
// detection gathered only for the fallback). Last, a step with no step
// group: the serial answer with at most two collective calls.
// Run by ctest as mpi.collide_share_ranks_N under `mpirun --oversubscribe
// -np N` (N = 1, 2, 3), and serially without MPI.
#include <algorithm>
#include <cstdio>
#include <cstring>
#include <map>
#include <string>
#include <vector>

#include "parallel/collide_share.hpp"
#include "parallel/comm.hpp"
#include "parallel/detect.hpp"
#include "parallel/place.hpp"
#include "tests/parallel/collide_case.hpp"
#include "tests/parallel/ranks_main.hpp"
#include "tests/parallel/same_detection.hpp"

using namespace floesim;

int main() {
  parallel::Session session;
  const parallel::Communicator& comm = session.world();
  const int ranks = comm.size();
  std::vector<std::string> failures;
  const test::CollideCase c = test::rows_of_four(3);
  parallel::FloeOwners owners(comm.rank(), ranks, c.domain);
  owners.assign(c.floes);
  const contact::Detection part = parallel::select_pairs(
      c.detection, [&](const contact::NearPair& p) { return owners.owner()[p.a] == comm.rank(); });
  enum class Mode { cold, warm, hooked };  // no store use; the store; the store under the test hook
  for (const bool on_part : {false, true})
  for (const Mode mode : {Mode::cold, Mode::warm, Mode::hooked}) {
    const bool warm = mode != Mode::cold, falls = mode == Mode::hooked;
    const std::string name = std::string(on_part ? "on the rank's part: " : "") +
                             (warm ? (falls ? "warm store, the hook: " : "warm store: ") : "");
    contact::ImpulseOptions o = c.options;
    contact::WarmStart serial_warm, shared_warm;
    if (warm) o.warm_min = 0;
    parallel::CollideShareOptions share;
    share.warm_conflict = falls;
    Floes s = c.floes, f = c.floes;
    contact::CollisionStats ss, fs;
    contact::ImpulseOptions so = o, fo = o;
    so.warm = &serial_warm;
    fo.warm = &shared_warm;
    const std::size_t a = contact::resolve_step_collisions(s, c.start, c.detection, c.dt, so, ss);
    parallel::AdvanceShareCounts counts;
    const std::size_t b =
        on_part ? parallel::collide_on_part(comm, owners.owner(), f, c.start, part, c.dt, fo, fs, counts, share)
                : parallel::collide_by_owner(comm, owners.owner(), f, c.start, c.detection, c.dt, fo, fs, counts,
                                             share);
    if (std::memcmp(f.state.data(), s.state.data(), f.state.size() * sizeof(FloeState)) != 0)
      failures.push_back(name + "the floes differ from the serial solve");
    if (!test::same_stats(fs, ss)) failures.push_back(name + "the collision counts differ from the serial solve");
    if (a != b) failures.push_back(name + "the speculative contacts' count differs");
    if (ss.lcps < 64 || a == 0) failures.push_back(name + "too few LCPs or no speculative contact: no test");
    if (counts.steps != 1 || counts.fallbacks != (falls ? 1 : 0))
      failures.push_back(name + "expected 1 try and " + std::to_string(falls ? 1 : 0) + " fallback, got " +
                         std::to_string(counts.steps) + " and " + std::to_string(counts.fallbacks));
    if (falls && counts.conflicts != std::map<std::string, long>{{"warm_start", 1}})
      failures.push_back(name + "the fallback was not counted as the hook's warm_start");
    if (!test::same_store(shared_warm, serial_warm))
      failures.push_back(name + "the warm store differs from the serial solve's");
    if (warm && serial_warm.pairs.empty()) failures.push_back(name + "no warm pair stored: no test");
    long busy = 0;  // ranks that solved groups
    for (const long g : counts.clusters) busy += g > 0 ? 1 : 0;
    if (!falls && busy != ranks) failures.push_back(name + "not every rank solved step groups");
    if (comm.writer()) {
      std::printf("%s%d ranks: %ld LCPs, %zu speculative contacts, fallbacks %ld, groups by rank:", name.c_str(),
                  ranks, ss.lcps, a, counts.fallbacks);
      for (const long g : counts.clusters) std::printf(" %ld", g);
      std::printf("\n");
    }
  }
  {
    // At rest and without the contacts' pairs (the witnesses only): no step
    // group on any rank. Nothing changes, as the serial solve, and the ranks
    // skip the exchanges: the edges' counts are the only call (a second, the
    // edges, when a rank has one), where a step with groups makes six.
    Floes s = c.floes, f = c.floes;
    std::vector<FloeState> start = c.start;
    for (std::vector<FloeState>* v : {&s.state, &f.state, &start})
      for (FloeState& x : *v) x.vx = x.vy = x.yaw_rate = 0.0;
    auto untouched = [](const contact::NearPair& p) { return p.contact_count == 0; };
    const contact::Detection whole = parallel::select_pairs(c.detection, untouched);
    const contact::Detection rest = parallel::select_pairs(part, untouched);
    contact::CollisionStats ss, fs;
    contact::ImpulseOptions so = c.options, fo = c.options;
    const std::size_t a = contact::resolve_step_collisions(s, start, whole, c.dt, so, ss);
    parallel::AdvanceShareCounts counts;
    const long long calls = comm.traffic().calls;
    const std::size_t b = parallel::collide_on_part(comm, owners.owner(), f, start, rest, c.dt, fo, fs, counts);
    const long long made = comm.traffic().calls - calls;
    if (std::memcmp(f.state.data(), s.state.data(), f.state.size() * sizeof(FloeState)) != 0 || a != b ||
        !test::same_stats(fs, ss))
      failures.push_back("no step group: the floes or counts differ from the serial solve");
    if (whole.pairs.empty() || ss.lcps != 0) failures.push_back("no step group: no witnesses, or an LCP: no test");
    if (ranks > 1 && made > 2)
      failures.push_back("no step group: " + std::to_string(made) + " collective calls, at most 2 expected");
    if (comm.writer())
      std::printf("no step group, %d ranks: %zu pairs, %lld collective calls\n", ranks, whole.pairs.size(), made);
  }
  {
    // The routed pairs' exchange itself (parallel::exchange_pairs, the
    // collisions' and the advance's one framing), with 0, 1 and 2 pieces a
    // message: rank r sends rank s != r the pairs of its part with
    // (a + b) mod ranks = s, with pieces that name (r, s, k). Every rank must get its part
    // merged with every pair sent to it, in pair order (a pair once), and
    // from each sender with pairs for it, in rank order, its pieces.
    for (std::size_t count = 0; count <= 2; ++count) {
      std::vector<contact::Detection> out(static_cast<std::size_t>(ranks));
      parallel::Carried carried{count, std::vector<parallel::Pieces>(out.size()), {}};
      const auto piece = [&](int from, int to, std::size_t k) {
        std::vector<std::byte> b(3 * k + 2, static_cast<std::byte>(16 * from + to));
        b.back() = static_cast<std::byte>(k);
        return b;
      };
      const auto to = [&](const contact::NearPair& p) { return static_cast<int>((p.a + p.b) % ranks); };
      for (int s = 0; s < ranks; ++s) {
        if (s == comm.rank()) continue;
        const auto su = static_cast<std::size_t>(s);
        out[su] = parallel::select_pairs(part, [&](const contact::NearPair& p) { return to(p) == s; });
        if (!out[su].pairs.empty())
          for (std::size_t k = 0; k < count; ++k) carried.outgoing[su].push_back(piece(comm.rank(), s, k));
      }
      const contact::Detection got = parallel::exchange_pairs(comm, part, out, count > 0 ? &carried : nullptr);
      // Expected: this rank's part and, from every other rank, its part's
      // pairs sent here (the whole detection's, selected).
      const contact::Detection want = parallel::select_pairs(c.detection, [&](const contact::NearPair& p) {
        return owners.owner()[p.a] == comm.rank() || to(p) == comm.rank();
      });
      if (!test::same_lists(got.pairs, want.pairs) || !test::same_lists(got.contacts, want.contacts) ||
          !test::same_lists(got.witnesses, want.witnesses) || got.reach != part.reach)
        failures.push_back("exchange_pairs with " + std::to_string(count) + " pieces: the pairs held differ");
      std::vector<parallel::Pieces> expected;
      for (int r = 0; r < ranks && count > 0; ++r) {
        const bool sends = r != comm.rank() && std::any_of(c.detection.pairs.begin(), c.detection.pairs.end(),
                                                           [&](const contact::NearPair& p) {
                                                             return owners.owner()[p.a] == r && to(p) == comm.rank();
                                                           });
        if (!sends) continue;
        expected.emplace_back();
        for (std::size_t k = 0; k < count; ++k) expected.back().push_back(piece(r, comm.rank(), k));
      }
      if (count > 0 && carried.received != expected)
        failures.push_back("exchange_pairs with " + std::to_string(count) + " pieces: the pieces received differ");
      if (ranks > 1 && count == 2 && comm.sum(static_cast<long long>(carried.received.size())) == 0)
        failures.push_back("exchange_pairs: no pair crossed a cut: no test");
    }
  }
  return test::verdict(comm, failures, "the step groups' solves equal the serial solve");
}
