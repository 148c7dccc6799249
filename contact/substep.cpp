#include "contact/substep.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numeric>
#include <queue>
#include <sstream>
#include <stdexcept>

#include "contact/step_limit.hpp"
#include "core/error.hpp"

namespace floesim::contact {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr int kFree = -1;
// A sub-step is halved after an overlap down to this fraction of the floor.
constexpr double kHalvingFloor = 0x1.0p-20;

// Pairs measured with their contact points and witnesses.
struct Measured {
  std::vector<NearPair> pairs;
  std::vector<ContactPoint> contacts;
  std::vector<Witness> witnesses;
};

// A cluster being sub-stepped. Its floes move on straight lines between its
// sub-step ends (tau_snap -> tau), where its collisions are resolved.
struct Cluster {
  std::vector<std::uint32_t> members;  // dynamic floes
  double tau = 0.0;                    // s into the step: where the cluster is
  double tau_snap = 0.0;               // start of its last sub-step
  std::vector<FloeState> snap;         // members' states at tau_snap (velocities of that sub-step)
  std::vector<std::uint32_t> internal; // pairs: members with members, and with obstacles
  Measured cur;                        // the internal pairs measured at tau
  bool alive = true;                   // false once merged into another cluster
  bool events_only = false;            // its time step overlapped: events for the rest of the step
  double jam_h = std::numeric_limits<double>::infinity();  // s, its time step (halved when one overlaps)
};

// One call of advance_with_collisions (the steps of substep.hpp). Clusters
// are advanced in time order, one sub-step at a time (the cluster furthest
// behind goes next), so when one must merge with another, that one has a
// sub-step in progress that started no later than now: its floes are put
// where their straight paths take them now, and the two go on together.
class Stepper {
public:
  Stepper(Floes& floes, const CollisionShapes& shapes, const Detection& detection, double dt,
          const SubstepOptions& options, CollisionStats& stats, SubstepReport& report,
          const ClusterShare* share = nullptr)
      : floes_(floes), shapes_(shapes), det_(&detection), dt_(dt), opt_(options), stats_(stats), report_(report),
        share_(share) {}

  // A share's run (advance_share): what it did.
  ShareOutcome outcome() const {
    ShareOutcome o;
    o.conflict = conflict_;
    o.floor_tau = floor_tau_;
    o.floor_cluster = floor_cluster_;
    for (std::size_t k = 0; k < clusters_.size(); ++k) {
      if (!own_[k]) continue;
      ++o.clusters;
      if (clusters_[k].alive) o.moved.insert(o.moved.end(), clusters_[k].members.begin(), clusters_[k].members.end());
    }
    std::sort(o.moved.begin(), o.moved.end());
    return o;
  }

