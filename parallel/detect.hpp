#pragma once
// Contact detection (contact/detection.hpp) by place among the ranks (stage
// six of docs/parallel.md). Every rank holds every floe; rank r poses only
// its own floes (parallel::FloeOwners) and their halo, runs the broad phase
// on those, and measures the pairs whose floe a it owns
// (parallel::detection_subset). The ranks' lists are gathered (one message a
// rank: the counts and the three lists) and merged into the serial order:
// pairs by (a, b, shift), each pair's contact points and witnesses moved with
// it. Each pair is found once, on one rank, and measured by the same code on
// the same data, so the result is the serial one, field by field, on any
// number of ranks and whatever the strips.

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "contact/detection.hpp"
#include "parallel/comm.hpp"
#include "parallel/place.hpp"

namespace floesim::parallel {

// Collective: every rank calls it with the same floes, options and owners
// (assigned for these floes). options.subset is set here. Charges this
// rank's own work (its subset, pose, broad and narrow phases; not the
// gather) to `owners`, for the load balance.
contact::Detection detect(const Communicator& comm, FloeOwners& owners, const Floes& floes,
                          const contact::CollisionShapes& shapes, contact::DetectionOptions options,
                          contact::Detection* part = nullptr, bool whole = true, const HeldFloes* held = nullptr);
// (`part`, if not null, receives this rank's part: detect_part's. Serially, the whole detection.
// With `whole` false on several ranks (and `part` given) the parts are not
// gathered and the result is empty: the caller gathers later if it must.
// With `held`, this rank's held floes (held_floes), its subset reads only
// those: detection_subset.)

// The whole detection from every rank's part (each rank's detect_part, in
// pair order): the parts gathered to every rank (one allgather_bytes) and
// merged. Collective. The whole reach: each rank's part.reach holds the
// reaches of the floes it held at the detection (its own and its band's,
// Simulation::set_reach and parallel::announce_held), and sends those of
// `own`, the floes it owned then (12 bytes a floe), which partition the
// pack; a caller that reads no reach passes none (the reach is then this
// rank's, whole only where it holds every floe's).
contact::Detection gather(const Communicator& comm, const contact::Detection& part,
                          std::span<const std::uint32_t> own = {});

// The overlap check by parts (Simulation::detect_and_check): the first
// overlapping pair of a detection in pair order, and the distance at t of the
// last pair of those two floes in the previous detection (-1 m if none), as
// the serial scan of the whole lists finds them.
struct Overlap {
  bool any = false;
  std::uint32_t a = 0, b = 0;
  double before = -1.0;  // m
};
// A part's first overlapping pair as a key ordered as the pairs (a, b; the
// shift does not matter: only a and b are said), kNoOverlap if none.
inline constexpr long long kNoOverlap = 0x7fffffffffffffffLL;
long long overlap_key(const contact::Detection& part);
// The distance of the last pair (a, b) of `previous`, if it holds one.
bool distance_before(const contact::Detection& previous, std::uint32_t a, std::uint32_t b, double& distance);
// Collective: `part` this rank's part of the new detection, `previous` its
// part of the previous one (or the whole, the same on every rank). Every
// pair (a, b) of a detection is in the part of the owner of a at that
// detection, so the least key over the ranks is the serial first pair, and
// the rank that holds the previous pairs (a, b) holds all of them: the same
// answer on every rank. One reduction; one gather (16 bytes a rank) more
// only when a pair overlaps.
Overlap first_overlap(const Communicator& comm, const contact::Detection& part, const contact::Detection& previous);

// A detection's lists as one message (three counts, then the pairs, contact
// points and witnesses; the reach is not sent), and back.
std::vector<std::byte> pack(const contact::Detection& d);
contact::Detection unpack_detection(std::span<const std::byte> bytes);

// Pair p of `from` appended to `to` with its contact points and witnesses
// (first_contact and first_witness moved to where they now start in `to`).
void append_pair(contact::Detection& to, const contact::Detection& from, const contact::NearPair& p);

// The pairs of `d` (in its order) for which keep(pair) is true, with their
// contact points and witnesses.
template <class Keep>
contact::Detection select_pairs(const contact::Detection& d, Keep&& keep) {
  contact::Detection out;
  for (const contact::NearPair& p : d.pairs)
    if (keep(p)) append_pair(out, d, p);
  return out;
}

// The floes of routed pairs (docs/parallel.md, "The state held by owner
// with a halo", piece 2): what a share's solves read of a floe it need not
// hold (a step group's member or obstacle beyond its band; for the
// advance, a cluster's member, candidate or obstacle), sent with the pairs
// once a floe and receiver. Per floe, ascending: its present state (the
// collisions' W^-, the advance's start), its state at the step's start
// (the collisions only: `start` empty for the advance), its mass and yaw
// inertia: 212 bytes a floe (116 without `start`).
struct RoutedFloes {
  std::vector<std::uint32_t> floe;
  std::vector<FloeState> now, start;
  std::vector<double> mass, inertia_z;
};
// Both floes of every pair of `pairs`, as `floes` and `start` (if not
// empty) hold them.
RoutedFloes routed_floes(const Floes& floes, std::span<const FloeState> start, const contact::Detection& pairs);
// Writes `routed`'s floes into `floes` (state, mass, inertia) and, if it
// carries them, their states at the step's start into `start`.
void hold(const RoutedFloes& routed, Floes& floes, std::span<FloeState> start);
std::vector<std::byte> pack(const RoutedFloes& routed);
RoutedFloes unpack_routed_floes(std::span<const std::byte> bytes);

// What a routed pairs' message carries besides its pairs: packed pieces
// (each a pack(...) of the caller's: the floes' states, their shapes).
// `pieces` is the count per message with pairs, the same on every rank (the
// receiver reads that many); `outgoing[s]` the pieces for rank s (as many,
// when it gets pairs; else none); `received` is filled with the pieces of
// each message with pairs received, in rank order.
using Pieces = std::vector<std::vector<std::byte>>;
struct Carried {
  std::size_t pieces = 0;
  std::vector<Pieces> outgoing;
  std::vector<Pieces> received;
};

// One routed pairs' message: the byte counts (8 bytes each) of the pairs
// and of every piece but the last (none without pieces: the pairs alone),
// then the pairs (pack) and the pieces. unpack_routed reads `count` pieces
// into `pieces` and returns the pairs.
std::vector<std::byte> pack_routed(const contact::Detection& pairs, const Pieces& pieces);
contact::Detection unpack_routed(std::span<const std::byte> message, std::size_t count, Pieces& pieces);

// The routed pairs' exchange, the one framing of the collisions' and the
// advance's (collide_on_part, advance_on_part): `outgoing[s]` (pairs of
// this rank's part, in pair order) sent to rank s (none to itself; an empty
// one sends nothing) as one message (pack_routed), and `part` merged with
// what every rank sent here, in pair order (merge). Collective: one
// alltoall_bytes, two calls. With `carried`, each message with pairs
// carries its pieces too.
contact::Detection exchange_pairs(const Communicator& comm, const contact::Detection& part,
                                  const std::vector<contact::Detection>& outgoing, Carried* carried = nullptr);

// Rank `rank`'s part of the detection by place (no communication): the
// serial detection's pairs whose floe a `rank` owns, with their contact
// points and witnesses. With `held` (rank's held_floes) the subset reads
// only the held floes.
contact::Detection detect_part(const FloeOwners& owners, int rank, const Floes& floes,
                               const contact::CollisionShapes& shapes, contact::DetectionOptions options,
                               const HeldFloes* held = nullptr);

// The parts of one detection (each in pair order, no pair in two parts)
// merged into pair order: pairs, and each pair's contact points and
// witnesses, its first_contact and first_witness moved to where they now
// start. The reach is the first part's (every part has the whole reach).
contact::Detection merge(std::vector<contact::Detection> parts);

}  // namespace floesim::parallel
