#pragma once
// Collision impulses: the velocity–impulse LCP with Stewart–Trinkle friction
// (Rabatel et al. 2015; report 002, eq. 3.5) and Poisson restitution, solved
// per connected component of the contact graph.
//
// For contact j between floes a and b (normal N_j from a to b, tangent
// T_j = k x N_j, point P_j), the relative velocity of b with respect to a at
// P_j along a unit vector u is  u . (v_b(P_j) - v_a(P_j)) = g_u W, where the
// row g_u has (u, (P_j - G_b) x u) in b's block and -(u, (P_j - G_a) x u) in
// a's. Stack the normal rows Gn (m x 3n) and the tangent rows Gt (2m x 3n: +T_j
// then -T_j per contact). With A the block-diagonal mass matrix (static floes:
// A^-1 = 0) and W^- the velocities before the collision, the unknowns
// z = (lambda [m], beta [2m], alpha [m]) >= 0 solve the LCP
//
//       | Gn A^-1 Gn^T   Gn A^-1 Gt^T   0 |       | Gn W^- |
//   M = | Gt A^-1 Gn^T   Gt A^-1 Gt^T   E |,  q = | Gt W^- |,
//       | mu I           -E^T           0 |       | 0      |
//
// E = blockdiag((1, 1)^T). Complementarity says: the normal relative
// velocity after the impulse is >= 0 and positive only where lambda = 0
// (Signorini, in velocities); alpha is the sliding speed, beta the friction
// impulse along +-T, at most mu lambda, and acting only against sliding
// (Coulomb). This is the compression phase (restitution 0), W^c = W^- +
// A^-1 (Gn^T lambda + Gt^T beta); Poisson's law then gives
//   W^+ = (1 + e) W^c - e W^-   (decompression impulse e times the compression one).
//
// Gap stabilisation: a contact whose gap g has fallen below min_gap (round-off
// and rotation make gaps creep down over many steps) asks for the small
// separating normal velocity (min_gap - g)/tau instead of 0, i.e.
// q_j -= (min_gap - g)/tau, with a fixed relaxation time tau (not the step:
// a short step must not turn a tiny gap error into a large velocity). Contacts
// at or above min_gap keep the exact Signorini condition (and the exact
// restitution law).
//
// Resting contacts (ImpulseOptions::rest_speed): a contact whose points
// approach no faster than rest_speed before its collision (in a sub-step's
// event, or at the start of a step before the step's smooth forces) rests:
// restitution 0. Its rebound would not lift the floes out of the contact
// distance before the push that made the approach closes it again.
//
// Collisions at the start of a step (resolve_step_collisions): resting and
// speculative contacts. Poisson's law is a law of impacts. A contact is
// "pushed" when its approach was made by this step: at the start of the step
// it approached no faster than rest_speed, or than a third of its approach
// now, or than the step's smooth forces move either floe's point there
// (|dv(P)| of either floe between the start of the step and W^-). The
// approach then comes from the step's forces, and from the impulses of the
// contacts around it: in a jam, neighbours get the same push from the wind
// and approach because the floe ahead is held.
//  * A pushed contact point is resting: restitution 0 (Poisson's law per
//    contact, e_k = 0: W^+ = W^c + A^-1 G^T diag(e_k) z^c, which is
//    (1 + e) W^c - e W^- when every e_k = e). Bouncing it by e times a speed
//    the step itself created would make a jammed pack rattle at a rate set by
//    the step. The second and third conditions matter in chains: a floe
//    pushed by the wind against a floe the wall holds has no relative
//    approach of its own, yet its contact takes the impulse that stops the
//    wind's push; bounced by e, that floe chattered at a few mm/s for ever
//    (tests/coupling/test_collisions.cpp, the row against a wall). An approach
//    slower than one step's push is re-made within the step anyway: a bounce
//    that slow would land again before the step ends.
//  * Speculative contacts (after Catto's): a pushed point of two floes at a
//    gap g >= xi (a witness of the detection, detection.hpp) that would come
//    closer than xi/2 within the step h may close by at most 0.9 (g - xi/2):
//    it asks for v_n >= -0.9 (g - xi/2)/h, i.e. q_j += 0.9 (g - xi/2)/h, with
//    restitution 0. It applies an impulse only if the pair would otherwise
//    end the step closer than xi/2 + 0.1 (g - xi/2); the pair then arrives at
//    the end of the step instead of colliding within it. (Until 2026-12-02
//    this comment said (g - xi/2)/2; the code has always used 0.9.) The
//    turning of the floes over h is added to the target in a jam's time step
//    (turning_closing, step_limit.hpp; substep.hpp). As the approach may come
//    from the impulses of the step, the speculative points are found after a
//    solve, and the components that gained some are solved again from W^-
//    (at most two more times). Impacts (approaches that are not pushed) keep
//    their instant and restitution: the step's sub-steps resolve them
//    (substep.hpp).
//  * Jams: a contact component of at least jam.floes floes (jam.hpp) is a jam. Every
//    contact of a jam floe rests and every point beyond xi of its pairs (with
//    other jam floes, obstacles, or floes coming at it) is speculative from
//    the first solve: the jam is time-stepped (one LCP per step, as in dense
//    granular flows, where event-driven collisions collapse into ever shorter
//    sub-steps). That LCP is solved in the jam's time step
//    (advance_with_collisions, substep.hpp), from W^-: this function leaves
//    the jam's contacts and points alone (unless jam.at_step_start). Floes
//    jammed by the wind against an obstacle touch each other
//    all the time, and would otherwise need an event, and an LCP of the whole
//    jam, each time one pair among hundreds closed a gap; a floe that drifts
//    into a jam is stopped within the last step before it touches (at most
//    its speed times the step early), without rebound (a jam of tens of floes
//    takes the blow as a body, not as a single elastic partner).
//
// Components are built from dynamic floes joined by contacts; an obstacle
// (static floe) does not join components since it transmits no impulse.