  void run() {
    const std::size_t n = floes_.size();
    start_ = floes_.state;
    lin_.assign(n, 0.0);
    bool outrun = false;
    for (std::size_t i = 0; i < n; ++i) {
      if (floes_.is_static[i]) continue;
      const FloeState& s = start_[i];
      lin_[i] = (std::hypot(s.vx, s.vy) + std::abs(s.yaw_rate) * shapes_.radius[i]) * dt_;
      outrun = outrun || lin_[i] > det_->reach[i];
    }
    if (outrun) rebuild_pairs();
    build_pair_index();
    room_.resize(det_->pairs.size());
    for (std::size_t p = 0; p < det_->pairs.size(); ++p) {
      const NearPair& q = det_->pairs[p];
      room_[p] = pair_room(floes_, shapes_, q, witnesses_of(q, det_->witnesses), opt_.collision_distance, dt_);
    }
    make_clusters();
    reach_left_.assign(n, kInf);
    budget_.assign(n, kInf);
    outran_.assign(n, 0);
    for (std::size_t i = 0; i < n; ++i)
      if (!floes_.is_static[i]) reach_left_[i] = det_->reach[i] - lin_[i];
    if (clusters_.empty()) {
      for (std::size_t i = 0; i < n; ++i)
        if (!floes_.is_static[i]) floes_.state[i] = linear(static_cast<std::uint32_t>(i), dt_);
      return;
    }
    posed_ = PosedShapes(floes_, shapes_);
    // Free floes go to the end of the step now: nobody reads them before, and
    // a floe that joins a cluster is put back on its straight path.
    for (std::size_t i = 0; i < n; ++i)
      if (!floes_.is_static[i] && cluster_of_[i] == kFree) floes_.state[i] = linear(static_cast<std::uint32_t>(i), dt_);
    // Time order: a min-heap of (tau, cluster); stale entries are skipped.
    using Entry = std::pair<double, int>;
    std::priority_queue<Entry, std::vector<Entry>, std::greater<Entry>> queue;
    own_.assign(clusters_.size(), 1);
    for (std::size_t k = 0; k < clusters_.size(); ++k) {
      Cluster& c = clusters_[k];
      // A share runs the clusters whose lowest floe (members.front()) it owns.
      if (share_) own_[k] = share_->owner[c.members.front()] == share_->rank;
      if (!own_[k]) continue;
      compute_budgets(static_cast<int>(k));
      collect_internal(static_cast<int>(k));
      measure_internal(c);
      snapshot(c);
      queue.push({0.0, static_cast<int>(k)});
    }
    while (!queue.empty()) {
      const auto [tau, k] = queue.top();
      queue.pop();
      Cluster& c = clusters_[static_cast<std::size_t>(k)];
      if (!c.alive || tau != c.tau || !(c.tau < dt_)) continue;
      advance_cluster(k);
      if (conflict_ != ShareOutcome::Conflict::none) return;
      if (c.alive && c.tau < dt_) queue.push({c.tau, k});
    }
    for (std::size_t k = 0; k < clusters_.size(); ++k)
      if (const Cluster& c = clusters_[k]; c.alive && own_[k]) {
        ++report_.clusters;
        report_.largest_cluster = std::max(report_.largest_cluster, static_cast<long>(c.members.size()));
      }
  }

private:
  std::uint32_t other(std::uint32_t p, std::uint32_t i) const {
    const NearPair& q = det_->pairs[p];
    return q.a == i ? q.b : q.a;
  }

  // The floe on its straight path, tau after the start of the step.
  FloeState linear(std::uint32_t i, double tau) const {
    return drifted(start_[i], tau);
  }

  // How far any point of floe i is from where its straight path would put it.
  double deviation(std::uint32_t i, double tau) const {
    const FloeState l = linear(i, tau);
    const FloeState& s = floes_.state[i];
    return std::hypot(s.x - l.x, s.y - l.y) + shapes_.radius[i] * std::abs(s.yaw - l.yaw);
  }

  void rebuild_pairs() {
    DetectionOptions o;
    o.collision_distance = opt_.collision_distance;
    o.domain = opt_.domain;
    o.reach = det_->reach;
    o.horizon = dt_;
    for (std::size_t i = 0; i < o.reach.size(); ++i) o.reach[i] = std::max(o.reach[i], 1.5 * lin_[i]);
    rebuilt_ = detect(floes_, shapes_, o);
    det_ = &rebuilt_;
    ++report_.rebuilt;
  }

  // pairs_of(i): indices of the candidate pairs of floe i (compressed rows).
  void build_pair_index() {
    const std::size_t n = floes_.size();
    pair_offsets_.assign(n + 1, 0);
    for (const NearPair& q : det_->pairs) {
      ++pair_offsets_[q.a + 1];
      ++pair_offsets_[q.b + 1];
    }
    std::partial_sum(pair_offsets_.begin(), pair_offsets_.end(), pair_offsets_.begin());
    pair_list_.resize(pair_offsets_[n]);
    std::vector<std::size_t> fill(pair_offsets_.begin(), pair_offsets_.end() - 1);
    for (std::size_t p = 0; p < det_->pairs.size(); ++p) {
      pair_list_[fill[det_->pairs[p].a]++] = static_cast<std::uint32_t>(p);
      pair_list_[fill[det_->pairs[p].b]++] = static_cast<std::uint32_t>(p);
    }
    stamp_.assign(det_->pairs.size(), 0);
  }
  std::span<const std::uint32_t> pairs_of(std::uint32_t i) const {
    return {pair_list_.data() + pair_offsets_[i], pair_offsets_[i + 1] - pair_offsets_[i]};
  }

