// Simulation: what this rank holds of the floes (docs/parallel.md, "The
// state held by owner with a halo (plan)"): the owners at the start and at
// a detection in place, the band announced by the owners, the hand-over at
// a move of the cuts, the whole lists and the whole state on demand, and
// the periodic wrap of the held floes. The step's phases are in
// simulation.cpp.
#include <algorithm>
#include <cmath>
#include <cstring>

#include "core/error.hpp"
#include "coupling/simulation.hpp"
#include "fluid/fft2d.hpp"
#include "fluid/sea.hpp"
#include "parallel/detect.hpp"
#include "parallel/held.hpp"

namespace floesim {

void Simulation::hand_over_moved(StepContext& ctx, std::span<const int> detected) {
  // Rank r's copies of the floes it holds (its own and its band at the
  // last detection, held_now()) are current: every holder moves, wraps and
  // drifts them alike. Its other copies are not (wrap_periodic and the
  // vertical drift pass over the held floes only), and a move of the cuts
  // can make r the owner of such a floe: r would drift it from its stale
  // copy, and the drift's exchange would send that copy to its holders.
  // So each floe whose owner changed goes from its owner at the last
  // detection, which held it, to its new owner: what the new owner's
  // drift and the phases after it read of it that the constants do not
  // give (the collision shapes, the drift's quadrature, the moorings'
  // anchors and the floes' masses are every rank's):
  // - its state (96 B): the drift's start, and the advance's;
  // - its step-start copy ctx.start (96 B): the collisions' and the
  //   advance's start state of the floes it owns, and what a rejected try
  //   restores the state from (the update at the redone try does not move
  //   the cuts again);
  // - its detection reach (8 B): the advance's outrun check over the own
  //   floes (band18; the reaches of the floes a rank does not hold are not
  //   written there).
  // The water velocity goes from the coupling's owner to the drift's
  // (hand_water_over, after this). One all-to-all of 200 B a floe that
  // changes owner, in a step whose cuts moved (every 10 steps at most).
  FLOESIM_ASSERT(detection_part_ && detected.size() == scenario_.floes.size());
  comm_.hand_over_each(detected, owners_.owner(), scenario_.floes.state, ctx.start, detection_part_->reach);
}

void Simulation::copy_start(StepContext& ctx) {
  // The readers of ctx.start on a rank read the floes it holds: the
  // collisions and the advance (the pairs of its part, all held), the
  // vertical drift (held_now()), hand_over_moved (the old owner sends its
  // own floes'), the detection's notices (a leaving floe's, from its old
  // owner), whole_state (the owners' entries for the others) and the
  // poison mode's checks (the held floes'). Their entries are the ones
  // copied; a floe that comes to the rank within the step gets its entry
  // with its state (hand_over_moved, the notices, whole_state). Where a
  // rank may read every floe (no halo exchange; or state_whole_, every
  // copy as current as the run made it: before the first drift's exchange,
  // whose step may pose every floe) every entry is copied, as serially. The array is the last step's: no allocation while
  // the floe count holds.
  const std::vector<FloeState>& state = scenario_.floes.state;
  ctx.start = std::move(start_copies_);
  ctx.start_held.clear();
  if (halo_exchange() && !state_whole_) ctx.start_held = held_now();
  if (ctx.start_held.empty()) {
    ctx.start.assign(state.begin(), state.end());
    return;
  }
  ctx.start.resize(state.size());  // a split's pieces: new entries, written below where held
  for (std::size_t i = 0; i < state.size(); ++i)
    if (ctx.start_held[i]) ctx.start[i] = state[i];
}

void Simulation::restore_start(const StepContext& ctx) {
  // A rejected try's floes back at t: the entries copied, and those
  // written since for the floes that came to this rank (held_now(): its
  // own floes now, from the try's notices or a move of the cuts). With
  // every entry current (a whole copy, or whole_state's gather of both in
  // the try) every floe's.
  std::vector<FloeState>& state = scenario_.floes.state;
  const std::vector<std::uint8_t> held = ctx.start_held.empty() || state_whole_ ? std::vector<std::uint8_t>{} : held_now();
  if (held.size() != state.size()) {
    state = ctx.start;
    return;
  }
  for (std::size_t i = 0; i < state.size(); ++i)
    if (ctx.start_held[i] || held[i]) state[i] = ctx.start[i];
}

std::vector<std::uint8_t> Simulation::held_now() const {
  // The last detection's band and own floes (held_); the floes this rank
  // owns now: after a move of the cuts some of those were in no band of
  // it, and came to it by hand_over_moved; its own floes for the coupling:
  // between a move of the slabs and the footprints' next rebuild (with a
  // window) they need not be in its band, and it poses them (their x, y,
  // yaw) and its law reads their heave, pitch and roll. Their copies are
  // current: the drift's exchange sends each to its holders (the coupling's
  // owner among them), the detection's the floes entering a band, and the
  // collisions' and advance's moves reach every rank.
  // With the implicit step every rank also holds every floe's vertical
  // DOFs (heave, pitch, roll and their rates), which the replicated solve
  // alone writes, alike on every rank (FloeSeaContact::implicit_step): not
  // marked here, this is the held set of the whole state.
  const std::size_t n = scenario_.floes.size();
  if (!holds_part()) return {};
  std::vector<std::uint8_t> held = held_.mask;
  for (const std::uint32_t i : owners_.mine()) held[i] = 1;
  if (floe_sea_)
    for (const std::uint32_t i : floe_sea_->own_floes())
      if (i < n) held[i] = 1;
  return held;
}

bool Simulation::holds_part() const {
  const std::size_t n = scenario_.floes.size();
  return !comm_.serial() && held_.mask.size() == n && owners_.owner().size() == n;
}

std::vector<std::uint8_t> Simulation::kicked_floes() const {
  return halo_exchange() ? held_now() : std::vector<std::uint8_t>{};
}

void Simulation::start_owners() {
  // One decomposition (docs/parallel.md, stage seven): with a sea in slabs
  // the floes' strips are its slabs, moved by whole blocks of the
  // transform's rows (drift()); otherwise the strips' cuts are free in y.
  owners_ = parallel::FloeOwners(comm_.rank(), comm_.size(), detection_options_.domain);
  wrapped_.clear();  // the places are the start's or a checkpoint's, every copy as given: none to wrap late
  if (sea_ && !sea_->slab_rows().empty())
    owners_.set_slabs({sea_->slab_rows(), sea_->grid().dy(), fluid::RealFft2d::kRows});
}

void Simulation::detect_in_place() {
  // Each rank its part, the pairs of the floes it owns at their present
  // places (parallel::detect, as detect_and_check's); the whole lists
  // gathered only for the advance from the whole detection, else by
  // whole_detection() when a step needs them.
  if (comm_.serial()) {
    set_reach();
    detection_ = contact::detect(scenario_.floes, shapes_, detection_options_);
    detection_whole_ = true;
    held_ = hold_band();
    return;
  }
  // The owners at the floes' present places: after a split (the pieces
  // owned by place_pieces) from the owners' own floes, as at a step's
  // detection (FloeOwners::migrate: their leave notices; no other floe's
  // copy read); at the start and after a restore (no owners yet) from
  // every floe's place, every copy the file's.
  if (owners_.assigned_for(scenario_.floes)) owners_.migrate(comm_, scenario_.floes);
  else owners_.assign(scenario_.floes);
  set_reach();
  wrap_entering(owners_.mine());
  // Outside a step nothing is known of who held what (the start, a
  // restore: every copy is the file's; a split: the split's readers
  // gathered, the other unheld copies stale): every entering floe's state
  // goes with its notice.
  std::optional<parallel::HaloPart> halo = halo_part(nullptr, nullptr);
  held_ = hold_band({}, {}, halo ? &*halo : nullptr);
  hold_quadrature();
  hold_shapes();
  note_arrived(halo);
  if (halo) announced_ = std::move(halo->announced);
  wrap_entering(held_.index);
  contact::Detection part;
  const bool whole = !advance_share_options_.on_part;
  detection_ = parallel::detect(comm_, owners_, scenario_.floes, shapes_, detection_options_, &part, whole, &held_);
  detection_whole_ = whole;
  detection_part_ = std::move(part);
  detection_own_ = owners_.mine();
}

parallel::HeldFloes Simulation::hold_band(std::span<const parallel::LeaveNotice> leaving,
                                          std::span<const long long> leaving_counts, parallel::HaloPart* halo) {
  const std::size_t n = scenario_.floes.size();
  if (comm_.serial()) return held_.mask.size() == n ? std::move(held_) : parallel::every_floe(n);
  // Each owner tests its own floes against the ranks' strips and announces
  // them, with their reaches, to the ranks whose band holds them
  // (parallel::announce_held: the band's rule, H the ranks' largest h_j).
  return parallel::announce_held(comm_, owners_, scenario_.floes, shapes_, detection_options_, leaving, leaving_counts,
                                 halo);
}

bool Simulation::halo_exchange() const {
  // The reader of every floe that stays (docs/parallel.md, "The halo
  // exchange (halo26)", "... on the seas not in slabs (halo27)", "... for
  // the implicit step (implicit28)"): the advance from the whole detection
  // sets up every floe's pairs. Every sea, in slabs or not, with the
  // explicit kicks or the implicit step (whose solve on every rank reads
  // every floe's vertical DOFs, which every rank holds, and its yaw,
  // gathered from its owner), reads only the floes its ranks hold.
  return !comm_.serial() && advance_share_options_.on_part;
}

void Simulation::send_to_holders() {
  // Rank s reads, until the next drift, the floes it holds (held_now() on
  // s): its band and own floes at the last detection, the floes it owns
  // now, its coupling's own floes. Their copies there are current but for
  // the drift, which only the owner made; so the owner sends each floe's
  // drifted state (96 B and its index) to
  // - the ranks it announced the floe to at the last detection, if it
  //   owned the floe then (announced_): their bands held it;
  // - every other rank, if it did not (the floe came to it since, by the
  //   drift's migration or a move of the cuts: the ranks that hold it,
  //   its old owner and that owner's band, are known to that owner only);
  //   the floes that change owner are few, and each new owner then
  //   announces them at the next detection;
  // - its coupling's owners (FloeSeaContact::floe_owners, the last
  //   rebuild's, and next_floe_owners, the next rebuild's on a sea not in
  //   slabs), if not among those: between a move of the slabs and the
  //   footprints' next rebuild the coupling's floes need not be in its
  //   band, nor a flume's floes in its rank's share of the columns
  //   (FloeSeaContact::own_floes holds them from this exchange on).
  // The floes this rank owns now are its own already.
  const auto ranks = static_cast<std::size_t>(comm_.size());
  const int me = comm_.rank();
  const std::size_t n = scenario_.floes.size();
  std::span<const int> coupling, next;
  if (floe_sea_ && floe_sea_->floe_owners().size() == n) coupling = floe_sea_->floe_owners();
  if (floe_sea_ && floe_sea_->next_floe_owners().size() == n) next = floe_sea_->next_floe_owners();
  std::vector<std::vector<std::uint32_t>> to(ranks);
  for (const std::uint32_t j : owners_.mine()) {
    std::span<const int> holders;
    const bool known = announced_.find(j, holders);
    if (known) {
      for (const int s : holders) to[static_cast<std::size_t>(s)].push_back(j);
    } else {
      for (std::size_t s = 0; s < ranks; ++s)
        if (static_cast<int>(s) != me) to[s].push_back(j);
      continue;
    }
    const auto add = [&](int c) {
      std::vector<std::uint32_t>& list = to[static_cast<std::size_t>(c)];
      if (c != me && !std::binary_search(holders.begin(), holders.end(), c) && (list.empty() || list.back() != j))
        list.push_back(j);
    };
    if (!coupling.empty()) add(coupling[j]);
    if (!next.empty()) add(next[j]);
  }
  comm_.send_items(scenario_.floes.state, to);
}

std::optional<parallel::HaloPart> Simulation::halo_part(const parallel::Announced* last,
                                                        std::vector<FloeState>* start) {
  // The poison mode (a test) poisons the unheld floes after the drift
  // whatever the exchange, so its runs take part (b) even where the drift
  // sends every state (the advance from the whole detection): the
  // floes entering a band then come from their owners as with the exchange,
  // and what the mode finds is a phase's read beyond the held floes, not
  // the entering floes that part (b) would have brought.
  if (!halo_exchange() && !poison_) return std::nullopt;
  parallel::HaloPart halo;
  halo.last = last;
  halo.state = &scenario_.floes.state;
  halo.start = start;
  return halo;
}

void Simulation::note_arrived(const std::optional<parallel::HaloPart>& halo) {
  if (!halo || wrapped_.empty()) return;
  for (const std::uint32_t j : halo->written)
    if (j < wrapped_.size()) wrapped_[j] = 1;
}

const contact::Detection& Simulation::whole_detection() {
  // Collective: every rank reaches it at the same point of the same step.
  if (!detection_whole_) {
    detection_ = parallel::gather(comm_, *detection_part_, detection_own_);
    detection_whole_ = true;
  }
  return detection_;
}

void Simulation::whole_state(StepContext& ctx, parallel::WholeState what) {
  // Collective, as whole_detection(): state_whole_ and `what` are the same
  // on every rank. Each floe's state, and with WholeState::state_and_start
  // its step-start copy, from its owner (the drift's, owners_: it drifted
  // the floe and holds both current), in one message: 96 B a floe the rank
  // does not own for the state alone, 192 B with the copy. Only the floes
  // this rank does not hold (held_now()) take them: a held floe's copy is current
  // already (every holder updates it alike), and the poison mode's NaN in a
  // held floe, a reader's trace, stays to be reported.
  //
  // state_whole_ (one flag: both whole) is set only by the gather of both.
  // The state alone leaves the step-start copies stale, so a later ask in
  // the step gathers again; the advance, which asks for the state alone,
  // keeps what it gathered (its `start`) and asks once. (A split gathers
  // only the states it reads: split_states.)
  //
  // The poison mode's mutation `stale` (coupling/poison_mode.hpp) gathers
  // nothing: a step that reads every floe then reads the poison.
  if (state_whole_ || (poison_ && poison_->options().stale)) return;
  std::vector<FloeState>& state = scenario_.floes.state;
  const std::size_t n = state.size();
  FLOESIM_ASSERT(ctx.start.size() == n && owners_.owner().size() == n);
  const std::vector<std::uint8_t> held_mask = held_now();  // empty: every floe held
  const auto held = [&](std::size_t i) { return held_mask.empty() || held_mask[i] != 0; };
  ++whole_state_counts_.gathers;
  const long long before = comm_.traffic().bytes;
  if (what == parallel::WholeState::state) {
    std::vector<FloeState> owned = state;
    comm_.complete_owned(owned, owners_.owner());
    whole_state_counts_.bytes += comm_.traffic().bytes - before;
    for (std::size_t i = 0; i < n; ++i)
      if (!held(i)) state[i] = owned[i];
    return;
  }
  std::vector<std::array<FloeState, 2>> both(n);
  for (std::size_t i = 0; i < n; ++i) both[i] = {state[i], ctx.start[i]};
  comm_.complete_owned(both, owners_.owner());
  whole_state_counts_.bytes += comm_.traffic().bytes - before;
  for (std::size_t i = 0; i < n; ++i)
    if (!held(i)) {
      state[i] = both[i][0];
      ctx.start[i] = both[i][1];
    }
  state_whole_ = true;
}

std::vector<std::uint8_t> Simulation::split_states(std::span<const std::uint32_t> readers,
                                                   std::span<const std::uint8_t> held) {
  // Each rank sends its readers (its parents that may split or be decided
  // again, and their neighbours among its held floes: current copies) to
  // every rank, 100 B a floe (its index, 4 B, and state, 96 B), in one
  // allgather_bytes (two calls). Only the floes a rank does not hold take
  // them, as in whole_state: a held copy is current already, and the poison
  // mode's NaN in one stays to be reported. Every rank gets every rank's
  // readers, so the mask is the same everywhere. The poison mode's mutation
  // `stale` writes none: conclude then reads the poison.
  std::vector<FloeState>& state = scenario_.floes.state;
  constexpr std::size_t kRecord = sizeof(std::uint32_t) + sizeof(FloeState);
  std::vector<std::byte> message(readers.size() * kRecord);
  for (std::size_t k = 0; k < readers.size(); ++k) {
    std::memcpy(message.data() + k * kRecord, &readers[k], sizeof(std::uint32_t));
    std::memcpy(message.data() + k * kRecord + sizeof(std::uint32_t), &state[readers[k]], sizeof(FloeState));
  }
  const long long before = comm_.traffic().bytes;
  std::vector<std::size_t> counts;
  const std::vector<std::byte> all = comm_.allgather_bytes(message, counts);
  ++percussion_ranks_.split_gathers;
  percussion_ranks_.split_bytes += comm_.traffic().bytes - before;
  const bool stale = poison_ && poison_->options().stale;
  std::vector<std::uint8_t> readable(state.size(), 0);
  for (std::size_t at = 0; at + kRecord <= all.size(); at += kRecord) {
    std::uint32_t i = 0;
    std::memcpy(&i, all.data() + at, sizeof i);
    FLOESIM_ASSERT(i < state.size());
    readable[i] = 1;
    if (!stale && !held.empty() && !held[i]) std::memcpy(&state[i], all.data() + at + sizeof i, sizeof(FloeState));
  }
  return readable;
}

parallel::WholeOnDemand Simulation::whole_on_demand(StepContext& ctx) {
  return {[this]() -> const contact::Detection& { return whole_detection(); },
          [this, &ctx](parallel::WholeState what) { whole_state(ctx, what); }};
}

void Simulation::wrap_periodic() {
  const contact::Domain& d = detection_options_.domain;
  if (!d.periodic) return;
  // The floes this rank holds (every floe on one rank, before the first
  // detection: held_now()). Every holder wraps
  // a floe alike from the same bits; the other ranks' copies stay
  // unwrapped until the drift's exchange brings the owner's (or
  // hand_over_moved to a new owner, or wrap_entering at the detection).
  wrapped_ = held_now();
  std::vector<FloeState>& state = scenario_.floes.state;
  for (std::size_t i = 0; i < state.size(); ++i)
    if (wrapped_.empty() || wrapped_[i]) wrap_floe(state[i]);
}

void Simulation::wrap_floe(FloeState& s) const {
  const contact::Domain& d = detection_options_.domain;
  s.x = d.xmin + std::fmod(std::fmod(s.x - d.xmin, d.width()) + d.width(), d.width());
  s.y = d.ymin + std::fmod(std::fmod(s.y - d.ymin, d.height()) + d.height(), d.height());
}

void Simulation::wrap_entering(std::span<const std::uint32_t> floes) {
  // The wrap rounds ((x - xmin) + width is rounded to the spacing of the
  // doubles between width and 2 width), so it is not the identity on a
  // place inside the box: a copy left unwrapped
  // differs from its holders' in the last bits. A floe that enters this
  // rank's held set at the detection was not wrapped here at the advance;
  // its copy is the holders' before their wrap (the drift's exchange gave
  // the owner's state to every rank, and the collisions' and the advance's
  // moves are every rank's alike), so one wrap now gives their bits.
  if (!detection_options_.domain.periodic || wrapped_.empty()) return;
  for (const std::uint32_t i : floes) {
    if (i >= wrapped_.size() || wrapped_[i]) continue;  // a split's piece (i >= size) is its parent's copy
    wrap_floe(scenario_.floes.state[i]);
    wrapped_[i] = 1;
  }
}

}  // namespace floesim
