#pragma once
// Stage seven (docs/parallel.md): the multirate advance of the floes by
// cluster owner. Each rank computes the rooms of the pairs whose lower floe
// it owns (FloeOwners, by place) and the ranks exchange the tight ones (room
// below xi); from those every rank finds the step's clusters, the same on
// every rank (contact/substep.hpp, "The set-up by share"); each cluster
// belongs to the owner of its lowest floe; each rank advances its own
// clusters and every free floe (linear motion), and the ranks then exchange
// the states of the floes their clusters moved (index + state) and their
// collision counts.
// A step where a rank's cluster met another rank's cluster or two ranks
// took the same free floe is tried again (from the rank's part) with those
// clusters joined on one rank (JoinedClusters); one where a share could not
// run alone (ShareOutcome::Conflict, the others) is advanced again whole on
// every rank from the step's states: the serial advance, so the answer is
// the serial one bit for bit either way.

#include <algorithm>
#include <cstddef>
#include <map>
#include <set>
#include <span>
#include <functional>
#include <string>
#include <vector>

#include "contact/substep.hpp"
#include "parallel/comm.hpp"
#include "parallel/detect.hpp"

namespace floesim::parallel {

// What a step that reads every floe asks of its caller, on demand, in the
// step that needs it (the halo plan's piece 3: the pair list's rebuild on a
// part, a fallback, a step the back-off does whole). Both are collective:
// every rank calls them at the same point of the same step, or none does.
// `detection`: the whole detection's lists (gathered once a detection).
// `state(what)`: every floe's state (WholeState::state), or its state and
// the step's start copy (WholeState::state_and_start), current on this
// rank, from the floes' owners: each path names what it reads. Until the
// halo exchange (piece 8) every rank holds every floe current after the
// drift and `state` does nothing; with the exchange (and in the poison mode
// of the run, which leaves the floes a rank does not hold stale as the
// exchange will) it gathers the floes the rank does not hold
// (Simulation::whole_state): the state and start once in a step, the state
// alone (half the bytes) each time it is asked for.
enum class WholeState {
  state,            // the state: the advance's rebuild, fallback and whole step
  state_and_start,  // and the step-start copy: the collide's fallback and whole step
};
struct WholeOnDemand {
  std::function<const contact::Detection&()> detection;
  std::function<void(WholeState)> state;
};

// One rank's part of a step's advance: what its share did, the states of the
// floes it moved (outcome.moved's order), its counts and, in a run that keeps
// the impulse record, its record (events: outcome.events; none on a conflict).
struct AdvancePart {
  contact::ShareOutcome outcome;
  std::vector<FloeState> states;
  contact::CollisionStats stats;
  contact::SubstepReport report;
  contact::ImpulseRecord record;
};

// A share's impulse record in a message (the loads, field by field, then the
// event count), appended to `out`; read back by take_record, which moves `in`
// past it.
void append_record(std::vector<std::byte>& out, const contact::ImpulseRecord& record);
contact::ImpulseRecord take_record(const std::byte*& in);

// A share's warm-store writes in a message (contact::WarmStart::Written:
// ShareOutcome::warm, StepCollisionShare::warm; and the uses: the pairs'
// count, the uses, then per pair its key, clock, entries' count and
// entries, 37 bytes each), appended to `out`; read back by take_warm, which
// moves `in` past them. Written into a store by hold_warm (each pair
// replaced, the uses added).
void append_warm(std::vector<std::byte>& out, const contact::WarmStart::Written& pairs, long uses);
contact::WarmStart::Written take_warm(const std::byte*& in, long& uses);
void hold_warm(const contact::WarmStart::Written& pairs, long uses, contact::WarmStart& store);

std::vector<std::byte> pack(const AdvancePart& part);
AdvancePart unpack_advance_part(std::span<const std::byte> bytes);

// The first exchange: a share's tight pairs and contact edges
// (contact::ShareRooms), 56 bytes a tight or near pair (a, b, shift, room,
// the floes' reach less travel, their owners) and 16 an edge (a, b, their
// owners) after a header (conflict, outrun, the two counts: 32 bytes).
std::vector<std::byte> pack(const contact::ShareRooms& rooms);
contact::ShareRooms unpack_share_rooms(std::span<const std::byte> bytes);

// Every rank's tight pairs and contact edges (rank order) as one list each
// for ShareAdvance::advance; false, leaving `all` unspecified, when a rank's
// set-up had a conflict.
bool combine_rooms(std::span<const contact::ShareRooms> parts, contact::ShareRooms& all);

// The second half of a rank's share (ShareAdvance::advance, given every
// rank's tight pairs) and its part; `floes` (the share's floes) is left with
// the share's states. `record`: the share's impulse record (the one its
// options point at; null: none), moved into the part.
AdvancePart finish_share(contact::ShareAdvance& share, const contact::ShareRooms& all, const Floes& floes,
                         contact::ImpulseRecord* record = nullptr);
// The same from the share's outcome (a share on a part: ShareAdvance::advance()).
AdvancePart share_part(const contact::ShareAdvance& share, contact::ShareOutcome outcome, const Floes& floes,
                       contact::ImpulseRecord* record = nullptr);

// On a part: the pairs of `part` that `routes` (ShareAdvance::clusters) sends
// to each of `ranks` ranks (none to itself).
std::vector<contact::Detection> routed_pairs(const contact::Detection& part,
                                             std::span<const std::pair<int, std::uint32_t>> routes, int ranks);

// Whether a gathered share's set-up said a floe of its own would outrun
// its reach (contact::ShareRooms::outrun): then every rank rebuilds.
bool any_outrun(std::span<const contact::ShareRooms> rooms);

// Until the halo exchange (docs/parallel.md, the halo plan's piece 8) every
// rank holds every floe: the dynamic floes not in `held` (ascending: the
// share's held floes, ShareAdvance::held), which the share did not move,
// put at the end of the step on their straight paths from the state they
// hold (the step's start), as their holders' shares move them when free
// (the same formula, the same bits). Those a cluster moved come in the
// parts (combine_parts, after this). Piece 8 replaces this pass: each rank
// then holds only its floes and its band.
void move_not_held(Floes& floes, std::span<const std::uint32_t> held, double dt);

// What the advance's sub-steps read of a routed pair's floe besides its
// state, mass and inertia (parallel::RoutedFloes): its collision shape (the
// members and obstacles are posed and measured) and its reach (a member's
// reach left, reach less its straight travel). Sent with the routed floes,
// in the same order, once a floe and receiver: 4 + 8 + 8 + 4 bytes a floe,
// 4 a part and 16 a vertex.
struct RoutedShapes {
  std::vector<std::uint32_t> floe;  // ascending (RoutedFloes::floe)
  std::vector<double> radius, reach;
  std::vector<std::uint32_t> parts;     // per floe: its parts
  std::vector<std::uint32_t> vertices;  // per part: its vertices
  std::vector<Vec2> vertex;             // m, body frame
};
RoutedShapes routed_shapes(const contact::CollisionShapes& shapes, std::span<const double> reach,
                           std::span<const std::uint32_t> floes);
// Writes the shapes into `shapes` and the reaches into `reach`: a floe
// whose parts `shapes` holds has them overwritten in place (the same bits
// as its sender's, which built them from the same vertices), a floe whose
// parts it does not hold (held by band, contact/shapes.hpp) gets them
// appended.
void hold(const RoutedShapes& routed, contact::CollisionShapes& shapes, std::span<double> reach);
std::vector<std::byte> pack(const RoutedShapes& routed);
RoutedShapes unpack_routed_shapes(std::span<const std::byte> bytes);

// The advance's routed pairs' exchange (parallel::exchange_pairs, with two
// pieces: the floes' states, RoutedFloes, and shapes, RoutedShapes):
// `outgoing[s]` (pairs of this rank's part, in pair order) to rank s with
// the states and shapes of their floes as `floes`, `shapes` and
// `part.reach` hold them; the floes received written into `floes`,
// `shapes` and the returned list's reach (hold), which is `part` merged
// with the pairs received, in pair order. Collective: one alltoall_bytes,
// two calls. `shape_bytes` adds the shapes' bytes this rank sent.
contact::Detection exchange_advance_pairs(const Communicator& comm, const contact::Detection& part,
                                          const std::vector<contact::Detection>& outgoing, Floes& floes,
                                          contact::CollisionShapes& shapes, long* shape_bytes = nullptr);

// Throws RunError, naming the lowest such rank and its floe, when a part
// says a routed floe came to it without its state, mass, shape or reach
// (contact::ShareOutcome::Conflict::missing_floe): a fault of the routing,
// not a fallback. Every rank reads the same parts and throws the same.
void check_routed_floes(std::span<const AdvancePart> parts);

// Combines every rank's part (rank order) into `floes` (each rank's moved
// floes get its states; the free floes are already at the end of the step on
// every rank), `stats`, `report`, `record` (if not null: the parts'
// records merged in the serial order, contact::merge_advance_record) and
// `warm` (if not null: the run's warm store, every part's stored pairs
// written into it, hold_warm), and returns true; or returns false,
// changing nothing, when a part has a conflict, two parts moved one floe
// or stored one warm pair.
bool combine_parts(std::span<const AdvancePart> parts, Floes& floes, contact::CollisionStats& stats,
                   contact::SubstepReport& report, contact::ImpulseRecord* record = nullptr,
                   contact::WarmStart* warm = nullptr);

// A step redone whole costs the share's work and the whole advance; packs
// where ranks' clusters keep meeting (a jam across strips, a jam whose LCP
// uses the warm store) would pay it at every step. So after a fallback the
// next `wait` advances are whole at once (no share, no gather); `wait` is 1
// after the first fallback and doubles with each fallback in a row, up to
// max_wait; a combined advance resets it. Every rank sees the same
// fallbacks, so all agree on the steps they skip (same collective calls).
// Either way the answer is the serial one.
struct AdvanceShareOptions {
  long max_wait = 64;
  // Simulation: advance from the rank's part of the detection
  // (advance_on_part) rather than from the whole (advance_by_owner);
  // [run] advance_on_part. On by default: with the join candidates routed it
  // combines as often as from the whole (docs/parallel.md, "The advance from
  // the rank's part").
  bool on_part = true;
  // From the rank's part: the tries of a step, the first included, before
  // the whole advance, where a try's conflicts are clusters of two runners
  // meeting (JoinedClusters). Each try joins more clusters; on the wall jam
  // of examples/pack_against_wall.toml every such step combined by its
  // second or third (docs/parallel.md, "The conflicting clusters on one rank").
  int max_rounds = 8;
};

// How the advances by cluster owner went (the run's summary), and the
// back-off's state. The collisions at the step's start by owner
// (collide_share.hpp) keep their own, with the same back-off.
struct AdvanceShareCounts {
  long steps = 0;               // advances tried by owner
  long fallbacks = 0;           // of those, redone whole
  long whole = 0;               // advances done whole at once by the back-off
  std::vector<long> clusters;   // per rank: clusters it ran (steps not redone)
  std::vector<long> rooms;      // per rank: pair rooms it computed (steps not redone)
  long pairs = 0;               // pairs in those steps (a replicated set-up computes every one's room)
  // From the rank's part (advance_on_part): the tries redone because a free
  // floe joined a cluster without being its candidate (missing_pairs), the
  // tries with a jam-sized cluster (its pad edges gathered), and the join
  // candidates gathered over the tries (contact::JoinCandidate).
  long missing = 0;
  long pads = 0;
  long candidates = 0;
  // From the rank's part: the tries where a floe would outrun its reach
  // (every rank rebuilt the pair list and gathered the rooms again).
  long rebuilds = 0;
  // From the rank's part: the bytes of the collision shapes and reaches
  // this rank sent with its routed pairs' floes (RoutedShapes).
  long shape_bytes = 0;
  // From the rank's part: the steps whose first try met clusters of two
  // runners and which combined in a later try with those clusters joined on
  // one rank (not counted in `fallbacks`), and the tries made again for
  // them (JoinedClusters).
  long joined = 0;
  long rounds = 0;
  long kept = 0;  // of those tries again, the ones where this rank kept its part (no share run)
  // The tries that fell back, by what made them (the run's summary, one
  // line a kind): each try counts once under each kind that some part of
  // its last try (or its set-up) said, so the kinds may sum to more than
  // the fallbacks. A try whose meeting clusters were joined and then
  // combined counts in `joined` only.
  // The advance's kinds: the names of contact::ShareOutcome::Conflict
  // (conflict_name), the collisions' those of
  // contact::StepCollisionShare::Conflict, and for both `taken_twice` and
  // `stored_twice`, which no part can see (parallel/refusals.hpp).
  std::map<std::string, long> conflicts;
  long wait = 0;                // advances still to do whole
  long next_wait = 1;           // the wait after the next fallback