  // Clusters: connected components of the hot pairs between dynamic floes,
  // grown through tight pairs (room below xi: a floe of the cluster that
  // collides would soon bring the other in anyway, one at a time), numbered
  // by their lowest floe.
  void make_clusters() {
    const std::size_t n = floes_.size();
    DisjointSets sets(n);
    auto find = [&](std::uint32_t i) { return sets.find(i); };
    std::vector<std::uint8_t> hot(n, 0);
    const double tight = opt_.collision_distance;
    for (std::size_t p = 0; p < det_->pairs.size(); ++p) {
      if (!(room_[p] < tight)) continue;
      const NearPair& q = det_->pairs[p];
      const bool da = !floes_.is_static[q.a], db = !floes_.is_static[q.b];
      if (room_[p] < 0.0) {
        if (da) hot[q.a] = 1;
        if (db) hot[q.b] = 1;
      }
      if (da && db) sets.join(q.a, q.b);
    }
    // A jam (a contact component of jam.floes floes or more, impulse.hpp)
    // joins a cluster whole: its floes would come in one by one anyway, each
    // time with an LCP of the part that came in so far.
    find_jams();
    for (std::uint32_t i = 0; i < n; ++i)
      if (jam_of_[i] >= 0) sets.join(i, jams_[static_cast<std::size_t>(jam_of_[i])].front());
    // A jam whose LCP was not solved at the start of the step (jam.hpp,
    // at_step_start) is time-stepped whatever its rooms: its time step is
    // where its contacts are resolved.
    if (!opt_.impulse.jam.at_step_start)
      for (std::uint32_t i = 0; i < n; ++i)
        if (jam_of_[i] >= 0) hot[i] = 1;
    // A cluster of jam.floes floes or more takes time steps, whose LCP turns
    // and speeds up its floes: their deviations from the straight paths
    // outgrow small budgets. The dynamic floes close to such a cluster (room
    // below jam.pad xi) join it now rather than during its time step, where
    // each join reruns its LCP.
    {
      std::vector<std::uint32_t> size(n, 0), hot_root(n, 0);
      for (std::uint32_t i = 0; i < n; ++i)
        if (!floes_.is_static[i]) {
          ++size[find(i)];
          if (hot[i]) hot_root[find(i)] = 1;
        }
      std::vector<std::uint8_t> big(n, 0);
      for (std::uint32_t i = 0; i < n; ++i) {
        const std::uint32_t r = find(i);
        big[i] = !floes_.is_static[i] && hot_root[r] && size[r] >= opt_.impulse.jam.floes;
      }
      const double pad = opt_.impulse.jam.pad * tight;
      for (std::size_t p = 0; p < det_->pairs.size(); ++p) {
        const NearPair& q = det_->pairs[p];
        if (!(room_[p] < pad) || floes_.is_static[q.a] || floes_.is_static[q.b] || !(big[q.a] || big[q.b])) continue;
        hot[q.a] = hot[q.a] || big[q.a];
        hot[q.b] = hot[q.b] || big[q.b];
        sets.join(q.a, q.b);
      }
    }
    std::vector<std::uint8_t> active_root(n, 0);
    for (std::uint32_t i = 0; i < n; ++i)
      if (hot[i]) active_root[find(i)] = 1;
    cluster_of_.assign(n, kFree);
    std::vector<int> of_root(n, kFree);
    for (std::uint32_t i = 0; i < n; ++i) {
      if (floes_.is_static[i] || !active_root[find(i)]) continue;
      const std::uint32_t r = find(i);
      if (of_root[r] == kFree) {
        of_root[r] = static_cast<int>(clusters_.size());
        clusters_.emplace_back();
      }
      cluster_of_[i] = of_root[r];
      clusters_[static_cast<std::size_t>(of_root[r])].members.push_back(i);
    }
  }

