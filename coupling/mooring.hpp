#pragma once
// Soft moorings: a horizontal spring and damper between a floe's centroid G
// and an anchor A, the place where the floe starts, as wave-basin tests hold
// their floes (docs/validation.md). Per unit mass, with omega = 2 pi / period
// and zeta the damping ratio,
//     dV/dt = -omega^2 (G - A) - 2 zeta omega V,
// applied in the drift phase as a kick over the step dt, the damper taken
// implicitly (stable for any zeta dt):
//     V <- (V - dt omega^2 (G - A)) / (1 + 2 zeta omega dt).
// A mooring much slower than the waves changes the response at the wave
// period T by a factor 1 / (1 - (T / period)^2) on the surge (an oscillator
// driven above its resonance): under 1% for period > 10 T. The mooring acts
// on the floe it was given to; a floe that splits loses it (its pieces are
// new floes). Positions are taken as they are: in a periodic domain the
// anchor does not wrap.

#include <cstdint>
#include <span>
#include <vector>

#include "core/floes.hpp"

namespace floesim {

class Moorings {
public:
  Moorings() = default;
  // The moorings asked by `inputs`, the inputs of floes
  // [floes.size() - inputs.size(), floes.size()) (the inline floes come after
  // a pack's), anchored where those floes are now.
  Moorings(const Floes& floes, std::span<const FloeInput> inputs);

  bool empty() const { return list_.empty(); }
  // The kick above over dt for every moored floe still in the run.
  void kick(Floes& floes, double dt) const;
  // The same for the moored floes among `only` (ascending floe indices: on
  // several ranks the floes the rank drifts); no other floe is read or
  // written. Each floe's kick reads and writes that floe alone, so these
  // floes get the bits the whole kick gives them.
  void kick(Floes& floes, double dt, std::span<const std::uint32_t> only) const;

private:
  void kick_one(Floes& floes, std::size_t i, double dt) const;
  struct Mooring {
    std::uint32_t id = 0;  // the floe's number (Floes::id)
    Vec2 anchor = Vec2::Zero();
    double omega = 0.0;    // rad/s
    double damping = 0.0;  // zeta
  };
  std::vector<Mooring> list_;
};

}  // namespace floesim
