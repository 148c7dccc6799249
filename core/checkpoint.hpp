#pragma once
// A checkpoint: everything a run carries from one step to the next, as data,
// so that `floesim run --restart` (and floesim.Simulation.from_run) continue
// a run exactly as if it had never stopped: the records after the restart
// equal those of the uninterrupted run bit for bit. Each layer fills and
// reads its own part (the floes here; the sea's modal state through
// fluid::Sea; the floe–sea contact, the incident waves and the statistics in
// coupling; the jam LCPs' warm starts of contact). What a layer can compute
// again from this state to the same bits (footprints, detection, collision
// shapes, FFT plans, BEM matrices, fracture models) is not stored.
//
// Stored in the run file, group /checkpoint (docs/formats.md, "Checkpoint"),
// replaced whole at each checkpoint: one file holds a run and the means to
// continue it, and a checkpoint always goes with the records it follows.

#include <cstdint>
#include <array>
#include <string>
#include <vector>

#include "core/floes.hpp"

namespace floesim {

// Version of the /checkpoint group's layout; a reader refuses other versions.
inline constexpr long long kCheckpointVersion = 1;

// A modal sea (fluid::ModalBank, every deferred kick applied): amplitudes and
// rates, and the sea's time.
struct ModalState {
  bool present = false;
  double time = 0.0;          // s
  std::vector<double> q, v;
  // The pressure a sea with a static part holds (fluid::Sea::hold_pressure;
  // Pa, one value per grid node); empty when none is held.
  std::vector<double> held_pressure;
};

// The incident waves kept for drag (coupling/incident.hpp): their sea and the
// two velocity snapshots, at t0 and t1, on the grid.
struct IncidentState {
  bool present = false;
  ModalState sea;
  double t0 = 0.0, t1 = 0.0;  // s
  std::vector<double> u0, v0, u1, v1;  // m/s
};

// What the floe–sea contact (coupling/floe_sea.hpp) keeps beyond the floes
// and the sea: each floe's reference bottom (a split piece inherits its
// parent's), and the kick length its loads cache was evaluated for (< 0: stale).
struct FloeSeaState {
  bool present = false;
  std::vector<double> bottom0;  // m
  double loads_h = -1.0;        // s
  double penalty_energy = 0.0;  // J, at that evaluation
  // Per floe, the pose (x, y, yaw) its footprint was last built at
  // (coupling/moving_footprint.hpp); empty: none built yet.
  std::vector<std::array<double, 3>> footprint_reference;
  // Implicit integrator, per floe: the horizontal load (Fx, Fy, torque) the
  // next step's first half kick applies, the last step's mean
  // (coupling/floe_sea.hpp); empty: the loads at the state.
  std::vector<std::array<double, 3>> mean_horizontal;
};

// The jam LCPs' warm starts (contact::WarmStart): per floe pair (key), the
// step clock when stored and its entries, each kWidth numbers: body point (2,
// the contact's vertex), body normal (2), the 4 basic flags (0 or 1),
// vertex_of_b (0 or 1).
struct WarmStartState {
  static constexpr std::size_t kWidth = 9;
  long long clock = 0;
  std::vector<std::uint64_t> keys;
  std::vector<long long> stored;
  std::vector<long long> offsets{0};  // pair k owns entries [offsets[k], offsets[k + 1])
  std::vector<double> entries;        // 8 per entry
};

struct Checkpoint {
  // The simulation (coupling::Simulation) at the end of a step.
  double time = 0.0;          // s
  long long steps = 0;
  double equal_dt = -1.0;     // s, the last of the equal steps of the penalty limit (< 0: none)
  Floes floes;                // every per-floe array, with numbers and ids_issued
  ModalState sea;
  IncidentState incident;
  FloeSeaState floe_sea;
  WarmStartState warm;
  // Cumulative statistics (collisions, sub-steps, momentum budget, fracture),
  // by name; they feed the /diagnostics records.
  std::vector<std::string> counter_names;
  std::vector<double> counters;
  std::string floor_pair;     // the last pair held at the sub-step floor (a warning's text)

  // The run file the checkpoint belongs to (coupling/run.hpp).
  long long next_record = 1;        // index k of the next scheduled record, at k output_interval
  long long records = 0;            // records written on schedule up to this state
  long long fracture_events = 0;    // rows of /events/fracture up to this state
  long long collision_events = 0;   // rows of /events/collisions up to this state
  std::vector<long long> record_floes;  // floes numbered at each of those records (/floes tables' sizes)
};

// Lets go of the state a Simulation has taken in restore(): the seas', the
// contact's and the warm starts' parts (on a large sea, 64 B a cell). What a
// continued run still reads is kept: the marks above, the counters and the
// floes' numbering (RunWriter's Resume).
void release_restored(Checkpoint& c);

// Written by RunWriter::write_checkpoint (core/run_file.hpp).
// Reads the checkpoint of a run file. Throws InputError naming the file when
// it has none ("the run has no checkpoint"), or one of another version, or a
// part is missing or inconsistent.
Checkpoint read_checkpoint(const std::string& path);

}  // namespace floesim
