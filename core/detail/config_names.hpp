#pragma once
// The names of the configuration's choices, in one place for the reader
// (core/config.cpp: Section::choice) and the writer of the resolved
// configuration (core/config_toml.cpp), so that what a run file stores reads
// back as the same choice. Internal to core.

#include <string>
#include <utility>
#include <vector>

#include "core/params.hpp"

namespace floesim::detail {

template <class E>
using Names = std::vector<std::pair<std::string, E>>;

inline const Names<SeaModel> kSeaModels = {
    {"none", SeaModel::none}, {"spectral", SeaModel::spectral}, {"bem", SeaModel::bem}};
inline const Names<WaveKind> kWaveKinds = {{"none", WaveKind::none},
                                           {"regular", WaveKind::regular},
                                           {"standing", WaveKind::standing},
                                           {"jonswap", WaveKind::jonswap}};
inline const Names<PenaltyLaw> kPenaltyLaws = {
    {"strong", PenaltyLaw::strong}, {"weak", PenaltyLaw::weak}, {"blend", PenaltyLaw::blend}};
inline const Names<FootprintChoice> kFootprints = {{"automatic", FootprintChoice::automatic},
                                                   {"cell", FootprintChoice::cell},
                                                   {"tent", FootprintChoice::tent}};
inline const Names<CouplingIntegrator> kIntegrators = {{"explicit", CouplingIntegrator::explicit_kicks},
                                                       {"implicit", CouplingIntegrator::implicit}};
inline const Names<HorizontalLoads> kHorizontalLoads = {{"step_mean", HorizontalLoads::step_mean},
                                                        {"step_ends", HorizontalLoads::step_ends}};
inline const Names<SeriesInterpolation> kSeriesInterpolations = {{"linear", SeriesInterpolation::linear},
                                                                 {"previous", SeriesInterpolation::previous}};
inline const Names<FractureCriterion> kFractureCriteria = {{"stress", FractureCriterion::stress},
                                                           {"griffith", FractureCriterion::griffith}};
inline const Names<FractureMesher> kFractureMeshers = {{"auto", FractureMesher::automatic},
                                                      {"cgal", FractureMesher::cgal}};
// Two choices stored as flags: [contact] domain and [coupling] start.
inline const Names<bool> kDomains = {{"open", false}, {"periodic", true}};
inline const Names<bool> kStarts = {{"equilibrium", false}, {"given", true}};

// The name of choice e (every value of E has one in its table).
template <class E>
std::string name_of(E e, const Names<E>& names) {
  for (const auto& [s, v] : names)
    if (v == e) return s;
  return "?";
}

}  // namespace floesim::detail
