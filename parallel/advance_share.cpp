// The advance by cluster owner (parallel/advance_share.hpp): the drivers
// (advance_by_owner, advance_on_part) and the combination of the ranks'
// rooms and parts. The messages' bytes are advance_pack.cpp's, the routed
// pairs and shapes advance_routed.cpp's, the joined clusters
// advance_joined.cpp's.
#include "parallel/advance_share.hpp"

#include <algorithm>
#include <optional>
#include <string>
#include <utility>

#include "core/error.hpp"
#include "parallel/refusals.hpp"

namespace floesim::parallel {

namespace {

using contact::CollisionStats;
using contact::ShareOutcome;
using contact::SubstepReport;

}  // namespace

bool combine_rooms(std::span<const contact::ShareRooms> parts, contact::ShareRooms& all) {
  all.tight.clear();
  all.touching.clear();
  for (const contact::ShareRooms& p : parts) {
    if (p.conflict != ShareOutcome::Conflict::none) return false;
    all.tight.insert(all.tight.end(), p.tight.begin(), p.tight.end());
    all.touching.insert(all.touching.end(), p.touching.begin(), p.touching.end());
  }
  return true;
}

AdvancePart finish_share(contact::ShareAdvance& share, const contact::ShareRooms& all, const Floes& floes,
                         contact::ImpulseRecord* record) {
  return share_part(share, share.advance(all), floes, record);
}

AdvancePart share_part(const contact::ShareAdvance& share, contact::ShareOutcome outcome, const Floes& floes,
                       contact::ImpulseRecord* record) {
  AdvancePart part;
  part.outcome = std::move(outcome);
  part.stats = share.stats();
  part.report = share.report();
  if (part.outcome.conflict == ShareOutcome::Conflict::none) {
    for (const std::uint32_t i : part.outcome.moved) part.states.push_back(floes.state[i]);
    if (record) part.record = std::move(*record);
  } else {
    part.outcome.events.clear();
    part.outcome.warm.clear();
    part.outcome.warm_uses = 0;
  }
  return part;
}

const char* conflict_name(contact::ShareOutcome::Conflict conflict) {
  using C = contact::ShareOutcome::Conflict;
  switch (conflict) {
    case C::none: return "none";
    case C::foreign_cluster: return "foreign_cluster";
    case C::failed_lcp: return "failed_lcp";
    case C::error: return "error";
    case C::missing_pairs: return "missing_pairs";
    case C::missing_floe: return "missing_floe";
  }
  return "unknown";
}

namespace {
const char* refused_name(contact::ShareOutcome::Conflict conflict) {
  return conflict == ShareOutcome::Conflict::none ? nullptr : conflict_name(conflict);
}
}  // namespace

void count_conflicts(std::span<const AdvancePart> parts, AdvanceShareCounts& counts) {
  for (const std::string& k : refusals(parts, refused_name)) ++counts.conflicts[k];
}

// A set-up's conflicts (the gathered rooms' flags), each kind once.
static void count_set_up(std::span<const contact::ShareRooms> rooms, AdvanceShareCounts& counts) {
  std::vector<AdvancePart> parts(rooms.size());
  for (std::size_t r = 0; r < rooms.size(); ++r) parts[r].outcome.conflict = rooms[r].conflict;
  count_conflicts(parts, counts);
}

bool combine_parts(std::span<const AdvancePart> parts, Floes& floes, CollisionStats& stats, SubstepReport& report,
                   contact::ImpulseRecord* record, contact::WarmStart* warm) {
  if (!refusals(parts, refused_name).empty()) return false;
  if (warm)
    for (const AdvancePart& p : parts) hold_warm(p.outcome.warm, p.outcome.warm_uses, *warm);
  for (const AdvancePart& p : parts)
    for (std::size_t j = 0; j < p.states.size(); ++j) floes.state[p.outcome.moved[j]] = p.states[j];
  // Counts: sums, but the largest LCP and cluster (maxima) and the pair
  // list's rebuild, which every share did alike (taken once).
  const AdvancePart* floor = nullptr;
  for (const AdvancePart& p : parts) {
    contact::add_collision_counts(stats, p.stats);
    const auto rto = contact::substep_counts(report);
    const auto rfrom = contact::substep_counts(p.report);
    for (std::size_t k = 0; k < rto.size(); ++k) {
      if (rfrom[k].second == &p.report.rebuilt) continue;
      *rto[k].second = rfrom[k].second == &p.report.largest_cluster ? std::max(*rto[k].second, *rfrom[k].second)
                                                                    : *rto[k].second + *rfrom[k].second;
    }
    // The serial queue's last floor step: the largest key (tau, cluster).
    if (p.report.floor_steps > 0 &&
        (!floor || std::pair(p.outcome.floor_tau, p.outcome.floor_cluster) >
                       std::pair(floor->outcome.floor_tau, floor->outcome.floor_cluster)))
      floor = &p;
  }
  if (!parts.empty()) report.rebuilt += parts.front().report.rebuilt;
  if (floor) report.floor_pair = floor->report.floor_pair;
  if (record) {
    std::vector<contact::RecordPart> records;
    for (const AdvancePart& p : parts) records.push_back({&p.record, {}, p.outcome.events});
    contact::merge_advance_record(*record, records);
  }
  return true;
}

namespace {

// Which lists the parts' `outcome.pairs` count (each share's set-up
// counts the pairs of the list it saw): one list every share saw whole
// (the whole detection, or the list every rank rebuilt over every floe
// when a floe outran its reach), which every part counts alike, so the
// step's pairs are one part's; or each rank's own part of the detection,
// disjoint parts of the list, so the step's pairs are their sum.
enum class PairLists { whole_on_every_rank, one_part_a_rank };

struct Gathered {
  std::vector<AdvancePart> parts;  // every rank's, rank order
  bool combined = false;           // combine_parts took them
};

// Every rank's part (one allgather_bytes), then, a routed floe that came
// incomplete being a fault (check_routed_floes), their combination
// (combine_parts); when they combine, each rank's clusters and rooms and
// the step's pairs (by `lists`) are counted. On a conflict nothing is
// counted: the caller counts it, or tries again.
Gathered gather_and_combine(const Communicator& comm, const AdvancePart& mine, PairLists lists, Floes& floes,
                            CollisionStats& stats, SubstepReport& report, contact::ImpulseRecord* record,
                            contact::WarmStart* warm, AdvanceShareCounts& counts) {
  Gathered g;
  g.parts = comm.allgather_parts(pack(mine), unpack_advance_part);
  check_routed_floes(g.parts);
  counts.clusters.resize(g.parts.size(), 0);
  counts.rooms.resize(g.parts.size(), 0);
  g.combined = combine_parts(g.parts, floes, stats, report, record, warm);
  if (!g.combined) return g;
  for (std::size_t r = 0; r < g.parts.size(); ++r) {
    counts.clusters[r] += g.parts[r].outcome.clusters;
    counts.rooms[r] += g.parts[r].outcome.rooms;
    if (lists == PairLists::one_part_a_rank || r == 0) counts.pairs += g.parts[r].outcome.pairs;
  }
  return g;
}

}  // namespace

void advance_by_owner(const Communicator& comm, std::span<const int> owner, Floes& floes,
                      const contact::CollisionShapes& shapes, const contact::Detection& detection, double dt,
                      const contact::SubstepOptions& options, contact::CollisionStats& stats,
                      contact::SubstepReport& report, AdvanceShareCounts& counts,
                      const AdvanceShareOptions& share_options) {
  if (counts.whole_now()) {
    contact::advance_with_collisions(floes, shapes, detection, dt, options, stats, report);
    return;
  }
  const std::vector<FloeState> start = floes.state;
  bool combined = false;
  {
    // A run that keeps the impulse record: the share records into its own
    // (sent in its part), and every rank merges the parts in the serial order.
    contact::ImpulseRecord* const record = options.impulse.record;
    contact::ImpulseRecord own;
    contact::SubstepOptions own_options = options;
    if (record) own_options.impulse.record = &own;
    // The set-up by share, then the exchange of the tight pairs.
    contact::ShareAdvance share(floes, shapes, detection, dt, own_options, {owner, comm.rank()});
    const std::vector<contact::ShareRooms> rooms = comm.allgather_parts(pack(share.rooms()), unpack_share_rooms);
    contact::ShareRooms all;
    // Every rank sees the same gathered conflicts: all skip the second
    // exchange alike.
    if (combine_rooms(rooms, all)) {
      const AdvancePart mine = finish_share(share, all, floes, record ? &own : nullptr);
      const Gathered g = gather_and_combine(comm, mine, PairLists::whole_on_every_rank, floes, stats, report,
                                            record, options.impulse.warm, counts);
      combined = g.combined;
      if (!combined) count_conflicts(g.parts, counts);
    } else {
      count_set_up(rooms, counts);
    }
  }
  if (combined) {
    counts.combined();
    return;
  }
  // A conflict: the whole advance from the step's states, as the serial run.
  counts.fell_back(share_options);
  floes.state = start;
  contact::advance_with_collisions(floes, shapes, detection, dt, options, stats, report);
}

bool any_outrun(std::span<const contact::ShareRooms> rooms) {
  return std::any_of(rooms.begin(), rooms.end(), [](const contact::ShareRooms& r) { return r.outrun; });
}

void advance_on_part(const Communicator& comm, std::span<const int> owner, std::span<const std::uint32_t> mine,
                     Floes& floes, contact::CollisionShapes& shapes, const contact::Detection& part,
                     const WholeOnDemand& whole, double dt,
                     const contact::SubstepOptions& options, contact::CollisionStats& stats,
                     contact::SubstepReport& report, AdvanceShareCounts& counts,
                     const AdvanceShareOptions& share_options) {
  if (comm.serial())
    return advance_by_owner(comm, owner, floes, shapes, whole.detection(), dt, options, stats, report, counts,
                            share_options);
  // The advance reads the floes' states (W^+ of the collisions), never the
  // step-start copy: it asks for the states alone (96 B a floe the rank does
  // not hold, when they are not whole).
  // The whole paths below read every floe's shape: those this rank does not
  // hold (contact/shapes.hpp) built from their vertices first.
  if (counts.whole_now()) {
    whole.state(WholeState::state);
    shapes.ensure_every(floes);
    contact::advance_with_collisions(floes, shapes, whole.detection(), dt, options, stats, report);
    return;
  }
  std::vector<FloeState> start = floes.state;
  bool start_whole = false;  // `start` holds every floe's current state (the rebuild gathered it)
  bool combined = false;
  // A try whose parts refuse only because clusters of two runners meet is
  // tried again with those clusters joined on one rank (JoinedClusters),
  // from the step's start, on the rooms, contact edges and pad edges
  // gathered in the first try (functions of the step's start: the same).
  JoinedClusters joined;
  contact::ShareRooms all;
  std::vector<contact::ContactEdge> pad_edges;
  // A rank whose part had no conflict and none of whose clusters a try
  // again joins elsewhere or takes in keeps that part and its floes' states
  // (`kept`, `kept_state`): its share would run the same clusters on the
  // same pairs again. It still makes the try's set-up and routing (its
  // part's pairs may go to a joined group's runner).
  std::optional<AdvancePart> kept;
  std::vector<FloeState> kept_state;
  for (int round = 0;; ++round) {
    if (round > 0) floes.state = start;
    // A run that keeps the impulse record: as advance_by_owner (the events'
    // places are the queue's keys, which read no list of the detection).
    contact::ImpulseRecord* const record = options.impulse.record;
    contact::ImpulseRecord own;
    contact::SubstepOptions own_options = options;
    if (record) own_options.impulse.record = &own;
    contact::ShareAdvance share(floes, shapes, part, dt, own_options, {owner, comm.rank(), joined.runners()}, true,
                                mine);
    if (round == 0) {
      std::vector<contact::ShareRooms> rooms = comm.allgather_parts(pack(share.rooms()), unpack_share_rooms);
      // A floe outrunning its reach on some rank (the flags gathered with the
      // rooms: the same on every rank): every rank rebuilds the pair list and
      // gathers the rooms again.
      if (any_outrun(rooms)) {
        ++counts.rebuilds;
        // The rebuild detects over every floe (the serial set-up's, contact::
        // Stepper::set_up_rebuilt): every floe's straight path and place from
        // its state at the step's start, which the floes still are (rooms()
        // moves none), made whole here; the fallback below starts again from
        // it. And every floe's reach from its owner (a rank wrote only its
        // band's at the detection, band18; 8 bytes a floe, in such a step only).
        whole.state(WholeState::state);
        shapes.ensure_every(floes);
        start = floes.state;
        start_whole = true;
        std::vector<double> reach = part.reach;
        comm.complete_owned(reach, owner);
        rooms = comm.allgather_parts(pack(share.rooms_rebuilt(reach)), unpack_share_rooms);
      }
      // The gathered conflicts are the same on every rank: all skip the
      // next exchanges alike.
      if (!combine_rooms(rooms, all)) {
        count_set_up(rooms, counts);
        break;
      }
    } else {
      // The set-up of the same pairs from the same start: the same rooms
      // as the first try's, whose gathered `all` the clusters read.
      const contact::ShareRooms again = share.rooms();
      FLOESIM_ASSERT(again.conflict == contact::ShareOutcome::Conflict::none && !again.outrun);
    }
    // The clusters are the same on every rank, and so are their runners.
    contact::ShareAdvance::Routes routes = share.clusters(all);
    // A jam-sized cluster (the same on every rank): every rank's pad edges first.
    if (routes.conflict == contact::ShareOutcome::Conflict::none && routes.pads) {
      if (round == 0) {
        ++counts.pads;
        pad_edges = comm.allgather<contact::ContactEdge>(share.pad_edges());
      }
      routes = share.pads(pad_edges);
    }
    if (routes.conflict != contact::ShareOutcome::Conflict::none) {
      ++counts.conflicts[conflict_name(routes.conflict)];
      break;
    }
    // Every rank's join candidates (8 bytes each), then the pairs touching a
    // cluster's members or candidates to its runner; with no cluster
    // anywhere (the same on every rank) nothing to route.
    if (routes.any_cluster) {
      const std::vector<contact::JoinCandidate> candidates =
          comm.allgather<contact::JoinCandidate>(routes.candidates);
      counts.candidates += static_cast<long>(candidates.size());
      const std::vector<std::pair<int, std::uint32_t>> to = share.routes(candidates);
      // The pairs with their floes (state at the start, mass, inertia,
      // collision shape, reach), which the share then reads from the
      // message (ShareAdvance::hold takes their start states into its
      // straight paths).
      share.hold(exchange_advance_pairs(comm, part, routed_pairs(part, to, comm.size()), floes, shapes,
                                        &counts.shape_bytes));
    }
    AdvancePart done;
    if (kept) {
      done = std::move(*kept);
      floes.state = std::move(kept_state);
      ++counts.kept;
    } else {
      done = share_part(share, share.advance(), floes, record ? &own : nullptr);
      move_not_held(floes, share.held(), dt);
    }
    kept.reset();
    // The parts' lists: each rank's part, or after a rebuild the whole
    // rebuilt list on every rank.
    const Gathered g = gather_and_combine(
        comm, done, start_whole ? PairLists::whole_on_every_rank : PairLists::one_part_a_rank, floes, stats,
        report, record, options.impulse.warm, counts);
    const std::vector<AdvancePart>& parts = g.parts;
    combined = g.combined;
    if (combined) {
      if (round > 0) ++counts.joined;
      break;
    }
    // Joined on one rank when every conflict is clusters of two runners
    // meeting; a step whose pair list was rebuilt whole is left to the
    // whole advance (its set-up is not the part's), and so is the last
    // try's conflict, counted by kind.
    if (!start_whole && round + 1 < share_options.max_rounds && joined.add(parts, share)) {
      ++counts.rounds;
      const bool touched = std::any_of(joined.runners().begin(), joined.runners().end(), [&](const auto& kr) {
        return kr.second == comm.rank() || share.runner_of_cluster(kr.first) == comm.rank();
      });
      if (done.outcome.conflict == contact::ShareOutcome::Conflict::none && !touched) {
        kept = std::move(done);
        kept_state = floes.state;
      }
      continue;
    }
    count_conflicts(parts, counts);
    if (std::any_of(parts.begin(), parts.end(), [](const AdvancePart& p) {
          return p.outcome.conflict == contact::ShareOutcome::Conflict::missing_pairs;
        }))
      ++counts.missing;
    break;
  }
  if (combined) {
    counts.combined();
    return;
  }
  counts.fell_back(share_options);
  floes.state = start;
  // After a rebuild `start` is whole already: the fallback gathers nothing more.
  if (!start_whole) whole.state(WholeState::state);
  shapes.ensure_every(floes);
  contact::advance_with_collisions(floes, shapes, whole.detection(), dt, options, stats, report);
}

}  // namespace floesim::parallel
