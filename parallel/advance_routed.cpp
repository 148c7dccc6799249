// The advance from the rank's part (parallel/advance_share.hpp): the pairs
// a rank routes to the runners of their clusters, with their floes' states
// and collision shapes, and what a rank does with the floes it does not
// hold (move_not_held, until the halo exchange's piece 8).
#include "parallel/advance_share.hpp"

#include <algorithm>
#include <string>

#include "core/error.hpp"
#include "parallel/detect.hpp"

namespace floesim::parallel {

std::vector<contact::Detection> routed_pairs(const contact::Detection& part,
                                             std::span<const std::pair<int, std::uint32_t>> routes, int ranks) {
  std::vector<contact::Detection> out(static_cast<std::size_t>(ranks));
  std::vector<std::uint8_t> to(part.pairs.size());
  for (int s = 0; s < ranks; ++s) {
    std::fill(to.begin(), to.end(), 0);
    bool any = false;
    for (const auto& [r, p] : routes)
      if (r == s) {
        to[p] = 1;
        any = true;
      }
    if (!any) continue;
    std::size_t j = 0;
    out[static_cast<std::size_t>(s)] = select_pairs(part, [&](const contact::NearPair&) { return to[j++] != 0; });
  }
  return out;
}

RoutedShapes routed_shapes(const contact::CollisionShapes& shapes, std::span<const double> reach,
                           std::span<const std::uint32_t> floes) {
  RoutedShapes out;
  out.floe.assign(floes.begin(), floes.end());
  for (const std::uint32_t i : floes) {
    out.radius.push_back(shapes.radius[i]);
    out.reach.push_back(reach[i]);
    out.parts.push_back(static_cast<std::uint32_t>(shapes.parts_of(i)));
    for (std::size_t p = shapes.parts_begin(i); p < shapes.parts_end(i); ++p) {
      const std::span<const Vec2> v = shapes.part(p);
      out.vertices.push_back(static_cast<std::uint32_t>(v.size()));
      out.vertex.insert(out.vertex.end(), v.begin(), v.end());
    }
  }
  return out;
}

void hold(const RoutedShapes& routed, contact::CollisionShapes& shapes, std::span<double> reach) {
  std::size_t part = 0, vertex = 0;
  for (std::size_t k = 0; k < routed.floe.size(); ++k) {
    const std::uint32_t i = routed.floe[k];
    shapes.radius[i] = routed.radius[k];
    reach[i] = routed.reach[k];
    if (!shapes.has(i)) {
      // Not held here: its parts go to the arrays' end (as an entering
      // floe's, CollisionShapes::hold), kept until the next detection's hold.
      const std::span<const std::uint32_t> sizes(routed.vertices.data() + part, routed.parts[k]);
      std::size_t count = 0;
      for (const std::uint32_t s : sizes) count += s;
      shapes.append(i, sizes, std::span<const Vec2>(routed.vertex.data() + vertex, count));
      part += routed.parts[k];
      vertex += count;
      continue;
    }
    FLOESIM_ASSERT(shapes.parts_of(i) == routed.parts[k]);
    for (std::size_t p = shapes.parts_begin(i); p < shapes.parts_end(i); ++p, ++part) {
      FLOESIM_ASSERT(shapes.vertex_offsets[p + 1] - shapes.vertex_offsets[p] == routed.vertices[part]);
      std::copy_n(routed.vertex.begin() + static_cast<std::ptrdiff_t>(vertex), routed.vertices[part],
                  shapes.vertices.begin() + static_cast<std::ptrdiff_t>(shapes.vertex_offsets[p]));
      vertex += routed.vertices[part];
    }
  }
}

contact::Detection exchange_advance_pairs(const Communicator& comm, const contact::Detection& part,
                                          const std::vector<contact::Detection>& outgoing, Floes& floes,
                                          contact::CollisionShapes& shapes, long* shape_bytes) {
  // Two pieces with each message's pairs: their floes' states, their shapes.
  Carried carried{2, std::vector<Pieces>(outgoing.size()), {}};
  for (std::size_t s = 0; s < outgoing.size(); ++s) {
    if (outgoing[s].pairs.empty()) continue;
    const RoutedFloes routed = routed_floes(floes, {}, outgoing[s]);
    carried.outgoing[s] = {pack(routed), pack(routed_shapes(shapes, part.reach, routed.floe))};
    if (shape_bytes) *shape_bytes += static_cast<long>(carried.outgoing[s][1].size());
  }
  contact::Detection held = exchange_pairs(comm, part, outgoing, &carried);
  for (const Pieces& r : carried.received) {
    parallel::hold(unpack_routed_floes(r[0]), floes, {});
    hold(unpack_routed_shapes(r[1]), shapes, held.reach);
  }
  return held;
}

void check_routed_floes(std::span<const AdvancePart> parts) {
  for (std::size_t r = 0; r < parts.size(); ++r) {
    const contact::ShareOutcome& o = parts[r].outcome;
    if (o.conflict != contact::ShareOutcome::Conflict::missing_floe) continue;
    throw RunError("the advance's share on rank " + std::to_string(r) + ": floe " +
                   (o.moved.empty() ? std::string("?") : std::to_string(o.moved.front())) +
                   " of its routed pairs came without its state, mass, collision shape or reach "
                   "(not finite where the share holds it)");
  }
}

void move_not_held(Floes& floes, std::span<const std::uint32_t> held, double dt) {
  // The formula of the share's free floes (contact::drifted from the step's
  // start): the same bits as the rank holding the floe computes.
  std::size_t k = 0;
  for (std::uint32_t i = 0; i < floes.size(); ++i) {
    if (k < held.size() && held[k] == i) {
      ++k;
      continue;
    }
    if (!floes.is_static[i]) floes.state[i] = drifted(floes.state[i], dt);
  }
}

}  // namespace floesim::parallel
