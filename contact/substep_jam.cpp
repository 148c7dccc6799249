// The jams' time steps of the multirate advance (contact/substep.hpp, item 5).
#include <algorithm>
#include <cmath>
#include <vector>

#include "contact/step_limit.hpp"
#include "contact/substep_stepper.hpp"
#include "core/error.hpp"

namespace floesim::contact::detail {

void Stepper::time_step(int k) {
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

}  // namespace floesim::contact::detail
