#pragma once
// The percussion phase of a run step (MODEL.md §5 step 5 and §6): after the
// collision LCPs, each floe struck by contact impulses is checked for
// fracture initiation with its elastic model (contact/fracture), and with
// [fracture] split = true a floe cracked through is replaced by its two
// pieces (contact/fracture/split.hpp), which carry on in the run.
//
// Loads. Contact j between floes a and b (normal N from a to b, tangent
// T = k x N) gave the impulse J = lambda N + beta T to b and -J to a, at the
// contact point; each floe gets the impulses of all its contacts of the
// step at once, in its body frame, spread over `duration` (response.hpp).
//
// Screening. An analysis costs a dynamic solve per floe, so a floe is
// analysed only when the contact pressure scale of its largest impulse,
//   p = (pi |J| / (2 tau)) / (h 2 r)   (peak force over thickness x patch width,
//                                      r the load radius),
// reaches `screen` times the stress the criterion needs (the strength; for
// griffith the stress sqrt(E G_c / (pi s)) that would open a flaw of one mesh
// size s). The largest tensile stress of the tests stays below p
// (docs/fracture.md), so the default screen of 0.1 leaves a wide margin.
//
// Models are built on a floe's first analysis (meshing and factorisations)
// and kept for its later ones; a floe that splits drops its model, and its
// pieces are not checked again in the step that made them.

#include <cstdint>
#include <memory>
#include <unordered_map>
#include <unordered_set>
#include <vector>

#include "contact/detection.hpp"
#include "contact/impulse.hpp"
#include "core/params.hpp"
#include "core/run_file.hpp"

namespace floesim {

namespace fracture { class FloeFracture; }

struct PercussionStats {
  long checks = 0;        // floes analysed (again when a step is redone)
  long screened = 0;      // floes struck but below the screen
  long initiations = 0;   // events (a crack whose line leaves the floe at once, from a corner, is not split)
  long splits = 0;
  long failed_splits = 0;  // cracked through but not split (sliver, or the pieces would overlap)
  double seconds = 0.0;    // wall time in analyses
};

class Percussion {
public:
  // `gap`: how far apart the pieces of a split are put (m).
  Percussion(const FractureParams& params, double gap, double screen = 0.1);
  ~Percussion();
  Percussion(Percussion&&) noexcept;
  Percussion& operator=(Percussion&&) noexcept;

  // Checks the floes struck by `impulses` (one per contact of `contacts`)
  // at time t. Split floes are replaced in `floes`, and `start` (the states
  // at the start of the step, to redo it) is kept in step with them.
  // Returns true if the set of floes changed.
  bool check(Floes& floes, const std::vector<contact::ContactPoint>& contacts,
             const std::vector<contact::ContactImpulse>& impulses, double t, std::vector<FloeState>& start);

  // The initiations since the last call.
  std::vector<FractureEventRow> take_events();
  const PercussionStats& stats() const { return stats_; }
  // Restart: the counts go on from a checkpoint's (models are rebuilt on a
  // floe's next analysis, to the same bits).
  void restore_stats(const PercussionStats& stats) { stats_ = stats; }

private:
  fracture::FloeFracture& model_of(const Floes& floes, std::size_t i);
  bool split(Floes& floes, std::size_t i, const Vec2& point, double direction, std::vector<FloeState>& start,
             FractureEventRow& event);

  FractureParams params_;
  double gap_, screen_;
  std::unordered_map<std::uint32_t, std::unique_ptr<fracture::FloeFracture>> models_;  // by floe number
  std::unordered_set<std::uint32_t> fresh_;  // pieces made in the current step
  double fresh_time_ = -1.0;
  std::vector<FractureEventRow> events_;
  PercussionStats stats_;
};

}  // namespace floesim