  // jam_of_[i]: the jam of floe i (-1: none), jams_: their floes.
  void find_jams() {
    const std::size_t n = floes_.size();
    DisjointSets sets(n);
    auto find = [&](std::uint32_t i) { return sets.find(i); };
    for (const ContactPoint& c : det_->contacts)
      if (!floes_.is_static[c.a] && !floes_.is_static[c.b]) sets.join(c.a, c.b);
    std::vector<std::uint32_t> size(n, 0);
    for (std::uint32_t i = 0; i < n; ++i)
      if (!floes_.is_static[i]) ++size[find(i)];
    jam_of_.assign(n, -1);
    std::vector<int> of_root(n, -1);
    for (std::uint32_t i = 0; i < n; ++i) {
      const std::uint32_t r = find(i);
      if (floes_.is_static[i] || size[r] < opt_.impulse.jam.floes) continue;
      if (of_root[r] < 0) {
        of_root[r] = static_cast<int>(jams_.size());
        jams_.emplace_back();
      }
      jam_of_[i] = of_root[r];
      jams_[static_cast<std::size_t>(of_root[r])].push_back(i);
    }
  }

  // Budget of each member: half the room of each pair with a floe outside
  // the cluster (obstacles do not move: their pairs are internal).
  void compute_budgets(int k) {
    for (std::uint32_t i : clusters_[static_cast<std::size_t>(k)].members) {
      double b = kInf;
      for (std::uint32_t p : pairs_of(i)) {
        const std::uint32_t j = other(p, i);
        if (floes_.is_static[j] || cluster_of_[j] == k) continue;
        b = std::min(b, 0.5 * room_[p]);
      }
      budget_[i] = b;
    }
  }

  void collect_internal(int k) {
    Cluster& c = clusters_[static_cast<std::size_t>(k)];
    c.internal.clear();
    ++epoch_;
    for (std::uint32_t i : c.members)
      for (std::uint32_t p : pairs_of(i)) {
        if (stamp_[p] == epoch_) continue;
        const std::uint32_t j = other(p, i);
        if (!floes_.is_static[j] && cluster_of_[j] != k) continue;
        stamp_[p] = epoch_;
        c.internal.push_back(p);
      }
  }

  // Measures a cluster's internal pairs at the present poses into m; true if
  // one overlaps.
  bool measure(const Cluster& c, Measured& m) const {
    m.pairs.clear();
    m.contacts.clear();
    m.witnesses.clear();
    bool overlap = false;
    for (std::uint32_t p : c.internal) {
      const NearPair& q = det_->pairs[p];
      const double range = exact_range(floes_, shapes_, q.a, q.b, dt_, opt_.collision_distance);
      m.pairs.push_back(measure_pair(posed_, q.a, q.b, q.shift, opt_.collision_distance, range, m.contacts, m.witnesses));
      overlap = overlap || m.pairs.back().overlap;
    }
    return overlap;
  }
  void measure_internal(Cluster& c) {
    for (std::uint32_t i : c.members) posed_.update(floes_, i);
    measure(c, c.cur);
  }

  void snapshot(Cluster& c) {
    c.snap.clear();
    for (std::uint32_t i : c.members) c.snap.push_back(floes_.state[i]);
    c.tau_snap = c.tau;
  }
  void restore(Cluster& c) {
    for (std::size_t m = 0; m < c.snap.size(); ++m) floes_.state[c.members[m]] = c.snap[m];
  }

  // The speculative contact of witness w of pair q (impulse.hpp).
  static ContactPoint speculative(const NearPair& q, const Witness& w) {
    return {q.a, q.b, 0.5 * (w.pa + w.pb), w.normal, w.distance, q.shift, true, w.vertex_of_b};
  }

