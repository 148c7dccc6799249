#include "coupling/moving_footprint.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <tuple>

#include "core/error.hpp"
#include "coupling/parallel.hpp"
#include "coupling/shared_cells.hpp"
#include "parallel/cell_routes.hpp"
#include "parallel/place.hpp"

namespace floesim {

MovingFootprints::MovingFootprints(const fluid::SurfaceGrid& grid, FootprintKernel kernel,
                                   FootprintMotionOptions options)
    : grid_(grid), kernel_(kernel), options_(options) {
  FLOESIM_ASSERT(options.fit_slack >= 0.0 && options.fit_spare >= 0.0);
}

FloePose window_displacement(const fluid::SurfaceGrid& grid, const FloePose& reference, const FloePose& at) {
  FloePose d{at.x - reference.x, at.y - reference.y, at.yaw - reference.yaw};
  if (grid.edge == fluid::GridEdge::periodic) {
    d.x -= grid.lx * std::round(d.x / grid.lx);
    if (grid.dims == 2) d.y -= grid.ly * std::round(d.y / grid.ly);
  }
  return d;
}

bool inside_windows(std::span<const std::uint32_t> floes, std::span<const std::uint8_t> include,
                    std::span<const FloePose> reference, std::span<const FloePose> poses, std::span<const double> radius,
                    const fluid::SurfaceGrid& grid, double reach) {
  const double reach_x = reach * grid.dx(), reach_y = reach * grid.dy();
  for (const std::uint32_t i : floes) {
    if (!include[i]) continue;
    const FloePose d = window_displacement(grid, reference[i], poses[i]);
    const double turn = radius[i] * std::abs(d.yaw);
    // A long-crested sea's strips span its width: only x moves a floe across them.
    if (std::abs(d.x) + turn > reach_x || (grid.dims == 2 && std::abs(d.y) + turn > reach_y)) return false;
  }
  return true;
}

bool MovingFootprints::movable(std::span<const std::uint8_t> include, std::span<const FloePose> poses) const {
  // The same on every rank: the reach, the reference's size and the
  // included floes are replicated, so the ranks return here together.
  if (options_.reach <= 0.0 || reference_.size() != poses.size()) return false;
  if (include_.size() != include.size() || !std::equal(include.begin(), include.end(), include_.begin())) return false;
  const bool inside = inside_windows(mine_, include_, reference_, poses, radius_, grid_, options_.reach);
  if (comm_.serial()) return inside;
  // Every rank's floes inside (mine_ partitions the floes: set_owners).
  return comm_.min(inside ? 1 : 0) == 1;
}

bool MovingFootprints::place(const Floes& floes, std::span<const std::uint8_t> include,
                             std::span<const FloePose> poses, int threads) {
  return place(floes, include, poses, threads, movable(include, poses));
}

bool MovingFootprints::place(const Floes& floes, std::span<const std::uint8_t> include,
                             std::span<const FloePose> poses, int threads, bool move_pieces,
                             std::span<const int> owners) {
  ++placements_;
  if (move_pieces) {
    move(poses, threads);
    return false;
  }
  rebuild_at(floes, include, poses, threads, owners);
  return true;
}

bool MovingFootprints::takes_owners(std::span<const int> first_row) const {
  if (comm_.serial() || row_owner_.empty()) return false;
  const std::vector<int>& rows = next_owner_rows_.empty() ? owner_rows_ : next_owner_rows_;
  return std::equal(rows.begin(), rows.end(), first_row.begin(), first_row.end());
}

std::vector<FloePose> MovingFootprints::whole_reference() const {
  std::vector<FloePose> all = reference_;
  if (!reference_whole_ && !comm_.serial()) comm_.complete_owned(all, owner_);
  return all;
}

void MovingFootprints::set_slabs(std::vector<int> first_row) {
  row_owner_ = parallel::row_owners(first_row);
  owner_rows_ = first_row;
  next_owner_rows_.clear();
  sea_rows_ = std::move(first_row);
  FLOESIM_ASSERT(row_owner_.empty() || static_cast<int>(row_owner_.size()) == grid_.ny);
}

int MovingFootprints::reach_rows_from(std::span<const int> first_row) const {
  // The owners' slabs moved away from first_row (stage seven): a floe's
  // pieces lie within piece_rows_ of its owner's slab, which is at most the
  // largest move of a cut away from the owner's slab in first_row.
  int moved = 0;
  if (first_row.size() == owner_rows_.size())
    for (std::size_t r = 0; r < first_row.size(); ++r) moved = std::max(moved, std::abs(first_row[r] - owner_rows_[r]));
  return piece_rows_ + moved;
}

void MovingFootprints::set_owners(std::span<const FloePose> poses, std::span<const int> owners) {
  const std::size_t n = poses.size();
  // Kept (keep_owners): the owners are those of the last rebuild, in place.
  const bool keep = std::exchange(keep_owners_, false);
  // (owners() given without keep_owners() would be cleared before its copy.)
  FLOESIM_ASSERT(keep ? owner_.size() == n && (owners.empty() || owners.data() == owner_.data())
                      : owners.empty() || owners.data() != owner_.data());
  if (!keep) owner_.assign(n, 0);
  by_place_ = !comm_.serial() && !row_owner_.empty();
  if (by_place_ && !next_owner_rows_.empty()) {
    // The sea's slabs moved since the last rebuild: the owners follow them.
    row_owner_ = parallel::row_owners(next_owner_rows_);
    owner_rows_ = std::move(next_owner_rows_);
    next_owner_rows_.clear();
  }
  reference_whole_ = true;
  if (keep) {
    reference_whole_ = false;  // the poses of this rank's floes only
  } else if (!comm_.serial() && !owners.empty()) {
    // Given: by place on these slabs (takes_owners: the rule below, applied
    // by their maker at the same poses), or without slabs by their maker's
    // rule (a sea not in slabs: FloeSeaContact's strips).
    FLOESIM_ASSERT(owners.size() == n);
    std::copy(owners.begin(), owners.end(), owner_.begin());
    reference_whole_ = false;
  } else if (by_place_) {
    // The row of the centroid, the grid's seam crossed (periodic).
    const double dy = grid_.dy();
    for (std::size_t i = 0; i < n; ++i) owner_[i] = row_owner_[static_cast<std::size_t>(parallel::grid_row(poses[i].y, dy, grid_.ny))];
  } else if (!comm_.serial()) {
    for (int r = 0; r < comm_.size(); ++r) {
      const parallel::Range share = parallel::share(n, r, comm_.size());
      std::fill(owner_.begin() + static_cast<std::ptrdiff_t>(share.begin), owner_.begin() + static_cast<std::ptrdiff_t>(share.end), r);
    }
  }
  mine_.clear();
  for (std::size_t i = 0; i < n; ++i)
    if (owner_[i] == comm_.rank()) mine_.push_back(static_cast<std::uint32_t>(i));
}

namespace {

// Copies `v` into an array with o.fit_spare times its size spare when its
// spare capacity exceeds o.fit_slack times its size
// (FootprintMotionOptions: why).
template <class T>
void fit(std::vector<T>& v, const FootprintMotionOptions& o) {
  const auto share = [&](double fraction) {
    return static_cast<std::size_t>(fraction * static_cast<double>(v.size()));
  };
  if (v.capacity() - v.size() <= share(o.fit_slack)) return;
  std::vector<T> kept;
  kept.reserve(v.size() + share(o.fit_spare));
  kept.assign(v.begin(), v.end());
  v.swap(kept);
}

void fit(Footprints& f, const FootprintMotionOptions& o) {
  std::apply([&](auto&... v) { (fit(v, o), ...); },
             std::tie(f.offsets, f.cell, f.area, f.centroid, f.edge_offsets, f.edge_cell, f.edge_piece, f.edge_length,
                      f.edge_normal, f.edge_twist, f.edge_first, f.edge_swept));
}

}  // namespace

void MovingFootprints::rebuild_at(const Floes& floes, std::span<const std::uint8_t> include,
                                  std::span<const FloePose> reference, int threads, std::span<const int> owners) {
  ++rebuilds_;
  set_owners(reference, owners);
  if (comm_.serial()) {
    build_footprints(floes, include, grid_, pieces_, kernel_, threads, reference);
  } else {
    const double start = parallel::thread_seconds();
    std::vector<std::uint8_t> mask(include.size(), 0);
    for (std::uint32_t i : mine_) mask[i] = include[i];
    build_footprints(floes, mask, grid_, pieces_, kernel_, threads, reference);
    owned_seconds_ += parallel::thread_seconds() - start;
    if (gather_) gather_built();
  }
  reference_.assign(reference.begin(), reference.end());
  include_.assign(include.begin(), include.end());
  // R of every floe: its outline's, so made again only when the floes
  // changed (forget()); the largest over the included floes bounds the
  // pieces' rows on every rank alike.
  if (radius_.size() != floes.size()) {
    radius_.assign(floes.size(), 0.0);
    for (std::size_t i = 0; i < floes.size(); ++i)
      for (const Vec2& v : floes.vertices(i)) radius_[i] = std::max(radius_[i], v.norm());
  }
  double largest = 0.0;
  for (std::size_t i = 0; i < floes.size(); ++i)
    if (include[i]) largest = std::max(largest, radius_[i]);
  piece_rows_ = piece_rows_of(largest, options_.reach, grid_.dy());
  fit(pieces_, options_);
  area0_ = pieces_.area;
  moment0_.resize(area0_.size());
  for (std::size_t k = 0; k < area0_.size(); ++k) moment0_[k] = area0_[k] * pieces_.centroid[k];
  fit(area0_, options_);
  fit(moment0_, options_);
}

void MovingFootprints::move(std::span<const FloePose> poses, int threads) {
  Footprints& fp = pieces_;
  const double start = comm_.serial() ? 0.0 : parallel::thread_seconds();
  parallel::for_each_index(mine_.size(), threads, [&](std::size_t j) {
    const std::size_t i = mine_[j];
    if (fp.offsets[i] == fp.offsets[i + 1]) return;
    const FloePose d = window_displacement(grid_, reference_[i], poses[i]);
    const Vec2 delta{d.x, d.y};
    // Interior nodes stay where they are while G moves by delta.
    for (std::size_t k = fp.offsets[i]; k < fp.offsets[i + 1]; ++k) {
      fp.area[k] = area0_[k];
      fp.centroid[k] = moment0_[k] - area0_[k] * delta;  // the moment for now
    }
    // Nodes the outline crosses: the outline integrals' first-order terms.
    for (std::size_t e = fp.edge_offsets[i]; e < fp.edge_offsets[i + 1]; ++e) {
      const std::ptrdiff_t k = fp.edge_piece[e];
      if (k < 0) continue;
      fp.area[k] += fp.edge_normal[e].dot(delta) + fp.edge_twist[e] * d.yaw;
      fp.centroid[k] += fp.edge_first[e] * delta + fp.edge_swept[e] * d.yaw;
    }
    for (std::size_t k = fp.offsets[i]; k < fp.offsets[i + 1]; ++k) {
      const Vec2 moment = fp.centroid[k];
      if (fp.area[k] > 0.0) {
        fp.centroid[k] = moment / fp.area[k];
      } else {  // a node the floe is leaving
        fp.area[k] = 0.0;
        fp.centroid[k] = area0_[k] > 0.0 ? Vec2(moment0_[k] / area0_[k] - delta) : Vec2::Zero();
      }
    }
  }, static_cast<std::size_t>(parallel::kFloesPerThread));
  if (!comm_.serial()) owned_seconds_ += parallel::thread_seconds() - start;
  if (!comm_.serial() && gather_) gather_moved();
}

namespace {

// Bytes of a message, appended and read back in order.
template <class T>
void put(std::vector<std::byte>& out, const T* data, std::size_t count) {
  const auto* b = reinterpret_cast<const std::byte*>(data);
  out.insert(out.end(), b, b + count * sizeof(T));
}
template <class T>
const std::byte* take(const std::byte* in, T* data, std::size_t count) {
  std::memcpy(static_cast<void*>(data), in, count * sizeof(T));
  return in + count * sizeof(T);
}

}  // namespace

const Footprints& MovingFootprints::every_floe(Footprints& scratch) const {
  if (comm_.serial() || gather_) return pieces_;
  gather_area_pieces(scratch);
  return scratch;
}

void MovingFootprints::gather_area_pieces(Footprints& full) const {
  // pieces_ holds this rank's floes' pieces only (the other floes have none),
  // in floe order. Message: the pieces per floe of mine_, then their cells,
  // areas and centroids. Every rank knows every floe's owner: each floe's
  // pieces are taken from its owner's message, in floe order.
  const Footprints& fp = pieces_;
  const std::size_t n = fp.floes(), count = fp.cell.size();
  std::vector<std::uint64_t> per_floe(mine_.size());
  for (std::size_t j = 0; j < mine_.size(); ++j) per_floe[j] = fp.offsets[mine_[j] + 1] - fp.offsets[mine_[j]];
  std::vector<std::byte> message;
  message.reserve(per_floe.size() * 8 + count * (4 + 8 + 16));
  put(message, per_floe.data(), per_floe.size());
  put(message, fp.cell.data(), count);
  put(message, fp.area.data(), count);
  put(message, fp.centroid.data(), count);
  std::vector<std::size_t> sizes;
  const std::vector<std::byte> all = comm_.allgather_bytes(message, sizes);

  // Each rank's message: its floes' counts, and where its cells, areas and centroids start.
  const std::size_t ranks = sizes.size();
  std::vector<std::size_t> floes_of(ranks, 0);
  for (int o : owner_) ++floes_of[static_cast<std::size_t>(o)];
  struct Stream {
    const std::byte* counts;
    const std::byte* cell;
    const std::byte* area;
    const std::byte* centroid;
    std::size_t floe = 0, piece = 0;  // cursors
  };
  std::vector<Stream> stream(ranks);
  const std::byte* in = all.data();
  for (std::size_t r = 0; r < ranks; ++r) {
    const std::size_t pieces = (sizes[r] - floes_of[r] * sizeof(std::uint64_t)) / (sizeof(std::uint32_t) + sizeof(double) + sizeof(Vec2));
    stream[r].counts = in;
    stream[r].cell = in + floes_of[r] * sizeof(std::uint64_t);
    stream[r].area = stream[r].cell + pieces * sizeof(std::uint32_t);
    stream[r].centroid = stream[r].area + pieces * sizeof(double);
    in += sizes[r];
  }
  full = Footprints{};
  full.offsets.assign(n + 1, 0);
  for (std::size_t i = 0; i < n; ++i) {
    Stream& s = stream[static_cast<std::size_t>(owner_[i])];
    std::uint64_t c = 0;
    std::memcpy(&c, s.counts + s.floe++ * sizeof(std::uint64_t), sizeof(c));
    full.offsets[i + 1] = full.offsets[i] + c;
  }
  const std::size_t total = full.offsets[n];
  full.cell.resize(total);
  full.area.resize(total);
  full.centroid.resize(total);
  for (std::size_t i = 0; i < n; ++i) {
    Stream& s = stream[static_cast<std::size_t>(owner_[i])];
    const std::size_t at = full.offsets[i], pieces = full.offsets[i + 1] - at;
    take(s.cell + s.piece * sizeof(std::uint32_t), full.cell.data() + at, pieces);
    take(s.area + s.piece * sizeof(double), full.area.data() + at, pieces);
    take(s.centroid + s.piece * sizeof(Vec2), full.centroid.data() + at, pieces);
    s.piece += pieces;
  }
}

void MovingFootprints::gather_built() {
  Footprints& fp = pieces_;
  Footprints full;
  gather_area_pieces(full);
  // This rank's edge pieces point into the full list of area pieces.
  for (std::uint32_t i : mine_) {
    const auto shift = static_cast<std::ptrdiff_t>(full.offsets[i]) - static_cast<std::ptrdiff_t>(fp.offsets[i]);
    for (std::size_t e = fp.edge_offsets[i]; e < fp.edge_offsets[i + 1]; ++e)
      if (fp.edge_piece[e] >= 0) fp.edge_piece[e] += shift;
  }
  fp.offsets = std::move(full.offsets);
  fp.cell = std::move(full.cell);
  fp.area = std::move(full.area);
  fp.centroid = std::move(full.centroid);
}

void MovingFootprints::gather_moved() {
  // Every rank knows where each floe's pieces lie (the last build's layout)
  // and each floe's owner: one call, each rank's floes' areas then centroids.
  Footprints& fp = pieces_;
  const std::size_t n = fp.floes(), ranks = static_cast<std::size_t>(comm_.size());
  std::vector<std::size_t> pieces_of(ranks, 0), sizes(ranks);
  for (std::size_t i = 0; i < n; ++i) pieces_of[static_cast<std::size_t>(owner_[i])] += fp.offsets[i + 1] - fp.offsets[i];
  for (std::size_t r = 0; r < ranks; ++r) sizes[r] = pieces_of[r] * (sizeof(double) + sizeof(Vec2));
  std::vector<std::byte> message;
  message.reserve(sizes[static_cast<std::size_t>(comm_.rank())]);
  for (std::uint32_t i : mine_) put(message, fp.area.data() + fp.offsets[i], fp.offsets[i + 1] - fp.offsets[i]);
  for (std::uint32_t i : mine_) put(message, fp.centroid.data() + fp.offsets[i], fp.offsets[i + 1] - fp.offsets[i]);
  const std::vector<std::byte> all = comm_.allgather_known(message, sizes);
  std::vector<const std::byte*> area(ranks), centroid(ranks);
  const std::byte* in = all.data();
  for (std::size_t r = 0; r < ranks; ++r) {
    area[r] = in;
    centroid[r] = in + pieces_of[r] * sizeof(double);
    in += sizes[r];
  }
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t r = static_cast<std::size_t>(owner_[i]), at = fp.offsets[i], pieces = fp.offsets[i + 1] - at;
    area[r] = take(area[r], fp.area.data() + at, pieces);
    centroid[r] = take(centroid[r], fp.centroid.data() + at, pieces);
  }
}