#include <algorithm>
#include <array>
#include <compare>
#include <cstdint>
#include <span>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include "contact/detection.hpp"
#include "contact/jam.hpp"
#include "contact/lcp/fallback.hpp"

namespace floesim::contact {

// Warm starts of large LCPs (LemkeOptions::start, lemke.hpp): Lemke's final
// complementary basis for each large component, per contact point (which of
// lambda, beta+, beta-, alpha were basic), keyed by its pair of floes and its
// features: the vertex, in the body frame of the floe it belongs to, and the
// normal, in the body frame of the floe whose boundary the vertex faces
// (vertex_of_b says which). Both stay put while the floes move and the
// contact's mid-point slides along the edge. A contact of a large LCP takes
// the flags of the nearest stored point of its pair with the same vertex
// (within `match_distance`) and normal (within about 0.1 rad); a point with
// none starts with its w's basic. Lemke then starts from that
// basis. A wrong guess costs only time: the answer is accepted only with a
// residual within the fallback chain's accept_residual, and otherwise the
// LCP is solved from scratch by the chain (counted in warm_missed).
// The store is pruned by age: `tick()` (once per step of the run) drops,
// every `max_age` ticks, the pairs not stored for max_age ticks, so pairs that
// drifted apart and the floes a split retired do not pile up.
struct WarmStart {
  struct Entry {
    Vec2 body_point = Vec2::Zero();
    Vec2 body_normal = Vec2::UnitX();
    std::array<std::uint8_t, 4> basic{};  // lambda, beta+, beta-, alpha basic
    bool vertex_of_b = false;             // body_point is b's vertex in b's frame, body_normal in a's (else the other way)
  };
  struct Pair {
    std::vector<Entry> entries;
    long stored = 0;  // the clock when they were stored
  };
  std::unordered_map<std::uint64_t, Pair> pairs;
  double match_distance = 0.05;  // m
  long clock = 0;
  long max_age = 256;
  long uses = 0;  // solves that started from the store (a share's copy counts its own: ShareAdvance, resolve_step_collisions_share)
  // A share's copy of the run's store (ShareAdvance, resolve_step_collisions_share)
  // logs the keys of the pairs it stores, in order (repeats kept), so that
  // its caller can send those pairs to every rank (docs/parallel.md, "The
  // conflicting clusters on one rank"). Off in the run's store.
  bool log = false;
  std::vector<std::uint64_t> written;
  // The pairs a share stored, by key ascending, each with its entries as
  // the share's copy holds them at the end.
  using Written = std::vector<std::pair<std::uint64_t, Pair>>;

