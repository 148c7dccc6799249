#include "coupling/mooring.hpp"

#include <algorithm>
#include <numbers>

namespace floesim {

Moorings::Moorings(const Floes& floes, std::span<const FloeInput> inputs) {
  const std::size_t first = floes.size() - std::min(inputs.size(), floes.size());
  for (std::size_t k = 0; k < inputs.size() && first + k < floes.size(); ++k) {
    const FloeInput& in = inputs[k];
    if (!(in.mooring_period > 0.0)) continue;
    const std::size_t i = first + k;
    list_.push_back({floes.id[i], Vec2{floes.state[i].x, floes.state[i].y}, 2.0 * std::numbers::pi / in.mooring_period,
                     in.mooring_damping});
  }
  std::sort(list_.begin(), list_.end(), [](const Mooring& a, const Mooring& b) { return a.id < b.id; });
}

void Moorings::kick(Floes& floes, double dt) const {
  if (list_.empty()) return;
  for (std::size_t i = 0; i < floes.size(); ++i) kick_one(floes, i, dt);
}

void Moorings::kick(Floes& floes, double dt, std::span<const std::uint32_t> only) const {
  if (list_.empty()) return;
  for (const std::uint32_t i : only) kick_one(floes, i, dt);
}

void Moorings::kick_one(Floes& floes, std::size_t i, double dt) const {
  // Floes are found by their number (list_ is in increasing numbers): a
  // split renumbers the run's floes.
  const auto it = std::lower_bound(list_.begin(), list_.end(), floes.id[i],
                                   [](const Mooring& m, std::uint32_t id) { return m.id < id; });
  if (it == list_.end() || it->id != floes.id[i] || floes.is_static[i]) return;
  FloeState& s = floes.state[i];
  const double w2 = it->omega * it->omega, shrink = 1.0 / (1.0 + 2.0 * it->damping * it->omega * dt);
  s.vx = (s.vx - dt * w2 * (s.x - it->anchor.x())) * shrink;
  s.vy = (s.vy - dt * w2 * (s.y - it->anchor.y())) * shrink;
}

}  // namespace floesim