  // One event of cluster k: a sub-step, or floes joining it at its time.
  void advance_cluster(int k) {
    Cluster& c = clusters_[static_cast<std::size_t>(k)];
    if (c.members.size() >= opt_.impulse.jam.floes && !c.events_only) {
      time_step(k);
      return;
    }
    const double xi = opt_.collision_distance;
    double limit = kInf;
    const NearPair* by = nullptr;
    for (const NearPair& q : c.cur.pairs) {
      const double l = pair_step_limit(floes_, shapes_, q, witnesses_of(q, c.cur.witnesses), xi);
      if (l < limit) {
        limit = l;
        by = &q;
      }
    }
    double h = std::min(limit, dt_ - c.tau);
    if (h < opt_.floor && dt_ - c.tau > opt_.floor) {
      h = opt_.floor;
      ++report_.floor_steps;
      floor_tau_ = c.tau;
      floor_cluster_ = k;
      std::ostringstream m;
      m << "floes " << by->a << " and " << by->b << " at distance " << by->distance << " m, " << c.tau
        << " s into the step";
      report_.floor_pair = m.str();
    }
    snapshot(c);
    for (;;) {
      const bool last = h >= dt_ - c.tau;
      const double t1 = last ? dt_ : c.tau + h;
      for (std::size_t m = 0; m < c.members.size(); ++m) {
        floes_.state[c.members[m]] = drifted(c.snap[m], h);
      }
      // Budgets: the pairs with floes outside that this sub-step would break
      // bring those floes in, at the cluster's time.
      joining_.clear();
      merging_.clear();
      collect_breaks(k, t1);
      if (!joining_.empty() || !merging_.empty()) {
        restore(c);
        bring_in(k);
        return;
      }
      for (std::uint32_t i : c.members) posed_.update(floes_, i);
      if (!measure(c, next_)) {
        c.tau = t1;
        std::swap(c.cur, next_);
        ++report_.substeps;
        // Collisions at the end of the sub-step (at the end of the step they
        // are left to the next step, which starts with them).
        if (c.tau < dt_ && !c.cur.contacts.empty()) collide(c.cur.contacts);
        return;
      }
      // Overlap: redo with half the length.
      ++report_.rejected;
      restore(c);
      h *= 0.5;
      if (h < kHalvingFloor * opt_.floor) {
        const NearPair* bad = nullptr;
        for (const NearPair& q : next_.pairs)
          if (q.overlap) bad = &q;
        std::ostringstream m;
        m << "floes " << bad->a << " and " << bad->b << " overlap however short the sub-step, " << c.tau
          << " s into the step";
        throw RunError(m.str());
      }
    }
  }

  // The floes outside cluster k whose pairs with its members, now at time t1,
  // are past the members' budgets: free ones to joining_, clusters to merging_.
  void collect_breaks(int k, double t1) {
    for (std::uint32_t i : clusters_[static_cast<std::size_t>(k)].members) {
      const double dev = deviation(i, t1);
      if (dev > reach_left_[i] && !outran_[i]) {
        outran_[i] = 1;
        ++report_.reach_exceeded;
      }
      if (!(dev > budget_[i])) continue;
      for (std::uint32_t p : pairs_of(i)) {
        const std::uint32_t j = other(p, i);
        if (floes_.is_static[j] || cluster_of_[j] == k || !(0.5 * room_[p] < dev)) continue;
        if (cluster_of_[j] == kFree) joining_.push_back(j);
        else merging_.push_back(cluster_of_[j]);
      }
    }
  }

