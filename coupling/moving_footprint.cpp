#include "coupling/moving_footprint.hpp"

#include <algorithm>
#include <cmath>

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
  build_footprints(floes, include, grid_, pieces_, kernel_, threads, reference);
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
  parallel::for_each_index(fp.floes(), threads, [&](std::size_t i) {
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
}

}  // namespace floesim