  void tick() {
    if (++clock % max_age == 0) std::erase_if(pairs, [&](const auto& p) { return clock - p.second.stored > max_age; });
  }
  // A share's copy of this store: the same pairs and clock, no uses, its
  // writes logged.
  WarmStart share_copy() const {
    WarmStart copy = *this;
    copy.uses = 0;
    copy.log = true;
    copy.written.clear();
    return copy;
  }
  // What a share's copy stored (`written`, each pair once).
  Written written_pairs() const {
    std::vector<std::uint64_t> keys = written;
    std::sort(keys.begin(), keys.end());
    keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
    Written out;
    out.reserve(keys.size());
    for (const std::uint64_t k : keys) out.emplace_back(k, pairs.at(k));
    return out;
  }
};

// Per contact: the total impulse applied (compression + decompression), N s.
// Floe b received `vector` = normal N + tangential T at `point` (the contact's,
// in a's image of a periodic domain), floe a its opposite (percussion loads).
struct ContactImpulse {
  double normal = 0.0, tangential = 0.0;
  Vec2 vector = Vec2::Zero();  // N s, world
  Vec2 point = Vec2::Zero();   // m, world
};

// The contact impulses of a run step, per floe, for the percussion phase
// (coupling/percussion.hpp): the collisions at the step's start, its
// sub-steps' events and its jam time steps all append here, so percussion
// sees every impulse of the step whatever sub-step it fell in. Each load is
// one contact's impulse on one dynamic floe, in that floe's body frame (a
// rigid floe's body point is the same material point all step long, so the
// loads of different instants can be put on one model). `event` numbers the
// solves (one collision instant each). `sustained`: a contact whose points
// approached no faster than ImpulseOptions::rest_speed before its solve (at
// the step's start, before the step's smooth forces), whose impulse is a
// force times the time it acted, not a percussion. The test is on a speed,
// not on the step: a jam's contacts, a floe's push against a coast, a
// speculative contact that stops a pushed floe are sustained; a floe that
// drifts into a jam at dm/s strikes it, speculative or not.
struct ImpulseRecord {
  struct Load {
    std::uint32_t floe = 0;
    std::uint32_t event = 0;
    Vec2 point = Vec2::Zero();    // m, body frame of `floe`
    Vec2 impulse = Vec2::Zero();  // N s, body frame of `floe`
    bool sustained = false;
    // The contact as a collision (the run file's /events/collisions): the
    // other floe (an index, static or not), the contact's normal impulse
    // lambda >= 0 (N s) and its point (m, world, in a's image).
    std::uint32_t other = 0;
    double normal = 0.0;
    Vec2 world = Vec2::Zero();
  };
  std::vector<Load> loads;
  std::uint32_t events = 0;
  void clear() {
    loads.clear();
    events = 0;
  }
};

// A share's part of the impulse record (a distributed run's, docs/parallel.md
// stage seven): the loads a share of the collision work recorded, and where
// they go in the record the whole (serial) call would have made, so that
// merging the parts of every share gives that record exactly: the same loads
// in the same order, the same event numbers and event count.
//  * The collisions at the step's start (resolve_step_collisions) are one
//    event; its loads follow the contacts of the call's list, in which a
//    share's contacts keep their relative order (its step groups' contacts,
//    each list in the order the whole call builds it). A contact's place
//    there is `ContactPlace`: the segment of the list (0: detected contacts;
//    1: a jam's speculative points; 2, 3: the speculative contacts of rounds
//    1 and 2), then its pair, keyed by the pair itself, and its index among
//    that pair's contact points (segment 0) or witnesses (1 to 3).
//  * The advance (advance_with_collisions) numbers one event per solve, in
//    the order of its queue's pops, keyed (tau, cluster) (substep.hpp); all
//    the solves of one pop are one cluster's, so one share's. A share's
//    event's place is `EventPlace`: its pop's key. Events whose loads a jam's
//    time step dropped (it solves again) still count, as in the serial record.
// Why a key by pair orders as the whole call's list. Each segment lists
// its contacts in the order of the detection's lists: segment 0 by contact
// point, the others by pair, then witness. The whole detection holds its
// pairs in pair order (pair_before: a, b, then b's shift, each pair once)
// and each pair's contact points and witnesses as one run of its lists,
// the runs in the pairs' order (detect measures the pairs in that order;
// parallel::merge keeps it). So a contact point's index in the whole list
// orders as (its pair, its index within the pair's run), and likewise a
// witness's: the key below, which any part of the detection that holds the
// pair gives alike (a share on a rank's part records with it, and no rank
// needs the whole lists to place its loads).
struct ContactPlace {
  std::uint32_t segment = 0;
  std::uint32_t a = 0, b = 0;         // the pair's floes (a < b)
  double shift_x = 0.0, shift_y = 0.0;  // m, b's periodic shift (pair_before's order)
  std::uint32_t index = 0;            // within the pair: its contact point's (segment 0) or witness's
  auto operator<=>(const ContactPlace&) const = default;
};
// The place of a pair's index-th contact point or witness in `segment`.
inline ContactPlace contact_place(std::uint32_t segment, const NearPair& p, std::uint32_t index) {
  return {segment, p.a, p.b, p.shift.x(), p.shift.y(), index};
}
struct EventPlace {
  double tau = 0.0;  // s into the step
  std::int64_t cluster = 0;
  auto operator<=>(const EventPlace&) const = default;
};
// A share's record as the merges read it (views of the share's part: nothing copied).
struct RecordPart {
  const ImpulseRecord* record = nullptr;  // the share's loads, its events numbered from 0
  std::span<const ContactPlace> places;   // step's start: per load, its contact's place
  std::span<const EventPlace> events;     // advance: per event of `record`, its place
};
// Appends the step-start collisions' record of the shares' `parts` to `into`
// as the whole call would have: one event (numbered into.events) whose loads
// are ordered by their contacts' places (a contact's two loads, a then b,
// stay together: one share made both).
void merge_step_record(ImpulseRecord& into, std::span<const RecordPart> parts);
// Appends the advance's record of the shares' `parts` to `into`: the events
// of every part ordered by place (each place is one share's: ties keep the
// share's own order), numbered on from into.events, with their loads.
void merge_advance_record(ImpulseRecord& into, std::span<const RecordPart> parts);

// Appends to `record` the nonzero impulses of `contacts` (one per contact, at
// the floes' present poses) as one event: -J on a, J on b (b's point shifted
// back to its own image). A contact is sustained if `sustained` flags it
// (slow_contacts below: its approach before the solve was at most
// rest_speed); otherwise it is an impact.
void record_impulses(ImpulseRecord& record, const Floes& floes, std::span<const ContactPoint> contacts,
                     std::span<const ContactImpulse> impulses, std::span<const std::uint8_t> sustained = {});

// Per contact, 1 if its two points approach no faster than `rest_speed`
// (m/s) with the velocities `velocities` (one per floe; the floes' present
// ones when empty), at the floes' present positions: a resting contact
// (ImpulseOptions::rest_speed).
std::vector<std::uint8_t> slow_contacts(const Floes& floes, std::span<const ContactPoint> contacts, double rest_speed,
                                        std::span<const FloeState> velocities = {});

struct ImpulseOptions {
  double restitution = 0.4;  // e in [0, 1]
  double friction = 0.7;     // mu >= 0
  // A component is solved only if some contact approaches faster than this
  // (m/s). Re-measured resting contacts approach at round-off speeds (1e-9
  // m/s, from the change of their points and normals as floes turn); at 1e-6
  // m/s a contact closes 10 um in a 10 s step, a thousandth of xi, which the
  // step limit and the gap stabilisation handle.
  double approach_tolerance = 1e-6;
  double min_gap = 0.0;      // m, see "gap stabilisation" above
  double relaxation_time = 10.0;  // s, tau of the gap stabilisation
  double collision_distance = 0.01;  // xi, m (speculative contacts)
  double speculative_step = 0.0;     // s, the step speculative contacts are for (set by resolve_step_collisions)
  // The step a contact's target is divided by is at least this (s): the
  // speculative gap and the floes' turning (turning_closing, step_limit.hpp)
  // become speeds over the step, and a gap measured at positions of size L
  // carries a round-off of about 1e-16 L (1e-12 m in a 10 km basin), which
  // over a 1.8e-15 s sliver asked for hundreds of m/s and threw a pack
  // apart. Over 1e-5 s (the sub-stepper's floor, substep.hpp) that round-off
  // is 1e-7 m/s, a tenth of approach_tolerance. Below the floor a contact
  // asks what it would over the floor: it may close less than the step
  // allows (never an overlap), and the turning it makes up for, O(h^2), is
  // round-off there.
  double step_floor = 1e-5;
  // The approach speed (m/s, the normal relative speed of a contact's two
  // points before its collision) at or below which a contact is resting, not
  // an impact. A floe pushed against another by a smooth acceleration a
  // (wind, drag, waves) that rebounds at e v climbs back (e v)^2/(2a) before
  // the push closes the gap again: below v_rest = sqrt(2 a xi)/e it never
  // leaves the contact distance xi, so the contact rests and the rebound is
  // a chatter below what the model resolves. A 1 m floe under a 15 m/s wind
  // (a = rho_a C_a U^2/(rho_i h) = 5.6e-4 m/s^2) gives, with xi = 1 cm and
  // e = 0.4, 8.4e-3 m/s; at 20 m/s 1.1e-2 m/s. Resting contacts get
  // restitution 0 and are recorded as sustained forces (ImpulseRecord); the
  // test is on the physical speed, so it does not depend on the step
  // (docs/contact.md, "Resting contacts"). Config key [contact] rest_speed.
  double rest_speed = 0.01;
  JamOptions jam;                    // what a jam is and how it is time-stepped (jam.hpp)
  std::size_t dense_max = 400;  // LCPs up to this size are assembled dense, larger sparse
  lcp::FallbackOptions solver;
  // Lemke's pivot limit on collision LCPs, per unknown, when
  // solver.lemke.max_pivots is 0 (Lemke's own default is 50 per unknown):
  // limit = lemke_pivots_per_unknown n + 1000. From scratch, the LCPs of a
  // 500-floe jam take 1 to 3 pivots per unknown, and beyond the limit the
  // chain's contact-wise Gauss–Seidel takes over; at 5 per unknown some of
  // its LCPs failed, at 15 none did (docs/contact.md).
  long lemke_pivots_per_unknown = 15;
  // An answer the fallback chain did not accept (its residual above
  // solver.accept_residual) is still taken when every contact's
  // complementarity error, as a velocity, is at most this (m/s; see
  // velocity_error in impulse.cpp). The chain's residual is relative to
  // |q|: on the 930-contact LCPs of a 500-floe jam its 1e-9 is about 1e-11
  // m/s, and Lemke and the contact-wise Gauss–Seidel stall above it on a few
  // of them (residuals 1.2e-9 to 4.5e-7, velocity errors 2.3e-10 to 5.0e-8
  // m/s, jam_500 to 2200 s). The tolerance is a tenth of approach_tolerance,
  // the approach below which a component is not solved at all: 1 um in a
  // 10 s step.
  double velocity_tolerance = 1e-7;
  // LCPs of at least warm_min unknowns start from the basis in `warm`
  // (null: never): the Newton method (from solver.newton_min_size unknowns)
  // and Lemke both take it as their first guess; the caller owns it and
  // keeps it across steps.
  WarmStart* warm = nullptr;
  std::size_t warm_min = 200;
  // A folder ("": none) where every LCP that ends as a failure (counted in
  // CollisionStats::failures) is written in the Siconos format
  // (lcp/siconos_io.hpp) as failed_lcp_<k>.dat, k = the failure's number in
  // the run, with the contact count, friction and the chain's attempts in
  // its comment: a failure from any run becomes test data. Config key
  // [contact] dump_failed_lcps.
  std::string dump_failed_lcps;
  // Where the solves append their impulses for the percussion phase (null:
  // nowhere); the caller owns it and clears it each step.
  ImpulseRecord* record = nullptr;
};

// Running totals of a run (written to /diagnostics/lcp and the summary).
struct CollisionStats {
  long contacts = 0;      // contact points in solved components
  long lcps = 0;          // LCP solves
  long pivots = 0;
  long failures = 0;      // solves that ended without an accepted solution
  long fallbacks = 0;     // solves that needed a fallback step
  long flagged = 0;       // of those, answered by projected Gauss–Seidel
  long gauss_seidel = 0;  // of those, answered by the contact-wise Gauss–Seidel (lcp/coulomb_gs.hpp)
  long tolerated = 0;     // answers the chain did not accept, taken within velocity_tolerance
  long largest = 0;       // largest LCP size
  long total_size = 0;    // sum of LCP sizes
  long warm = 0;          // of lcps, solved by Lemke warm-started from the last basis (or its normal flags alone)
  long warm_missed = 0;   // warm starts that ended without an accepted solution (then solved from scratch)
};

// The counts of `s` by name, in one list (checkpoints, sums over ranks):
// pointers into s (const or not, as s is).
template <class Stats>
auto collision_counts(Stats& s) {
  return std::array{std::pair{"contacts", &s.contacts}, std::pair{"lcps", &s.lcps},
                    std::pair{"pivots", &s.pivots}, std::pair{"failures", &s.failures},
                    std::pair{"fallbacks", &s.fallbacks}, std::pair{"flagged", &s.flagged},
                    std::pair{"gauss_seidel", &s.gauss_seidel}, std::pair{"tolerated", &s.tolerated},
                    std::pair{"largest", &s.largest}, std::pair{"total_size", &s.total_size},
                    std::pair{"warm", &s.warm}, std::pair{"warm_missed", &s.warm_missed}};
}

// The normal relative velocity (m/s, > 0: separating) contact c must reach
// in its LCP (above): 0, the gap stabilisation's, a speculative contact's
// allowed closing, plus its turning over options.speculative_step.
double normal_target(const ContactPoint& c, const ImpulseOptions& options);
// How far the contact's normal relative velocity, with the floes' present
// velocities, is below its target (m/s; <= 0: met).
double target_shortfall(const Floes& floes, const ContactPoint& c, const ImpulseOptions& options);

// Changes the velocities of the floes in contact (W^- -> W^+). Returns the
// impulses, one per contact, in the order of `contacts`. `resting` (optional,
// one flag per contact): restitution 0 for those (above). The record
// (options.record) takes the impulses of the contacts that approached no
// faster than rest_speed before the solve as sustained.
std::vector<ContactImpulse> resolve_collisions(Floes& floes, const std::vector<ContactPoint>& contacts,
                                               const ImpulseOptions& options, CollisionStats& stats,
                                               std::span<const std::uint8_t> resting = {});

// The collisions at the start of a step of length `step`: the contacts of
// `detection` (measured at the present positions) with their resting flags,
// and the speculative contacts (above). `start`: the floes at the start of the
// step, before its smooth forces. Returns how many speculative contacts took
// part. `impulses` (optional) receives the impulses of detection.contacts, in
// their order (percussion).
std::size_t resolve_step_collisions(Floes& floes, std::span<const FloeState> start, const Detection& detection,
                                    double step, const ImpulseOptions& options, CollisionStats& stats,
                                    std::vector<ContactImpulse>* impulses = nullptr);

// A share of the collision work by owner (a distributed run's, docs/parallel.md
// stage seven): per floe the rank that owns it, and this share's rank. The
// contact layer knows nothing of ranks: these are numbers. (The advance's
// clusters use it too, substep.hpp.)
struct ClusterShare {
  std::span<const int> owner;  // per floe: its rank, one of the sharing ranks' (each pair's room on one share)
  int rank = 0;
  // The advance (ShareAdvance) only: clusters given another runner than
  // their lowest floe's owner, (cluster, rank), the clusters numbered as
  // every share numbers them: the conflicting clusters joined on one rank
  // (docs/parallel.md, "The conflicting clusters on one rank").
  std::span<const std::pair<std::int32_t, std::int32_t>> runners = {};
};

// One share of resolve_step_collisions: the LCPs of the step groups whose
// lowest floe `share` gives to `share.rank`.
//
// The step groups. resolve_step_collisions solves the components of its
// contacts (round 0), then up to two rounds find the speculative contacts
// the answers make (a witness beyond xi whose points would close below xi/2
// within the step) and solve the components that gained some again from
// W^-. A speculative contact can join two components, so the components
// alone do not split the work. Let V0 be the floes of the contacts (round
// 0 may change them); a witness between two floes outside V0 is tested in
// round 1 on W^-, which every share knows; V1 adds to V0 the floes of the
// witnesses with an end in V0 (they may be taken) and of those taken on
// W^-; round 2 may take only witnesses with an end in V1 (the others are
// tested on the same velocities as in round 1, and were not taken). The
// step groups are the connected components of the dynamic floes joined by
// the contacts, the witnesses taken on W^- and every witness with an end in
// V1. Every component of every round lies in one group, and a group's
// solves read and write only its floes (obstacles are not changed). So the
// share, which runs the same rounds on its groups' contacts and witnesses
// only, makes the same solves on the same numbers as the whole call: its
// floes end with the whole call's velocities, its counts are the whole
// call's over its groups (sums; `largest` a maximum), and the groups of the
// shares are disjoint.
//
// The warm store (options.warm) is kept across steps by pair: a solve reads
// and then replaces the entries of its contacts' pairs (warm_guess,
// warm_store), and a contact's pair has both floes in one step group (or
// one and an obstacle): its component lies in one group. So the pairs one
// group's solves read and write are no other group's, and the share runs on
// a copy of the store as it was at the step's start (WarmStart::share_copy,
// the same on every rank): each of its solves reads what the whole call's
// solve of that component reads (the start's entry, or what an earlier
// solve of the same group stored: the share keeps its groups' solves in the
// whole call's order), and the share returns the pairs it stored (`warm`)
// and its uses. Written into every rank's store with the other shares'
// (each pair by one share, its last write the whole call's), they leave the
// store as the whole call leaves it. options.warm itself is not changed.
//
// A conflict (the caller then solves the whole step from the states on
// entry): a failed LCP (its dump, not written by a share, is numbered by the
// run's failures), a RunError. The share never sets `warm_start` itself:
// its caller may make a share's use of the store one (a test hook,
// parallel::CollideShareOptions::warm_conflict, which keeps the whole path
// reachable). options.record (if any) receives the share's loads as one
// event, and `places` their places in the whole call's record (RecordPart,
// merge_step_record).
struct StepCollisionShare {
  enum class Conflict { none, warm_start, failed_lcp, error };
  Conflict conflict = Conflict::none;
  std::vector<std::uint32_t> moved;  // ascending: the floes whose velocities the share changed
  long groups = 0;                   // step groups of the share
  std::size_t speculative = 0;       // speculative contacts that took part (resolve_step_collisions' count)
  std::vector<ContactPlace> places;  // per load the share recorded (options.record): its contact's place
  // With a warm store (options.warm; none on a conflict): the pairs the
  // share's solves stored and its solves that started from the store.
  WarmStart::Written warm;
  long warm_uses = 0;
};
//
// `groups` (optional): the step groups, found from every pair's edge
// (group_edges, step_groups below) by the caller; `detection` may then be a
// part of the step's detection, in pair order, that holds every pair with
// contact points or witnesses whose dynamic floes are all in the share's
// groups (a distributed run's rank: the pairs it detected and those the
// detecting ranks sent it; docs/parallel.md, "The detection's lists by
// owner"); `places` key the loads by pair (ContactPlace), so a share on a
// part records as one on the whole detection. Without `groups`, they are
// found from `detection`, the whole one.
struct StepGroups;
StepCollisionShare resolve_step_collisions_share(Floes& floes, std::span<const FloeState> start,
                                                 const Detection& detection, double step,
                                                 const ImpulseOptions& options, const ClusterShare& share,
                                                 CollisionStats& stats, const StepGroups* groups = nullptr);

// What one pair says of the step groups (resolve_step_collisions_share):
// whether it has contact points (`contacts`), whether it has a witness at or
// beyond xi and does not overlap (`witnesses`: a candidate for the rounds'
// speculative contacts, or a jam's speculative point), and whether one of
// those would become speculative on the present velocities, W^-
// (`speculative`). A function of the pair and the states alone, so the rank
// that detected the pair can say it; every rank then finds the same groups
// from every rank's edges (step_groups), whatever the order of the list.
// The edge also says both floes' owners (ClusterShare::owner at the step,
// which the detecting rank knows for the floes it holds), so that a group's
// owner, its lowest floe's, is known from the edges alone: 20 bytes.
struct GroupEdge {
  static constexpr std::uint32_t contacts = 1, witnesses = 2, speculative = 4;
  std::uint32_t a = 0, b = 0;  // floes, a < b
  std::uint32_t flags = 0;
  std::int32_t owner_a = 0, owner_b = 0;  // the ranks owning a and b (0 without owners)
};
// The edges of `detection`'s pairs that have a flag (in its order). `floes`
// holds W^-, `start` the step's start, as for resolve_step_collisions;
// `owner` (per floe, read for the pairs' floes only; empty: every floe 0).
std::vector<GroupEdge> group_edges(const Floes& floes, std::span<const FloeState> start, const Detection& detection,
                                   double step, const ImpulseOptions& options, std::span<const int> owner = {});

// The step groups of a step, over the edges' floes only (a compact index:
// no array over the whole pack): per such floe, whether it is in a jam (a
// component of at least options.jam.floes dynamic floes joined by contact
// points), the lowest floe of its step group (kNone: in none) and the rank
// owning that lowest floe (-1: in none), as the edges say it. A floe that
// is in no edge is in no jam and no group.
struct StepGroups {
  static constexpr std::uint32_t kNone = 0xffffffffu;
  std::vector<std::uint32_t> floes;   // ascending: the edges' floes
  std::vector<std::uint8_t> jam;      // per entry of `floes`
  std::vector<std::uint32_t> lowest;  // per entry: its group's lowest floe, or kNone
  std::vector<int> owner;             // per entry: the owner of its group's lowest floe, or -1

