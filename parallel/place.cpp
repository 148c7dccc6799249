#include "parallel/place.hpp"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <limits>
#include <numeric>

#include <time.h>

#include "core/error.hpp"
#include "parallel/bytes.hpp"
#include "parallel/cell_routes.hpp"

namespace floesim::parallel {

std::vector<double> cut_by_cost(std::span<const double> y, std::span<const double> cost, int ranks) {
  FLOESIM_ASSERT(y.size() == cost.size() && ranks >= 1);
  const std::size_t n = y.size();
  std::vector<std::uint32_t> order(n);
  std::iota(order.begin(), order.end(), 0u);
  std::sort(order.begin(), order.end(), [&](std::uint32_t i, std::uint32_t j) { return y[i] != y[j] ? y[i] < y[j] : i < j; });
  // prefix[k]: the cost of the k first items by y.
  std::vector<double> prefix(n + 1, 0.0);
  for (std::size_t k = 0; k < n; ++k) prefix[k + 1] = prefix[k] + cost[order[k]];
  const double total = prefix[n];
  constexpr double kInf = std::numeric_limits<double>::infinity();
  std::vector<double> cuts;
  std::size_t k = 0;  // strips 0..r-1 hold the k first items
  for (int r = 1; r < ranks; ++r) {
    const double target = total * r / ranks;
    // |prefix[k] - target| falls, then rises, with k: walk to its least.
    while (k < n && std::abs(prefix[k + 1] - target) <= std::abs(prefix[k] - target)) ++k;
    double cut = k == 0 ? -kInf : k == n ? kInf : 0.5 * (y[order[k - 1]] + y[order[k]]);
    if (k > 0 && k < n && cut <= y[order[k - 1]]) cut = y[order[k]];  // adjacent doubles: the midpoint rounds down
    cuts.push_back(cut);
  }
  return cuts;
}

std::vector<int> cut_rows_by_cost(std::span<const double> row_cost, int block, int ranks) {
  const int rows = static_cast<int>(row_cost.size());
  const int blocks = (rows + block - 1) / block;
  FLOESIM_ASSERT(block >= 1 && ranks >= 1 && blocks >= ranks);
  // prefix[b]: the cost of the b first blocks.
  std::vector<double> prefix(static_cast<std::size_t>(blocks) + 1, 0.0);
  for (int b = 0; b < blocks; ++b) {
    double c = 0.0;
    for (int y = b * block; y < std::min(rows, (b + 1) * block); ++y) c += row_cost[static_cast<std::size_t>(y)];
    prefix[static_cast<std::size_t>(b) + 1] = prefix[static_cast<std::size_t>(b)] + c;
  }
  const double total = prefix.back();
  std::vector<int> first{0};
  int k = 0;  // slabs 0..r-1 hold the k first blocks
  for (int r = 1; r < ranks; ++r) {
    const double target = total * r / ranks;
    // At least one block for this slab and for each of the later ones.
    const int last = blocks - (ranks - r);
    k += 1;
    while (k < last && std::abs(prefix[static_cast<std::size_t>(k) + 1] - target) <= std::abs(prefix[static_cast<std::size_t>(k)] - target)) ++k;
    first.push_back(k * block);
  }
  first.push_back(rows);
  return first;
}

double thread_seconds() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

FloeOwners::FloeOwners(int rank, int ranks, const contact::Domain& domain, StripOptions options)
    : rank_(rank), ranks_(ranks), domain_(domain), options_(options) {
  FLOESIM_ASSERT(ranks >= 1 && rank >= 0 && rank < ranks && options.rebalance_steps >= 1 &&
                 options.relaxation > 0.0 && options.relaxation <= 1.0);
}

double FloeOwners::place(const FloeState& s) const {
  if (!domain_.periodic) return s.y;
  const double h = domain_.height();
  return domain_.ymin + std::fmod(std::fmod(s.y - domain_.ymin, h) + h, h);
}

void FloeOwners::set_cuts(std::vector<double> cuts) {
  FLOESIM_ASSERT(cuts.size() == static_cast<std::size_t>(ranks_ - 1) && std::is_sorted(cuts.begin(), cuts.end()));
  cuts_ = std::move(cuts);
  cut_ = true;
}

void FloeOwners::set_slabs(RowSlabs slabs) {
  FLOESIM_ASSERT(slabs.first_row.size() == static_cast<std::size_t>(ranks_) + 1 && slabs.dy > 0.0 && slabs.block >= 1);
  slabs_ = std::move(slabs);
  row_owner_ = row_owners(slabs_.first_row);
  // The cuts in y: the slabs' boundaries (the grid's first row at y = 0).
  std::vector<double> cuts;
  for (int r = 1; r < ranks_; ++r) cuts.push_back(slabs_.dy * slabs_.first_row[static_cast<std::size_t>(r)]);
  set_cuts(std::move(cuts));
}

double FloeOwners::key(const FloeState& s) const {
  // With slabs: the centroid's grid row (parallel::grid_row, the
  // coupling's rule); else the place.
  return has_slabs() ? static_cast<double>(grid_row(s.y, slabs_.dy, slabs_.rows())) : place(s);
}

int FloeOwners::owner_of_key(double key) const {
  // With slabs: the slab of the row; else the strip of the place between the cuts.
  if (has_slabs()) return row_owner_[static_cast<std::size_t>(key)];
  return static_cast<int>(std::upper_bound(cuts_.begin(), cuts_.end(), key) - cuts_.begin());
}

void FloeOwners::assign_keys(std::span<const double> keys) {
  owner_.resize(keys.size());
  mine_.clear();
  for (std::size_t i = 0; i < keys.size(); ++i) {
    owner_[i] = owner_of_key(keys[i]);
    if (owner_[i] == rank_) mine_.push_back(static_cast<std::uint32_t>(i));
  }
}

void FloeOwners::assign(const Floes& floes) {
  // Every floe's key (without slabs its place, which the first cuts split
  // into equal counts), then the owners of the keys (owner_at's rule).
  const std::size_t n = floes.size();
  std::vector<double> keys(n);
  for (std::size_t i = 0; i < n; ++i) keys[i] = key(floes.state[i]);
  if (!has_slabs() && !cut_) set_cuts(cut_by_cost(keys, std::vector<double>(n, 1.0), ranks_));
  assign_keys(keys);
}

void FloeOwners::place_pieces(const Floes& floes, std::span<const std::uint32_t> replaced) {
  FLOESIM_ASSERT((cut_ || has_slabs()) && owner_.size() <= floes.size());
  const std::size_t before = owner_.size();
  owner_.resize(floes.size());
  for (const std::uint32_t i : replaced) {
    FLOESIM_ASSERT(i < before);
    owner_[i] = owner_at(floes.state[i]);
  }
  for (std::size_t j = before; j < floes.size(); ++j) owner_[j] = owner_at(floes.state[j]);
  // This rank's floes, ascending: a replaced parent's index kept only if
  // its first piece is here, the pieces that land here merged in.
  std::vector<std::uint32_t> pieces;
  for (const std::uint32_t i : replaced)
    if (owner_[i] == rank_) pieces.push_back(i);
  for (std::size_t j = before; j < floes.size(); ++j)
    if (owner_[j] == rank_) pieces.push_back(static_cast<std::uint32_t>(j));
  std::sort(pieces.begin(), pieces.end());
  std::erase_if(mine_, [&](std::uint32_t i) { return owner_[i] != rank_; });
  std::vector<std::uint32_t> merged;
  merged.reserve(mine_.size() + pieces.size());
  std::set_union(mine_.begin(), mine_.end(), pieces.begin(), pieces.end(), std::back_inserter(merged));
  mine_ = std::move(merged);
}

std::vector<LeaveNotice> FloeOwners::leaving(int rank, const Floes& floes) const {
  FLOESIM_ASSERT(assigned_for(floes) && rank >= 0 && rank < ranks_);
  std::vector<LeaveNotice> out;
  const auto test = [&](std::size_t j) {
    const int now = owner_at(floes.state[j]);
    if (now != rank) out.push_back({static_cast<std::uint32_t>(j), static_cast<std::int32_t>(now), place(floes.state[j]), 0.0});
  };
  if (rank == rank_) {
    for (const std::uint32_t j : mine_) test(j);
  } else {  // a simulated rank (tests): its floes from the owner array
    for (std::size_t j = 0; j < owner_.size(); ++j)
      if (owner_[j] == rank) test(j);
  }
  return out;
}

void FloeOwners::take_leaving(std::span<const LeaveNotice> notices) {
  std::vector<std::uint32_t> arrived;
  for (const LeaveNotice& k : notices) {
    FLOESIM_ASSERT(k.floe < owner_.size() && k.owner >= 0 && k.owner < ranks_ && owner_[k.floe] != k.owner);
    owner_[k.floe] = k.owner;
    if (k.owner == rank_) arrived.push_back(k.floe);
  }
  // This rank's floes, ascending: its floes that left dropped, those that
  // came to it merged in (a pass over its floes and the notices).
  std::erase_if(mine_, [&](std::uint32_t i) { return owner_[i] != rank_; });
  std::sort(arrived.begin(), arrived.end());
  std::vector<std::uint32_t> merged(mine_.size() + arrived.size());
  std::merge(mine_.begin(), mine_.end(), arrived.begin(), arrived.end(), merged.begin());
  mine_ = std::move(merged);
}

FloeOwners::WindowCharges FloeOwners::close_window(const Communicator& comm, const Floes& floes,
                                                   std::vector<double>& keys) {
  // One call, of sizes known to all (each rank's floe count is in the
  // owner array): each rank's by-place seconds, its row seconds (with
  // slabs) and, for the summary, the coupling's and the fracture analyses'
  // parts of the by-place seconds; then its own floes' keys, ascending.
  FLOESIM_ASSERT(comm.size() == ranks_ && owner_.size() == floes.size());
  WindowCharges w;
  constexpr std::size_t kPerRank = 4;
  std::vector<double> mine = {charged_, row_charged_, coupling_charged_, fracture_charged_};
  for (const std::uint32_t i : mine_) mine.push_back(key(floes.state[i]));
  std::vector<std::size_t> counts(static_cast<std::size_t>(ranks_), kPerRank * sizeof(double));
  for (const int r : owner_) counts[static_cast<std::size_t>(r)] += sizeof(double);
  const std::vector<std::byte> bytes = comm.allgather_known(std::as_bytes(std::span<const double>(mine)), counts);
  // Rank r's message, in rank order: its charges, then its floes' keys.
  charged_ = row_charged_ = coupling_charged_ = fracture_charged_ = 0.0;
  coupling_seconds_.resize(static_cast<std::size_t>(ranks_), 0.0);
  fracture_seconds_.resize(static_cast<std::size_t>(ranks_), 0.0);
  window_seconds_.assign(static_cast<std::size_t>(ranks_), 0.0);
  w.floe.assign(static_cast<std::size_t>(ranks_), 0.0);
  std::vector<std::vector<double>> rank_keys(static_cast<std::size_t>(ranks_));
  const std::byte* in = bytes.data();
  for (std::size_t r = 0; r < static_cast<std::size_t>(ranks_); ++r) {
    const std::vector<double> charges = take<double>(in, kPerRank);
    rank_keys[r] = take<double>(in, counts[r] / sizeof(double) - kPerRank);
    w.floe[r] = charges[0];
    coupling_seconds_[r] += charges[2];
    fracture_seconds_[r] += charges[3];
    w.rows += charges[1];
    window_seconds_[r] = w.floe[r] + charges[1];
  }
  // Each floe's key from its owner, whose floes came in ascending order.
  keys.resize(owner_.size());
  std::vector<std::size_t> next(static_cast<std::size_t>(ranks_), 0);
  for (std::size_t i = 0; i < owner_.size(); ++i) {
    const auto r = static_cast<std::size_t>(owner_[i]);
    keys[i] = rank_keys[r][next[r]++];
  }
  total_seconds_.resize(window_seconds_.size(), 0.0);
  for (std::size_t r = 0; r < window_seconds_.size(); ++r) total_seconds_[r] += window_seconds_[r];
  return w;
}

std::vector<double> FloeOwners::floe_costs(std::span<const double> floe_seconds) const {
  // A floe costs its owner's by-place seconds over its owner's floe count,
  // floored at cost_floor of the mean (StripOptions).
  std::vector<double> count(static_cast<std::size_t>(ranks_), 0.0);
  for (const int r : owner_) count[static_cast<std::size_t>(r)] += 1.0;
  const std::size_t n = owner_.size();
  const double seconds = std::accumulate(floe_seconds.begin(), floe_seconds.end(), 0.0);
  const double floor = n > 0 ? options_.cost_floor * seconds / static_cast<double>(n) : 0.0;
  std::vector<double> cost(n);
  for (std::size_t i = 0; i < n; ++i) {
    const auto r = static_cast<std::size_t>(owner_[i]);
    cost[i] = std::max(floe_seconds[r] / count[r], floor);  // count[r] >= 1: floe i is r's
  }
  return cost;
}

bool FloeOwners::move_slabs(const Communicator& comm, const Floes& floes) {
  // The owners are those at the floes' present places (update): the slabs
  // the floes were charged in.
  std::vector<double> row_of;  // each floe's row, from its owner
  const WindowCharges w = close_window(comm, floes, row_of);
  const int rows = slabs_.rows();
  const int blocks = (rows + slabs_.block - 1) / slabs_.block;
  const double seconds = std::accumulate(window_seconds_.begin(), window_seconds_.end(), 0.0);
  if (!(seconds > 0.0) || blocks < ranks_) return false;
  // Per row: the sea's uniform row cost, plus its floes' costs (above).
  std::vector<double> row_cost(static_cast<std::size_t>(rows), w.rows / rows);
  const std::vector<double> cost = floe_costs(w.floe);
  for (std::size_t i = 0; i < floes.size(); ++i) row_cost[static_cast<std::size_t>(row_of[i])] += cost[i];
  const std::vector<int> target = cut_rows_by_cost(row_cost, slabs_.block, ranks_);
  // Part way, in whole blocks (half a block or more of the way rounds to a
  // block), each slab keeping at least one block.
  std::vector<int> first = slabs_.first_row;
  for (int r = 1; r < ranks_; ++r) {
    const auto k = static_cast<std::size_t>(r);
    const double step = options_.relaxation * (target[k] - first[k]) / slabs_.block;
    int b = first[k] / slabs_.block + static_cast<int>(std::lround(step));
    b = std::max(b, first[k - 1] / slabs_.block + 1);
    b = std::min(b, blocks - (ranks_ - r));
    first[k] = b * slabs_.block;
  }
  if (first == slabs_.first_row) return false;
  RowSlabs moved = slabs_;
  moved.first_row = std::move(first);
  set_slabs(std::move(moved));  // the rows do not change: the keys stay the floes' rows
  ++moves_;
  assign_keys(row_of);
  return true;
}

bool FloeOwners::move_cuts(const Communicator& comm, const Floes& floes) {
  // The owners are those at the floes' present places (update): the strips
  // the floes were charged in.
  std::vector<double> y;  // each floe's place, from its owner
  const WindowCharges w = close_window(comm, floes, y);
  const double seconds = std::accumulate(w.floe.begin(), w.floe.end(), 0.0);
  const std::size_t n = floes.size();
  if (!(seconds > 0.0) || n == 0) return false;
  std::vector<double> cuts = cut_by_cost(y, floe_costs(w.floe), ranks_);
  for (std::size_t k = 0; k < cuts.size(); ++k)  // part way (an infinite cut, an empty strip: all the way)
    if (std::isfinite(cuts[k]) && std::isfinite(cuts_[k])) cuts[k] = cuts_[k] + options_.relaxation * (cuts[k] - cuts_[k]);
  std::sort(cuts.begin(), cuts.end());  // already ascending but for round-off
  const bool moved = cuts != cuts_;
  set_cuts(std::move(cuts));
  ++moves_;
  assign_keys(y);
  return moved;
}

bool FloeOwners::update(const Communicator& comm, const Floes& floes, std::size_t step) {
  bool window = false;
  if (!started_) {
    started_ = true;
    next_move_ = step + static_cast<std::size_t>(options_.rebalance_steps);
  } else if (step >= next_move_) {
    next_move_ = step + static_cast<std::size_t>(options_.rebalance_steps);
    window = true;
  }
  if (!comm.serial() && assigned_for(floes)) migrate(comm, floes);
  else assign(floes);  // the start, after a split, or serially
  if (!window) return false;
  return has_slabs() ? move_slabs(comm, floes) : move_cuts(comm, floes);
}

void FloeOwners::migrate(const Communicator& comm, const Floes& floes) {
  FLOESIM_ASSERT(comm.size() == ranks_ && comm.rank() == rank_);
  // owner_at is a function of the place alone, evaluated by the floe's
  // owner on its copy, the holders' bits: the owner assign() gives on any
  // rank whose copy is current, without reading any other floe.
  const std::vector<LeaveNotice> mine = leaving(rank_, floes);
  const std::vector<LeaveNotice> all = comm.allgather<LeaveNotice>(mine);
  take_leaving(all);
}

namespace {
// h_j at floe j's place y (the one formula of half_band, held_floes and detection_subset).
double half_band_at(double y, const contact::CollisionShapes& shapes, const contact::DetectionOptions& options,
                    std::size_t j) {
  return half_band_for(y, shapes.radius[j], options.reach_of(j), options.collision_distance);
}
}  // namespace

double half_band_for(double y, double radius, double reach, double collision_distance) {
  const double h = radius + reach + 0.5 * collision_distance;
  return h + 1e-9 * (1.0 + std::abs(y) + h);  // posing rounds; a floe held in excess costs only time
}

double half_band(const FloeOwners& owners, const Floes& floes, const contact::CollisionShapes& shapes,
                 const contact::DetectionOptions& options, std::size_t j) {
  return half_band_at(owners.place(floes.state[j]), shapes, options, j);
}

double largest_half_band(const FloeOwners& owners, int rank, const Floes& floes,
                         const contact::CollisionShapes& shapes, const contact::DetectionOptions& options) {
  const std::span<const int> owner = owners.owner();
  FLOESIM_ASSERT(owner.size() == floes.size());
  double largest = 0.0;
  if (rank == owners.rank()) {
    for (const std::uint32_t i : owners.mine()) largest = std::max(largest, half_band(owners, floes, shapes, options, i));
  } else {  // a simulated rank (tests): its floes from the owners
    for (std::size_t i = 0; i < floes.size(); ++i)
      if (owner[i] == rank) largest = std::max(largest, half_band(owners, floes, shapes, options, i));
  }
  return largest;
}

BandStrip band_strip(const FloeOwners& owners, int rank, const Floes& floes, const contact::CollisionShapes& shapes,
                     const contact::DetectionOptions& options) {
  const std::span<const int> owner = owners.owner();
  FLOESIM_ASSERT(owner.size() == floes.size() && rank >= 0 && rank < owners.ranks());
  constexpr double kInf = std::numeric_limits<double>::infinity();
  // The strip S_r; in a periodic box the end strips end at the box's edges
  // (every place lies in the box).
  const std::vector<double>& cuts = owners.cuts();
  BandStrip out;
  out.lo = rank == 0 ? -kInf : cuts[static_cast<std::size_t>(rank) - 1];
  out.hi = rank == owners.ranks() - 1 ? kInf : cuts[static_cast<std::size_t>(rank)];
  const contact::Domain& box = options.domain;
  if (box.periodic) {
    out.lo = std::max(out.lo, box.ymin);
    out.hi = std::min(out.hi, box.ymax);
  }
  // The strip widened to the rank's own floes' places: they lie in it but
  // for round-off (the slabs own by grid row), or but for the grid's wrap
  // (with the sea's slabs, a floe beyond the grid in an open box is owned
  // by the row it wraps to). The band's argument needs y_a in S_r for each
  // own floe a.
  const auto widen = [&](std::size_t j) {
    const double y = owners.place(floes.state[j]);
    out.lo = std::min(out.lo, y);
    out.hi = std::max(out.hi, y);
    out.largest = std::max(out.largest, half_band_at(y, shapes, options, j));
  };
  if (rank == owners.rank()) {
    for (const std::uint32_t j : owners.mine()) widen(j);
  } else {  // a simulated rank (tests): its floes from the owners
    for (std::size_t j = 0; j < floes.size(); ++j)
      if (owner[j] == rank) widen(j);
  }
  return out;
}

double strip_distance(double y, const BandStrip& strip, const contact::Domain& box) {
  const auto distance = [&](double at) { return std::max({0.0, strip.lo - at, at - strip.hi}); };
  double gap = distance(y);
  if (box.periodic) gap = std::min({gap, distance(y - box.height()), distance(y + box.height())});
  return gap;
}

HeldFloes held_floes(const FloeOwners& owners, int rank, const Floes& floes, const contact::CollisionShapes& shapes,
                     const contact::DetectionOptions& options, double largest) {
  const std::size_t n = floes.size();
  const std::span<const int> owner = owners.owner();
  const BandStrip strip = band_strip(owners, rank, floes, shapes, options);
  HeldFloes out;
  out.largest = largest;
  out.mask.assign(n, 0);
  for (std::size_t j = 0; j < n; ++j) {
    bool held = owner[j] == rank;
    if (!held) {
      const double y = owners.place(floes.state[j]);
      held = strip_distance(y, strip, options.domain) <= largest + half_band_at(y, shapes, options, j);
    }
    if (!held) continue;
    out.mask[j] = 1;
    out.index.push_back(static_cast<std::uint32_t>(j));
  }
  return out;
}

HeldFloes every_floe(std::size_t n) {
  HeldFloes out;
  out.mask.assign(n, 1);
  out.index.resize(n);
  std::iota(out.index.begin(), out.index.end(), 0u);
  out.largest = std::numeric_limits<double>::infinity();
  return out;
}

contact::DetectionSubset detection_subset(const FloeOwners& owners, int rank, const Floes& floes,
                                          const contact::CollisionShapes& shapes,
                                          const contact::DetectionOptions& options, const HeldFloes* held) {
  const std::size_t n = floes.size();
  const std::span<const int> owner = owners.owner();
  FLOESIM_ASSERT(owner.size() == n && (!held || held->mask.size() == n));
  const contact::Domain& d = options.domain;
  contact::DetectionSubset subset;
  subset.keep.assign(n, 0);
  // The floes read: the held ones (the posed floes are among them), or every floe.
  std::vector<std::uint32_t> all;
  if (!held) {
    all.resize(n);
    std::iota(all.begin(), all.end(), 0u);
  }
  const std::span<const std::uint32_t> read = held ? std::span<const std::uint32_t>(held->index) : std::span<const std::uint32_t>(all);
  // Each floe's band: centre y (wrapped), half width R + reach + xi/2, widened
  // by a round-off margin (half_band).
  std::vector<double> y(read.size()), half(read.size());
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (std::size_t k = 0; k < read.size(); ++k) {
    const std::uint32_t i = read[k];
    y[k] = owners.place(floes.state[i]);
    half[k] = half_band_at(y[k], shapes, options, i);
    if (owner[i] != rank) continue;
    subset.keep[i] = 1;
    lo = std::min(lo, y[k] - half[k]);
    hi = std::max(hi, y[k] + half[k]);
  }
  if (!(lo <= hi)) return subset;  // no floe of its own: nothing to pose
  const double centre = 0.5 * (lo + hi), width = 0.5 * (hi - lo);
  for (std::size_t k = 0; k < read.size(); ++k) {
    const std::uint32_t i = read[k];
    bool near = subset.keep[i] != 0;
    if (!near && d.periodic) {
      // The nearest image of the floe's centre (any whole number of periods).
      double gap = y[k] - centre;
      gap -= d.height() * std::round(gap / d.height());
      near = std::abs(gap) <= width + half[k];
    } else if (!near) {
      near = y[k] + half[k] >= lo && y[k] - half[k] <= hi;
    }
    if (near) subset.posed.push_back(i);
  }
  return subset;
}

}  // namespace floesim::parallel
