// Simulation: what a caller reads of the run between steps: the pack's
// momentum and energies (exact sums by owner, the same bits on any number
// of ranks), the LCP counters, the warnings and notes, the sea's grid and
// elevation. The step's phases are in simulation.cpp.
#include <array>
#include <string>

#include "coupling/simulation.hpp"
#include "coupling/simulation_detail.hpp"
#include "fluid/sea.hpp"

namespace floesim {

using simulation_detail::kFloorFraction;

void Simulation::add_owned_momentum(std::span<ExactSum, 2> into) const {
  // Each floe's m v is one rounded product, the same on any rank; the sum
  // of the products is exact (rounded once, by value()).
  const Floes& f = scenario_.floes;
  for_owned([&](std::size_t i) {
    if (f.is_static[i]) return;
    into[0].add(f.mass[i] * f.state[i].vx);
    into[1].add(f.mass[i] * f.state[i].vy);
  });
}

Vec2 Simulation::momentum() const {
  std::array<ExactSum, 2> p;
  add_owned_momentum(p);
  comm_.sum(p);
  return {p[0].value(), p[1].value()};
}

Energies Simulation::energies() const {
  // The floes' kinetic energies (horizontal; with a sea, vertical) and
  // their weight energy: each floe's terms, then their exact sums by owner,
  // combined over the ranks (one call; the same bits on any number of ranks).
  const Floes& f = scenario_.floes;
  std::array<ExactSum, 3> sums;  // horizontal kinetic, vertical kinetic, weight
  for_owned([&](std::size_t i) {
    if (f.is_static[i]) return;
    const FloeState& s = f.state[i];
    sums[0].add(0.5 * f.mass[i] * (s.vx * s.vx + s.vy * s.vy) + 0.5 * f.inertia_z[i] * s.yaw_rate * s.yaw_rate);
    if (!floe_sea_) return;
    sums[1].add(floe_sea_->vertical_kinetic(f, i));
    sums[2].add(floe_sea_->weight_energy(f, i));
  });
  comm_.sum(floe_sea_ ? std::span<ExactSum>(sums) : std::span<ExactSum>(sums).first(1));
  Energies e{{"floes_horizontal_kinetic"}, {sums[0].value()}};
  if (floe_sea_) {
    e.names.insert(e.names.end(), {"floes_vertical_kinetic", "floes_weight", "penalty"});
    e.values.insert(e.values.end(), {sums[1].value(), sums[2].value(), floe_sea_->penalty_energy()});
  }
  if (sea_) {
    const fluid::SeaEnergy se = sea_->energy();
    e.names.insert(e.names.end(), {"sea_kinetic", "sea_potential"});
    e.values.insert(e.values.end(), {se.kinetic, se.potential});
  }
  double total = 0.0;
  for (double v : e.values) total += v;
  e.names.push_back("total");
  e.values.push_back(total);
  return e;
}

LcpCounters Simulation::lcp_counters() const {
  LcpCounters c{static_cast<double>(stats_.lcps), static_cast<double>(stats_.pivots),
                static_cast<double>(stats_.failures), static_cast<double>(stats_.fallbacks), {}};
  const contact::SubstepReport& s = substeps_;  // in the order of kSubstepColumnNames
  c.substeps = {static_cast<double>(s.clusters),        static_cast<double>(s.substeps),
                static_cast<double>(s.time_steps),      static_cast<double>(s.largest_cluster),
                static_cast<double>(s.joined),          static_cast<double>(s.merges),
                static_cast<double>(s.rejected),        static_cast<double>(s.floor_steps),
                static_cast<double>(s.rebuilt)};
  return c;
}

std::vector<std::string> Simulation::warnings() const {
  std::vector<std::string> w;
  if (substeps_.floor_steps)
    w.push_back(std::to_string(substeps_.floor_steps) + " sub-step(s) were held at the floor " +
                std::to_string(kFloorFraction) + " dt_max although the collision limit asked for less (last: " +
                substeps_.floor_pair + ")");
  if (stats_.failures)
    w.push_back(std::to_string(stats_.failures) + " collision LCP(s) failed; those floes kept their velocities");
  if (percussion_ && percussion_->stats().failed_splits)
    w.push_back(std::to_string(percussion_->stats().failed_splits) +
                " floe(s) cracked through but were not split (a piece too small, or the pieces would overlap a neighbour)");
  if (stats_.flagged)
    w.push_back(std::to_string(stats_.flagged) + " collision LCP(s) were answered by projected Gauss–Seidel (approximate)");
  return w;
}

std::vector<std::string> Simulation::notes() const {
  std::vector<std::string> n = scenario_.notes;
  if (floe_sea_) n.insert(n.end(), floe_sea_->notes().begin(), floe_sea_->notes().end());
  return n;
}

SeaGridInfo Simulation::sea_grid() const {
  if (!sea_) return {};
  const fluid::SurfaceGrid& g = sea_->grid();
  return {g.dims, {g.nx, g.ny}, {g.lx, g.ly}};
}

std::span<const double> Simulation::sea_elevation() {
  if (!sea_) return {};
  // In slabs every rank's rows go to the writer alone (the other ranks get
  // an empty span); every rank calls it.
  return sea_->field_on_writer(fluid::Field::elevation);
}

}  // namespace floesim