  // Floe f's entry, or floes.size() if no edge has it (a binary search).
  std::size_t entry(std::uint32_t f) const {
    const auto at = std::lower_bound(floes.begin(), floes.end(), f);
    return at != floes.end() && *at == f ? static_cast<std::size_t>(at - floes.begin()) : floes.size();
  }
  bool in_jam(std::uint32_t f) const {
    const std::size_t k = entry(f);
    return k < floes.size() && jam[k];
  }
  std::uint32_t lowest_of(std::uint32_t f) const {
    const std::size_t k = entry(f);
    return k < floes.size() ? lowest[k] : kNone;
  }
  int owner_of(std::uint32_t f) const {
    const std::size_t k = entry(f);
    return k < floes.size() ? owner[k] : -1;
  }
  // Whether floe f's group is rank's: its lowest floe is owned there.
  bool mine(std::uint32_t f, int rank) const { return lowest_of(f) != kNone && owner_of(f) == rank; }
  // Whether there is a group at all; the count of rank's groups.
  bool any() const;
  long count(int rank) const;
};
// The step groups from every pair's edges (any order, each pair once): the
// same groups, lowest floes and owners whatever the order.
StepGroups step_groups(const Floes& floes, std::span<const GroupEdge> edges, const ImpulseOptions& options);

// Adds the counts of `part` (a share's) to `total`: sums, `largest` a maximum.
void add_collision_counts(CollisionStats& total, const CollisionStats& part);

}  // namespace floesim::contact
