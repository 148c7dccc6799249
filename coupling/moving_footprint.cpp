#include "coupling/moving_footprint.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "coupling/parallel.hpp"

namespace floesim {

MovingFootprints::MovingFootprints(const fluid::SurfaceGrid& grid, FootprintKernel kernel,
                                   FootprintMotionOptions options)
    : grid_(grid), kernel_(kernel), options_(options) {}

FloePose MovingFootprints::displacement(std::size_t i, const FloePose& at) const {
  const FloePose& p0 = reference_[i];
  FloePose d{at.x - p0.x, at.y - p0.y, at.yaw - p0.yaw};
  if (grid_.edge == fluid::GridEdge::periodic) {
    d.x -= grid_.lx * std::round(d.x / grid_.lx);
    if (grid_.dims == 2) d.y -= grid_.ly * std::round(d.y / grid_.ly);
  }
  return d;
}

bool MovingFootprints::inside_windows(const Floes& floes, std::span<const FloePose> poses) const {
  if (options_.reach <= 0.0 || reference_.size() != floes.size()) return false;
  const double reach_x = options_.reach * grid_.dx(), reach_y = options_.reach * grid_.dy();
  for (std::size_t i = 0; i < floes.size(); ++i) {
    if (!include_[i]) continue;
    const FloePose d = displacement(i, poses[i]);
    const double turn = radius_[i] * std::abs(d.yaw);
    // A long-crested sea's strips span its width: only x moves a floe across them.
    if (std::abs(d.x) + turn > reach_x || (grid_.dims == 2 && std::abs(d.y) + turn > reach_y)) return false;
  }
  return true;
}

bool MovingFootprints::place(const Floes& floes, std::span<const std::uint8_t> include,
                             std::span<const FloePose> poses, int threads) {
  ++placements_;
  const bool same_floes = include_.size() == include.size() && std::equal(include.begin(), include.end(), include_.begin());
  if (same_floes && inside_windows(floes, poses)) {
    move(poses, threads);
    return false;
  }
  rebuild_at(floes, include, poses, threads);
  return true;
}

void MovingFootprints::rebuild_at(const Floes& floes, std::span<const std::uint8_t> include,
                                  std::span<const FloePose> reference, int threads) {
  ++rebuilds_;
  if (comm_.serial()) {
    build_footprints(floes, include, grid_, pieces_, kernel_, threads, reference);
  } else {
    const parallel::Range mine = owned(floes.size());
    std::vector<std::uint8_t> mask(include.size(), 0);
    const auto from = static_cast<std::ptrdiff_t>(mine.begin), to = static_cast<std::ptrdiff_t>(mine.end);
    std::copy(include.begin() + from, include.begin() + to, mask.begin() + from);
    build_footprints(floes, mask, grid_, pieces_, kernel_, threads, reference);
    if (gather_) gather_built();
  }
  reference_.assign(reference.begin(), reference.end());
  include_.assign(include.begin(), include.end());
  radius_.assign(floes.size(), 0.0);
  for (std::size_t i = 0; i < floes.size(); ++i)
    for (const Vec2& v : floes.vertices(i)) radius_[i] = std::max(radius_[i], v.norm());
  area0_ = pieces_.area;
  moment0_.resize(area0_.size());
  for (std::size_t k = 0; k < area0_.size(); ++k) moment0_[k] = area0_[k] * pieces_.centroid[k];
}

void MovingFootprints::move(std::span<const FloePose> poses, int threads) {
  Footprints& fp = pieces_;
  const parallel::Range mine = owned(fp.floes());
  parallel::for_each_index(mine.size(), threads, [&](std::size_t j) {
    const std::size_t i = mine.begin + j;
    if (fp.offsets[i] == fp.offsets[i + 1]) return;
    const FloePose d = displacement(i, poses[i]);
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

void MovingFootprints::gather_built() {
  // pieces_ holds this rank's floes' pieces only (the other floes have none).
  // Message: the pieces per floe of the share, then their cells, areas and
  // centroids; the ranks' messages come back in rank order = floe order.
  Footprints& fp = pieces_;
  const std::size_t n = fp.floes();
  const parallel::Range mine = owned(n);
  const std::size_t first = fp.offsets[mine.begin], count = fp.offsets[mine.end] - first;
  std::vector<std::uint64_t> per_floe(mine.size());
  for (std::size_t j = 0; j < mine.size(); ++j)
    per_floe[j] = fp.offsets[mine.begin + j + 1] - fp.offsets[mine.begin + j];
  std::vector<std::byte> message;
  message.reserve(per_floe.size() * 8 + count * (4 + 8 + 16));
  put(message, per_floe.data(), per_floe.size());
  put(message, fp.cell.data() + first, count);
  put(message, fp.area.data() + first, count);
  put(message, fp.centroid.data() + first, count);
  std::vector<std::size_t> sizes;
  const std::vector<std::byte> all = comm_.allgather_bytes(message, sizes);

  Footprints full;
  full.offsets.assign(1, 0);
  const std::byte* in = all.data();
  for (int r = 0; r < comm_.size(); ++r) {
    const parallel::Range share = parallel::share(n, r, comm_.size());
    per_floe.resize(share.size());
    in = take(in, per_floe.data(), per_floe.size());
    std::size_t pieces = 0;
    for (std::uint64_t c : per_floe) {
      pieces += c;
      full.offsets.push_back(full.offsets.back() + c);
    }
    const std::size_t at = full.cell.size();
    full.cell.resize(at + pieces);
    full.area.resize(at + pieces);
    full.centroid.resize(at + pieces);
    in = take(in, full.cell.data() + at, pieces);
    in = take(in, full.area.data() + at, pieces);
    in = take(in, full.centroid.data() + at, pieces);
  }
  // This rank's edge pieces point into the full list of area pieces.
  const auto shift = static_cast<std::ptrdiff_t>(full.offsets[mine.begin]) - static_cast<std::ptrdiff_t>(first);
  for (std::ptrdiff_t& p : fp.edge_piece)
    if (p >= 0) p += shift;
  fp.offsets = std::move(full.offsets);
  fp.cell = std::move(full.cell);
  fp.area = std::move(full.area);
  fp.centroid = std::move(full.centroid);
}

void MovingFootprints::gather_moved() {
  // Every rank knows where each floe's pieces lie (the last build's layout):
  // one call, the shares' areas then centroids.
  Footprints& fp = pieces_;
  const std::size_t n = fp.floes();
  std::vector<std::size_t> sizes(static_cast<std::size_t>(comm_.size()));
  for (int r = 0; r < comm_.size(); ++r) {
    const parallel::Range share = parallel::share(n, r, comm_.size());
    const std::size_t pieces = fp.offsets[share.end] - fp.offsets[share.begin];
    sizes[static_cast<std::size_t>(r)] = pieces * (sizeof(double) + sizeof(Vec2));
  }
  const parallel::Range mine = owned(n);
  const std::size_t first = fp.offsets[mine.begin], count = fp.offsets[mine.end] - first;
  std::vector<std::byte> message;
  message.reserve(count * (sizeof(double) + sizeof(Vec2)));
  put(message, fp.area.data() + first, count);
  put(message, fp.centroid.data() + first, count);
  const std::vector<std::byte> all = comm_.allgather_known(message, sizes);
  const std::byte* in = all.data();
  for (int r = 0; r < comm_.size(); ++r) {
    const parallel::Range share = parallel::share(n, r, comm_.size());
    const std::size_t at = fp.offsets[share.begin], pieces = fp.offsets[share.end] - at;
    in = take(in, fp.area.data() + at, pieces);
    in = take(in, fp.centroid.data() + at, pieces);
  }
}

}  // namespace floesim