  // A dense cluster (jam.floes floes or more) takes the rest of the step in
  // one go: its contacts rest and every point of its pairs beyond xi is a
  // speculative contact for that time (impulse.hpp), one LCP instead of an
  // event, and an LCP of the whole cluster, each time one of its many pairs
  // meets. If that overlaps after all (a pair turning faster than its
  // linearised witness gaps tell: an error in h^2), the time step is redone
  // with half the length; below jam.step_floor dt the cluster goes back to
  // events for the rest of the step.
  void time_step(int k) {
    Cluster& c = clusters_[static_cast<std::size_t>(k)];
    const double xi = opt_.collision_distance;
    const double h = std::min(dt_ - c.tau, c.jam_h);
    const double t1 = h >= dt_ - c.tau ? dt_ : c.tau + h;
    ImpulseOptions impulse = opt_.impulse;
    impulse.speculative_step = h;
    snapshot(c);
    const std::vector<FloeState> before = c.snap;
    // Each solve from `before` replaces the last: the percussion record keeps
    // only the impulses of the time step taken (ImpulseRecord).
    const std::size_t recorded = impulse.record ? impulse.record->loads.size() : 0;
    auto rewind = [&] {
      if (impulse.record) impulse.record->loads.resize(recorded);
    };
    // The witnesses were found within the range the floes' velocities before
    // the LCP gave. The LCP may speed floes up (a jam passes the push on), so
    // vertices beyond that range could close within h, unseen. The pairs are
    // then measured again, at the same poses, within the range the new
    // velocities give; if that finds more witnesses, the LCP is solved again
    // from the velocities before it with them (a few rounds at most).
    for (std::uint32_t i : c.members) posed_.update(floes_, i);
    const Measured* wit = &c.cur;
    // The range each pair was measured within (c.cur: the velocities before the LCP, over dt).
    std::vector<double> ranges(c.internal.size());
    for (std::size_t i = 0; i < c.internal.size(); ++i) {
      const NearPair& q = det_->pairs[c.internal[i]];
      ranges[i] = exact_range(floes_, shapes_, q.a, q.b, dt_, xi);
    }
    std::vector<ContactPoint> contacts = c.cur.contacts;
    for (const NearPair& q : wit->pairs)
      for (const Witness& w : witnesses_of(q, wit->witnesses))
        if (w.distance >= xi) contacts.push_back(speculative(q, w));
    // A contact whose target grew (its turning) or that joined (a wider
    // witness) needs the LCP solved again only if the answer no longer solves
    // it: if it took an impulse, or if its target is not met by the present
    // velocities (by more than approach_tolerance, below which a contact is
    // not solved at all, impulse.hpp). Otherwise the answer is the new LCP's
    // too: that contact's impulse is 0, its velocity meets its target, and no
    // other row changed.
    const double tolerance = opt_.impulse.approach_tolerance;
    for (int round = 0;; ++round) {
      const std::vector<std::uint8_t> resting(contacts.size(), 1);
      // The LCP sees each contact's gap after h as linear; the floes' turning
      // closes some further (turning_closing, step_limit.hpp), which depends
      // on the velocities the LCP gives. So the LCP is solved again from the
      // velocities before it, each contact asking for what its turning
      // closed with the last answer on top, until no contact's turning grows
      // by more than jam.turning_slack xi (a few rounds at most: the turning
      // hardly changes with the small velocity changes it asks for). The
      // turning kept is the largest seen, so the rounds end.
      for (int turn = 0;; ++turn) {
        const std::vector<ContactImpulse> impulses = resolve_collisions(floes_, contacts, impulse, stats_, resting);
        if (turn == opt_.impulse.jam.turning_rounds) break;
        bool again = false;
        for (std::size_t j = 0; j < contacts.size(); ++j) {
          ContactPoint& cp = contacts[j];
          const double closing = turning_closing(floes_, cp, h);
          if (closing > cp.turning + opt_.impulse.jam.turning_slack * xi) {
            cp.turning = closing;
            again = again || impulses[j].normal > 0.0 || target_shortfall(floes_, cp, impulse) > tolerance;
          }
        }
        if (!again) break;
        for (std::size_t m = 0; m < before.size(); ++m) floes_.state[c.members[m]] = before[m];
        rewind();
      }
      if (round == 3) break;
      // Ranges only grow, so a measure finds every witness the last one found.
      bool wider = false;
      for (std::size_t i = 0; i < c.internal.size(); ++i) {
        const NearPair& q = det_->pairs[c.internal[i]];
        const double r = 1.5 * exact_range(floes_, shapes_, q.a, q.b, h, xi);
        if (r > ranges[i]) {
          ranges[i] = r;
          wider = true;
        }
      }
      if (!wider) break;
      // Into the buffer the last round did not use: `wit` may point at the other.
      Measured& into = wit == &wide_[0] ? wide_[1] : wide_[0];
      into.pairs.clear();
      into.contacts.clear();
      into.witnesses.clear();
      bool unmet = false;
      const std::size_t known = contacts.size();
      for (std::size_t i = 0; i < c.internal.size(); ++i) {
        const NearPair& q = det_->pairs[c.internal[i]];
        into.pairs.push_back(measure_pair(posed_, q.a, q.b, q.shift, xi, ranges[i], into.contacts, into.witnesses));
        // The pair's new witnesses beyond xi: those the last measure (at the
        // same poses, within a smaller range) did not find.
        const std::span<const Witness> old =
            i < wit->pairs.size() ? witnesses_of(wit->pairs[i], wit->witnesses) : std::span<const Witness>{};
        for (const Witness& w : witnesses_of(into.pairs.back(), into.witnesses)) {
          if (w.distance < xi) continue;
          const bool seen = std::any_of(old.begin(), old.end(), [&](const Witness& o) {
            return o.vertex_of_b == w.vertex_of_b && o.pa == w.pa && o.pb == w.pb;
          });
          if (seen) continue;
          ContactPoint cp = speculative(q, w);
          cp.turning = turning_closing(floes_, cp, h);
          unmet = unmet || target_shortfall(floes_, cp, impulse) > tolerance;
          contacts.push_back(cp);
        }
      }
      wit = &into;
      if (contacts.size() == known || !unmet) break;
      for (std::size_t m = 0; m < before.size(); ++m) floes_.state[c.members[m]] = before[m];
      rewind();
      ++report_.rejected;
    }
    snapshot(c);  // the velocities of the time step, for merges that look back into it
    auto undo = [&] {
      for (std::size_t m = 0; m < before.size(); ++m) floes_.state[c.members[m]] = before[m];
      c.snap = before;
      rewind();
    };
    for (std::size_t m = 0; m < c.members.size(); ++m) {
      floes_.state[c.members[m]] = drifted(floes_.state[c.members[m]], h);
    }
    joining_.clear();
    merging_.clear();
    collect_breaks(k, t1);
    if (!joining_.empty() || !merging_.empty()) {
      undo();
      bring_in(k);
      return;
    }
    for (std::uint32_t i : c.members) posed_.update(floes_, i);
    if (measure(c, next_)) {
      undo();
      for (std::uint32_t i : c.members) posed_.update(floes_, i);
      c.jam_h = 0.5 * h;
      ++report_.rejected;
      if (c.jam_h < opt_.impulse.jam.step_floor * dt_) {
        c.events_only = true;
        // Events resolve collisions at the end of their sub-steps; a jam
        // that took no time step yet has its contacts unresolved (jam.hpp,
        // at_step_start): they are an event now.
        if (c.tau == 0.0 && !opt_.impulse.jam.at_step_start && !c.cur.contacts.empty()) {
          collide(c.cur.contacts);
          snapshot(c);
        }
      }
      return;
    }
    c.tau = t1;
    std::swap(c.cur, next_);
    ++report_.substeps;
    ++report_.time_steps;
  }