MovingFootprints::Memory MovingFootprints::memory(std::span<const std::uint8_t> held) const {
  const std::size_t k = held_count(held, pieces_.floes());
  const Footprints& f = pieces_;
  Memory m;
  m.per_floe = per_floe_bytes(reference_, k);
  m.per_floe += per_floe_bytes(include_, k);
  m.per_floe += per_floe_bytes(radius_, k);
  m.per_floe += per_floe_bytes(owner_, k);
  m.per_floe += {capacity_bytes(mine_), capacity_bytes(mine_)};  // this rank's own floes: held already
  m.area_pieces = csr_bytes(f.offsets,
                            capacity_bytes(f.cell) + capacity_bytes(f.area) + capacity_bytes(f.centroid) +
                                capacity_bytes(area0_) + capacity_bytes(moment0_),
                            sizeof(std::uint32_t) + sizeof(double) + sizeof(Vec2) + sizeof(double) + sizeof(Vec2), held);
  m.edge_pieces = csr_bytes(f.edge_offsets,
                            capacity_bytes(f.edge_cell) + capacity_bytes(f.edge_piece) + capacity_bytes(f.edge_length) +
                                capacity_bytes(f.edge_normal) + capacity_bytes(f.edge_twist) +
                                capacity_bytes(f.edge_first) + capacity_bytes(f.edge_swept),
                            sizeof(std::uint32_t) + sizeof(std::ptrdiff_t) + sizeof(double) + sizeof(Vec2) +
                                sizeof(double) + sizeof(Eigen::Matrix2d) + sizeof(Vec2),
                            held);
  return m;
}

}  // namespace floesim