  // The back-off above. True (and counted in `whole`) when this step is to
  // be done whole at once; else the step is tried by owner (counted).
  bool whole_now() {
    if (wait > 0) {
      --wait;
      ++whole;
      return true;
    }
    ++steps;
    return false;
  }
  // The step tried by owner combined: the next fallback waits 1 again.
  void combined() { next_wait = 1; }
  // The step tried by owner fell back: wait, then double the next wait.
  void fell_back(const AdvanceShareOptions& o) {
    ++fallbacks;
    wait = next_wait;
    next_wait = std::min(2 * next_wait, o.max_wait);
  }
};

// The conflicting clusters on one rank (docs/parallel.md, "The conflicting
// clusters on one rank (onerank26)"). After a try whose parts refused to
// combine only because clusters of different runners would have merged
// (foreign_cluster: ShareOutcome::met) or taken one free floe (a floe two
// parts moved), add() joins those clusters, with the clusters each share
// had merged into them (ShareOutcome::merged), into groups, each run by the
// runner of its lowest cluster as `share` (that try's) ran it: runners()
// (ClusterShare::runners) for the next try. The groups only grow from try
// to try. Every rank reads the same parts and the same runners: the same
// groups. False, changing nothing, when a part had another conflict (or no
// clusters to join): the whole advance.
class JoinedClusters {
public:
  bool add(std::span<const AdvancePart> parts, const contact::ShareAdvance& share);
  std::span<const std::pair<std::int32_t, std::int32_t>> runners() const { return runners_; }

private:
  std::int32_t find(std::int32_t k);
  void unite(std::int32_t a, std::int32_t b);
  std::map<std::int32_t, std::int32_t> parent_;  // union-find over the clusters named so far
  std::set<std::int32_t> joined_;                // clusters of a conflict
  std::vector<std::pair<std::int32_t, std::int32_t>> runners_;  // (cluster, rank), ascending
};

// The name of a share's conflict as the summary prints it
// (parallel.advance_conflicts.NAME): the enumerator's.
const char* conflict_name(contact::ShareOutcome::Conflict conflict);
// The kinds of conflict a tried step's parts (rank order) say, each once,
// counted into `counts.conflicts` (parallel/refusals.hpp: the rule that
// combine_parts refuses by). A step whose parts combine counts nothing.
void count_conflicts(std::span<const AdvancePart> parts, AdvanceShareCounts& counts);

// The step's advance on every rank of `comm` (or whole, while the back-off
// above waits): this rank's share's set-up (its pairs' rooms), the exchange
// of the tight pairs, the share's advance, the exchange of the parts (each
// exchange one allgather_bytes: two collective calls on every rank), then
// the combination or, on a conflict, the whole advance
// (contact::advance_with_collisions) from the states on entry. A conflict in
// a set-up is known to every rank after the first exchange: every rank then
// skips the second. With options.impulse.record, each share records into
// a record of its own, sent in its part, and every rank merges the parts
// into options.impulse.record in the serial order (contact::RecordPart); on
// a fallback the whole advance records into it. Equal to the serial advance
// bit for bit, states, counts and record.
void advance_by_owner(const Communicator& comm, std::span<const int> owner, Floes& floes,
                      const contact::CollisionShapes& shapes, const contact::Detection& detection, double dt,
                      const contact::SubstepOptions& options, contact::CollisionStats& stats,
                      contact::SubstepReport& report, AdvanceShareCounts& counts,
                      const AdvanceShareOptions& share_options = {});

// The same from this rank's part of the detection (parallel::detect's part,
// docs/parallel.md "The advance from the rank's part"): the share's set-up
// on its part (every pair of the part its own; the straight paths of the
// floes it holds: `mine`, the rank's floes by place, ascending, and its
// pairs'), the exchange of the tight
// and near pairs and contact edges, the clusters (with every rank's pad
// edges gathered first when a cluster is jam-sized), then, when the step has
// a cluster, the gather of every rank's join candidates and the pairs
// touching each cluster's members or candidates sent to its runner (one
// alltoall_bytes: two collective calls), the share's advance on its part
// and the pairs received (it moves the free floes it holds;
// move_not_held the others, until piece 8), the exchange of the parts. A
// floe of any rank outrunning its reach (the flags gathered with the rooms)
// makes every rank rebuild the pair list and gather the rooms again (one
// more allgather_bytes in such a step); the rebuild reads every floe's
// state at the step's start and its reach: `whole.state` (the state alone,
// WholeState::state) first, then the
// reaches from their owners. `whole` gives the whole state and detection
// for the back-off's whole steps and the fallback (state first), which is
// taken also when a floe joins a share's cluster without being its
// candidate (Conflict::missing_pairs). A try whose only conflicts are
// clusters of two runners meeting is made again from the step's start with
// those clusters joined on one rank (JoinedClusters; the rooms and edges
// of the first try; up to share_options.max_rounds tries, each its
// candidates, routed pairs and parts exchanged again). With
// options.impulse.record the shares record and merge as in
// advance_by_owner. Equal to the serial advance bit for bit, states,
// counts, record and warm store.
void advance_on_part(const Communicator& comm, std::span<const int> owner, std::span<const std::uint32_t> mine,
                     Floes& floes, contact::CollisionShapes& shapes, const contact::Detection& part,
                     const WholeOnDemand& whole, double dt,
                     const contact::SubstepOptions& options, contact::CollisionStats& stats,
                     contact::SubstepReport& report, AdvanceShareCounts& counts,
                     const AdvanceShareOptions& share_options = {});

}  // namespace floesim::parallel