  // The floes in joining_ (free) and the clusters in merging_ join cluster k
  // at its time: a free floe where its straight path puts it, a cluster's
  // floes where its sub-step in progress puts them (it started no later than
  // now: time order). Then the collisions at that time are resolved.
  void bring_in(int k) {
    Cluster& c = clusters_[static_cast<std::size_t>(k)];
    // A jam comes in whole (make_clusters).
    for (std::size_t m = 0, n = joining_.size(); m < n; ++m) {
      const int jam = jam_of_[joining_[m]];
      if (jam < 0) continue;
      for (std::uint32_t f : jams_[static_cast<std::size_t>(jam)]) {
        if (cluster_of_[f] == kFree) joining_.push_back(f);
        else if (cluster_of_[f] != k) merging_.push_back(cluster_of_[f]);
      }
    }
    // A share stops at a cluster it does not run: the serial advance merges
    // the two at a time the share cannot know.
    for (int l : merging_)
      if (!own_[static_cast<std::size_t>(l)]) {
        conflict_ = ShareOutcome::Conflict::foreign_cluster;
        return;
      }
    std::sort(joining_.begin(), joining_.end());
    joining_.erase(std::unique(joining_.begin(), joining_.end()), joining_.end());
    for (std::uint32_t j : joining_) {
      cluster_of_[j] = k;
      c.members.push_back(j);
      floes_.state[j] = linear(j, c.tau);
      ++report_.joined;
    }
    std::sort(merging_.begin(), merging_.end());
    merging_.erase(std::unique(merging_.begin(), merging_.end()), merging_.end());
    for (int l : merging_) {
      Cluster& o = clusters_[static_cast<std::size_t>(l)];
      const double since = c.tau - o.tau_snap;  // >= 0 by the time order
      for (std::size_t m = 0; m < o.members.size(); ++m) {
        floes_.state[o.members[m]] = drifted(o.snap[m], since);
        cluster_of_[o.members[m]] = k;
        c.members.push_back(o.members[m]);
      }
      o.members.clear();
      o.alive = false;
      ++report_.merges;
    }
    compute_budgets(k);
    collect_internal(k);
    measure_internal(c);
    if (!c.cur.contacts.empty()) collide(c.cur.contacts);
    snapshot(c);
  }

