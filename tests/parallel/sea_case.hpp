#pragma once
// The spectral sea the distributed sea tests (sea_slab_ranks.cpp,
// incident_ranks.cpp) run in slabs: nx x ny cells of 8 m x 10 m, 30 m deep,
// a spread JONSWAP sea (Hs = 1 m, Tp = 6 s).

#include "core/params.hpp"

namespace floesim::test {

inline SeaParams slab_sea_params(int nx, int ny) {
  SeaParams p;
  p.model = SeaModel::spectral;
  p.dims = 2;
  p.size = {8.0 * nx, 10.0 * ny};
  p.cells = {nx, ny};
  p.depth = 30.0;
  p.waves.kind = WaveKind::jonswap;
  p.waves.hs = 1.0;
  p.waves.tp = 6.0;
  p.waves.spreading = 4.0;
  return p;
}

}  // namespace floesim::test
