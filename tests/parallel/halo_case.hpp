#pragma once
// The poison tool of the state held by owner with a halo (docs/parallel.md,
// "The state held by owner with a halo (plan)"), shared by test_halo.cpp and
// test_halo_split.cpp: a copy of the floes in which every floe a simulated
// rank should not hold is NaN (its state and the per-floe data held with
// it), the halo band B_r that a rank holds, and the dense moving pack the
// proofs run on.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "contact/detection.hpp"
#include "contact/shapes.hpp"
#include "core/pack_generator.hpp"
#include "coupling/drift.hpp"
#include "parallel/detect.hpp"
#include "parallel/place.hpp"
#include "tests/parallel/collide_case.hpp"

namespace floesim::test {

inline constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Per floe: 1 if the simulated rank holds it.
using Held = std::vector<std::uint8_t>;

// ---- The poison tool ----------------------------------------------------

inline void poison(double& x) { x = kNaN; }
inline void poison(FloeState& s) {
  double* d = reinterpret_cast<double*>(&s);
  std::fill_n(d, kStateColumns, kNaN);
}

// A copy of `floes` with every floe not held poisoned: its state and its
// per-floe numbers (the flags and ids, which are not state, stay).
inline Floes poisoned(const Floes& floes, const Held& held) {
  Floes out = floes;
  for (std::size_t i = 0; i < out.size(); ++i) {
    if (held[i]) continue;
    poison(out.state[i]);
    for (std::vector<double>* v : {&out.thickness, &out.density, &out.area, &out.mass, &out.inertia_z, &out.inertia_x,
                                   &out.inertia_y, &out.ocean_drag})
      poison((*v)[i]);
    for (std::size_t k = out.offsets[i]; k < out.offsets[i + 1]; ++k) out.body[k] = Vec2::Constant(kNaN);
  }
  return out;
}
inline std::vector<FloeState> poisoned(std::vector<FloeState> states, const Held& held) {
  for (std::size_t i = 0; i < states.size(); ++i)
    if (!held[i]) poison(states[i]);
  return states;
}
inline std::vector<double> poisoned(std::vector<double> per_floe, const Held& held) {
  for (std::size_t i = 0; i < per_floe.size(); ++i)
    if (!held[i]) poison(per_floe[i]);
  return per_floe;
}
inline contact::CollisionShapes poisoned(contact::CollisionShapes shapes, const Held& held) {
  for (std::size_t i = 0; i < held.size(); ++i) {
    if (held[i]) continue;
    poison(shapes.radius[i]);
    for (std::size_t p = shapes.parts_begin(i); p < shapes.parts_end(i); ++p)
      for (std::size_t k = shapes.vertex_offsets[p]; k < shapes.vertex_offsets[p + 1]; ++k)
        shapes.vertices[k] = Vec2::Constant(kNaN);
  }
  return shapes;
}
inline FootprintQuadrature poisoned(FootprintQuadrature q, const Held& held) {
  for (std::size_t i = 0; i < held.size(); ++i) {
    if (held[i]) continue;
    for (std::size_t k = q.first[i]; k < q.first[i] + q.count[i]; ++k) {
      q.point[k] = Vec2::Constant(kNaN);
      q.weight[k] = kNaN;
    }
  }
  return q;
}

inline bool all_nan(const FloeState& s) {
  const double* d = reinterpret_cast<const double*>(&s);
  return std::all_of(d, d + kStateColumns, [](double x) { return std::isnan(x); });
}
inline std::size_t count_held(const Held& held) { return static_cast<std::size_t>(std::count(held.begin(), held.end(), 1)); }

// ---- The halo band (docs/parallel.md, "The band"; parallel::held_floes) ---

// H as a run gets it: each simulated rank's largest_half_band (its own
// floes'), then their largest (the reduction, Communicator::max).
inline double largest_by_ranks(const parallel::FloeOwners& owners, const Floes& floes,
                               const contact::CollisionShapes& shapes, const contact::DetectionOptions& d) {
  double largest = 0.0;
  for (int r = 0; r < owners.ranks(); ++r)
    largest = std::max(largest, parallel::largest_half_band(owners, r, floes, shapes, d));
  return largest;
}

// The band's rule written out here, from the definition (the reference the
// library's held_floes is checked against): the floes whose place lies
// within H + h_j of the strip [cut[rank-1], cut[rank]) (the box's edges for
// the end strips of a periodic box), across the seam by the nearest image,
// H the largest h_j over the whole pack. A candidate pair's padded boxes
// overlap, so |y_a - y_b| <= h_a + h_b, and floe a lies in the strip: b
// lies within h_a + h_b <= H + h_b of it. With `one_pad` the band is the
// strip widened by H alone (too thin: the mutation the tests name).
inline Held halo_band_by_rule(const parallel::FloeOwners& owners, int rank, const Floes& floes,
                              const contact::CollisionShapes& shapes, const contact::DetectionOptions& d,
                              bool one_pad = false) {
  const std::size_t n = floes.size();
  constexpr double kInf = std::numeric_limits<double>::infinity();
  // h_j = R_j + reach_j + xi/2, with detection_subset's round-off margin.
  const auto half_band = [&](std::size_t j) {
    const double y = owners.place(floes.state[j]);
    const double h = shapes.radius[j] + d.reach_of(j) + 0.5 * d.collision_distance;
    return h + 1e-9 * (1.0 + std::abs(y) + h);
  };
  double largest = 0.0;  // H over the whole pack
  for (std::size_t j = 0; j < n; ++j) largest = std::max(largest, half_band(j));
  const std::vector<double>& cuts = owners.cuts();
  double lo = rank == 0 ? -kInf : cuts[static_cast<std::size_t>(rank) - 1];
  double hi = rank == owners.ranks() - 1 ? kInf : cuts[static_cast<std::size_t>(rank)];
  const contact::Domain& box = d.domain;
  if (box.periodic) {
    lo = std::max(lo, box.ymin);
    hi = std::min(hi, box.ymax);
  }
  Held held(n, 0);
  for (std::size_t j = 0; j < n; ++j) {
    if (owners.owner()[j] == rank) {
      held[j] = 1;
      continue;
    }
    const double y = owners.place(floes.state[j]);
    auto distance = [&](double at) { return std::max({0.0, lo - at, at - hi}); };
    double gap = distance(y);
    if (box.periodic) gap = std::min({gap, distance(y - box.height()), distance(y + box.height())});
    const double band = largest + (one_pad ? 0.0 : half_band(j));
    held[j] = gap <= band ? 1 : 0;
  }
  return held;
}

// The floes rank `rank` holds, as a run computes them
// (parallel::held_floes, H by the simulated ranks' reduction); with
// `one_pad`, the thin band of the named mutation (halo_band_by_rule).
inline Held halo_band(const parallel::FloeOwners& owners, int rank, const Floes& floes, const contact::CollisionShapes& shapes,
               const contact::DetectionOptions& d, bool one_pad = false) {
  if (one_pad) return halo_band_by_rule(owners, rank, floes, shapes, d, true);
  return parallel::held_floes(owners, rank, floes, shapes, d, largest_by_ranks(owners, floes, shapes, d)).mask;
}

// ---- The cases -----------------------------------------------------------

// A dense pack whose floes move at up to `speed` (m/s) and turn, with the
// reach of Simulation::set_reach (dt 10 s): pairs with contact points and
// witnesses, many across every cut.
struct Pack {
  Floes floes;
  contact::CollisionShapes shapes;
  contact::DetectionOptions detect;
  std::array<double, 4> window{};
};
inline Pack moving_pack(unsigned seed, bool periodic, double speed = 0.5, double concentration = 0.75) {
  GeneratedPack g = test::moving_generated_pack(seed, speed, concentration);
  Pack p;
  p.floes = std::move(g.floes);
  p.shapes = contact::build_collision_shapes(p.floes);
  p.window = g.window;
  const double dt = 10.0;
  contact::DetectionOptions& d = p.detect;
  d.collision_distance = 20.0;  // m: wide, so that many pairs have contact points
  d.horizon = dt;
  d.domain = {periodic, g.window[0], g.window[1], g.window[2], g.window[3]};
  d.reach.assign(p.floes.size(), 0.0);
  for (std::size_t i = 0; i < p.floes.size(); ++i) {
    const FloeState& s = p.floes.state[i];
    d.reach[i] = dt * (1.5 * (std::hypot(s.vx, s.vy) + std::abs(s.yaw_rate) * p.shapes.radius[i]) + 0.5 * speed) +
                 d.collision_distance;
  }
  return p;
}

// Equal counts (as a run starts) and uneven strips: one empty (two equal
// cuts) and one beyond the pack.
inline std::vector<double> uneven_cuts(const Pack& p, int ranks) {
  const double y0 = p.window[2], h = p.window[3] - p.window[2];
  switch (ranks) {
    case 2: return {y0 + 0.2 * h};
    case 3: return {y0 + 0.3 * h, y0 + 0.3 * h};
    default: return {y0 + 0.1 * h, y0 + 0.15 * h, y0 + 0.5 * h, y0 + 0.5 * h, y0 + 0.9 * h, y0 + 2.0 * h};
  }
}

// The strips the band's tests run over: equal counts, uneven (uneven_cuts),
// the sea's slabs (256 rows of the window's height from its bottom, blocks
// of 8, equal blocks but for the last slab), and `beyond`: the same slabs
// with the pack moved below the grid in an open box (the floes there are
// owned by the rows they wrap to).
enum class Strips { equal, uneven, slabs, beyond };
inline const char* strips_name(Strips s) {
  switch (s) {
    case Strips::equal: return "equal";
    case Strips::uneven: return "uneven";
    case Strips::slabs: return "slabs";
    default: return "beyond";
  }
}
inline parallel::RowSlabs slabs_of(const Pack& p, int ranks) {
  parallel::RowSlabs slabs;
  slabs.dy = (p.window[3] - p.window[2]) / 256.0;
  slabs.block = 8;
  for (int r = 0; r < ranks; ++r) slabs.first_row.push_back(8 * ((32 * r) / ranks));
  slabs.first_row.push_back(256);
  return slabs;
}
// The owners of `p` on `ranks` simulated ranks (rank 0's object; the tests
// pass each rank's number), with strips of the given kind.
inline parallel::FloeOwners owners_of(const Pack& p, int ranks, Strips kind) {
  if (kind == Strips::slabs && !(p.detect.domain.periodic && p.window[2] == 0.0))
    throw std::logic_error("the sea's slabs are tested in a periodic box from y = 0");
  parallel::FloeOwners owners(0, ranks, p.detect.domain);
  if (kind == Strips::uneven) owners.set_cuts(uneven_cuts(p, ranks));
  if (kind == Strips::slabs || kind == Strips::beyond) owners.set_slabs(slabs_of(p, ranks));
  owners.assign(p.floes);
  return owners;
}

// One configuration of the band's tests, and a line naming it (for CAPTURE).
struct StripCase {
  bool periodic = true;
  double speed = 0.5;
  Strips kind = Strips::equal;
  int ranks = 2;
  std::string name() const {
    return std::string(periodic ? "periodic" : "open") + ", " + std::to_string(speed) + " m/s, " +
           strips_name(kind) + ", " + std::to_string(ranks) + " ranks";
  }
};
// f(pack, case) over a periodic and an open box, moving_pack(7) at 0.5 and
// 2 m/s, strips of equal counts, uneven and the sea's slabs (periodic boxes
// only), on 2, 3 and 7 ranks: 30 configurations.
template <class F>
void for_each_strip_case(F&& f) {
  for (const bool periodic : {true, false})
    for (const double speed : {0.5, 2.0}) {
      const Pack p = moving_pack(7, periodic, speed);
      for (const Strips kind : {Strips::equal, Strips::uneven, Strips::slabs})
        for (const int ranks : {2, 3, 7}) {
          if (kind == Strips::slabs && !periodic) continue;
          f(p, StripCase{periodic, speed, kind, ranks});
        }
    }
}

// A rank's part of the detection from its band only.
struct BandPart {
  contact::Detection part;
  Held held;
};
inline BandPart part_from_band(const Pack& p, const parallel::FloeOwners& owners, int rank, bool one_pad) {
  BandPart out;
  out.held = halo_band(owners, rank, p.floes, p.shapes, p.detect, one_pad);
  contact::DetectionOptions d = p.detect;
  d.reach = poisoned(d.reach, out.held);
  out.part = parallel::detect_part(owners, rank, poisoned(p.floes, out.held), poisoned(p.shapes, out.held), d);
  return out;
}

}  // namespace floesim::test
