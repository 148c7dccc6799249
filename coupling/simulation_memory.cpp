// The per-floe structures held by band and their memory on this rank
// (docs/parallel.md, "The arrays held by band: measured (mem27)"):
// Simulation::hold_quadrature, Simulation::hold_shapes, Simulation::floe_memory.

#include "coupling/simulation.hpp"

namespace floesim {

void Simulation::hold_quadrature() {
  // Only the drift reads the quadrature, each rank its own floes' (which it
  // holds), in every case of several ranks (the halo exchange or not): the
  // floes of its band are kept too, so that a floe migrating to it across
  // a cut has its points already.
  if (!comm_.serial()) quadrature_.hold(scenario_.floes, held_now());
}

bool Simulation::shapes_held_by_band() const { return !comm_.serial() && advance_share_options_.on_part; }

void Simulation::build_shapes() {
  // A shape is a function of the floe's body vertices (every rank keeps
  // every floe's): held by band, each rank builds the held floes' at the
  // detection (hold_shapes), not every floe's here first.
  if (shapes_held_by_band())
    shapes_.forget(scenario_.floes);
  else
    shapes_ = contact::build_collision_shapes(scenario_.floes);
}

void Simulation::hold_shapes() {
  if (shapes_held_by_band()) shapes_.hold(scenario_.floes, held_now());
}

Simulation::FloeMemory Simulation::floe_memory() const {
  const std::vector<std::uint8_t> held = held_now();  // empty: every floe
  FloeMemory m;
  m.floes = scenario_.floes.size();
  m.held = held_count(held, m.floes);
  auto add = [&](const char* name, FloeBytes b) { m.parts.emplace_back(name, b); };
  const Floes::Memory f = scenario_.floes.memory(held);
  add("constants", f.constants);
  add("vertices", f.vertices);
  add("state", f.state);
  add("shapes", shapes_.memory(held));
  add("quadrature", quadrature_.memory(held));
  if (floe_sea_) {
    const FloeSeaContact::Memory c = floe_sea_->memory(held);
    add("coupling", c.per_floe);
    add("footprint_areas", c.footprints.area_pieces);
    add("footprint_edges", c.footprints.edge_pieces);
    add("footprint_floes", c.footprints.per_floe);  // poses, radii, owners a floe
  }
  FloeBytes reach = per_floe_bytes(detection_.reach, m.held);
  if (detection_part_) reach += per_floe_bytes(detection_part_->reach, m.held);
  add("reach", reach);
  add("owners", owners_.memory(m.held));
  // The held set itself: its mask (one entry a floe) and index (held).
  add("held_set", {capacity_bytes(held_.mask) + capacity_bytes(held_.index),
                   (held_.mask.empty() ? 0 : m.held) + capacity_bytes(held_.index)});
  add("announced", {capacity_bytes(announced_.floe) + capacity_bytes(announced_.offset) + capacity_bytes(announced_.rank),
                    capacity_bytes(announced_.floe) + capacity_bytes(announced_.offset) + capacity_bytes(announced_.rank)});
  add("wrapped", per_floe_bytes(wrapped_, m.held));
  FloeBytes total;
  for (const auto& [name, b] : m.parts) total += b;
  add("total", total);
  return m;
}

}  // namespace floesim