  // An event's collisions: contacts approaching no faster than rest_speed
  // rest (restitution 0, impulse.hpp), the others are impacts.
  void collide(const std::vector<ContactPoint>& contacts) {
    resolve_collisions(floes_, contacts, opt_.impulse, stats_,
                       slow_contacts(floes_, contacts, opt_.impulse.rest_speed));
  }

  Floes& floes_;
  const CollisionShapes& shapes_;
  const Detection* det_;
  Detection rebuilt_;  // when the pair list had to be rebuilt
  double dt_;
  const SubstepOptions& opt_;
  CollisionStats& stats_;
  SubstepReport& report_;
  const ClusterShare* share_;          // null: every cluster (the serial advance)
  std::vector<std::uint8_t> own_;      // per cluster: run by this call
  ShareOutcome::Conflict conflict_ = ShareOutcome::Conflict::none;
  double floor_tau_ = -1.0;            // the last floor step's key (tau, cluster)
  long floor_cluster_ = -1;

  std::vector<FloeState> start_;       // at the start of the step: the straight paths
  std::vector<double> lin_;            // m, linear travel of each floe over the step
  std::vector<double> room_;           // m, per pair, over the step on straight paths
  std::vector<std::size_t> pair_offsets_;
  std::vector<std::uint32_t> pair_list_;
  std::vector<int> cluster_of_;        // kFree or a cluster
  std::vector<Cluster> clusters_;
  std::vector<double> budget_, reach_left_;  // m, per floe
  std::vector<std::uint8_t> outran_;
  PosedShapes posed_;
  std::vector<std::uint32_t> stamp_;
  std::uint32_t epoch_ = 0;
  Measured next_;                      // a cluster's pairs after the sub-step being tried
  std::vector<std::uint32_t> joining_;
  std::vector<int> merging_;
  std::array<Measured, 2> wide_;                 // time_step: the pairs measured within wider ranges (two rounds)
  std::vector<int> jam_of_;                      // per floe: its jam, or -1
  std::vector<std::vector<std::uint32_t>> jams_; // the floes of each jam
};

}  // namespace

void advance_with_collisions(Floes& floes, const CollisionShapes& shapes, const Detection& detection, double dt,
                             const SubstepOptions& options, CollisionStats& stats, SubstepReport& report) {
  Stepper(floes, shapes, detection, dt, options, stats, report).run();
}

ShareOutcome advance_share(Floes& floes, const CollisionShapes& shapes, const Detection& detection, double dt,
                           const SubstepOptions& options, const ClusterShare& share, CollisionStats& stats,
                           SubstepReport& report) {
  if (options.impulse.record) throw std::logic_error("advance_share: the impulse record needs the serial order");
  // The warm store is replaced by an empty probe that only says whether a
  // solve of the share would have used it (ClusterShare above).
  SubstepOptions o = options;
  WarmStart probe;
  if (options.impulse.warm) o.impulse.warm = &probe;
  const long failures = stats.failures;
  Stepper stepper(floes, shapes, detection, dt, o, stats, report, &share);
  ShareOutcome outcome;
  try {
    stepper.run();
    outcome = stepper.outcome();
  } catch (const RunError&) {
    outcome.conflict = ShareOutcome::Conflict::error;
  }
  if (outcome.conflict == ShareOutcome::Conflict::none && probe.uses > 0)
    outcome.conflict = ShareOutcome::Conflict::warm_start;
  if (outcome.conflict == ShareOutcome::Conflict::none && stats.failures != failures)
    outcome.conflict = ShareOutcome::Conflict::failed_lcp;
  return outcome;
}

}  // namespace floesim::contact
