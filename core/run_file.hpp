#pragma once
// The run file (HDF5, format "floesim-1"; docs/formats.md): written
// incrementally, one record per output time, flushed after each record so that
// a run killed midway leaves a readable file holding every record so far. An
// XDMF file beside it (same name, .xmf) lets ParaView open the run.
//
// Layout (ARCHITECTURE.md, plus the /xdmf helpers):
//   attributes on /: format = "floesim-1", config (resolved TOML), status
//     ("running" while a run writes; "complete"; "failed: ...")
//   /time [T]
//   /floes/offsets [n+1], /floes/vertices [V, 2] (body frame),
//   /floes/thickness, /floes/mass, /floes/static, /floes/area [n]
//   /floes/state [T, n, 12] (columns attribute: x, y, yaw, vx, vy, yaw_rate,
//     heave, pitch, roll, heave_rate, pitch_rate, roll_rate)
//   Floes are numbered by creation (Floes::id): a floe that splits ends and
//   its two pieces are new floes appended to the /floes tables, so n grows
//   during a run; /floes/state (and /xdmf/vertices) hold NaN for a floe at the
//   records where it does not exist (before it was made, after it split).
//   /events/fracture [E, 17] (columns attribute): one row per fracture
//     initiation, FractureEventRow below.
//   /events/collisions [C, 7] (columns attribute): one row per collision
//     solve and pair of floes, CollisionEventRow; only in runs with
//     [run] record_collisions that had a collision.
//   /sea/x [nx], /sea/y [ny], /sea/eta [T, ny, nx] (dims 2) or [T, nx] (dims 1)
//   /diagnostics/energy [T, k] (columns attribute; the last column is "total")
//   /diagnostics/lcp [T, 4]: solves, pivots, failures, fallbacks (cumulative)
//   /diagnostics/substeps [T, 9] (columns attribute, kSubstepColumnNames):
//     the collision sub-stepper's counts (contact/substep.hpp), cumulative
//     except largest_cluster (the largest so far)
//   /xdmf/vertices [T, V, 3]: world vertex positions (x, y, heave) for ParaView
//   /xdmf/topology [E]: XDMF mixed-polygon connectivity
//   /checkpoint: the state to continue the run from (core/checkpoint.hpp);
//     not a result: compare_runs leaves it out

#include <array>
#include <memory>
#include <span>
#include <string>
#include <vector>

namespace floesim {

struct Floes;
struct FloeState;
struct Checkpoint;

inline constexpr const char* kRunFormat = "floesim-1";

// The sea grid recorded in /sea (cell centres).
struct SeaGridInfo {
  int dims = 0;                       // 0: no sea recorded
  std::array<int, 2> cells{};         // nx, ny (ny ignored for dims 1)
  std::array<double, 2> size{};       // m
};

// One fracture initiation: a row of /events/fracture.
struct FractureEventRow {
  double time = 0.0;        // s, of the collision
  double floe = 0.0;        // number of the floe that cracked
  double x = 0.0, y = 0.0;  // m, world: where the crack starts
  double direction = 0.0;   // degrees from +x, in [0, 180): the crack's direction
  double load = 0.0;        // N s: the magnitudes of the contact impulses on the floe, summed
  double stress = 0.0;      // Pa: the largest tensile principal stress
  double x0 = 0.0, y0 = 0.0, x1 = 0.0, y1 = 0.0;  // m, world: the crack's ends
  double criterion = 0.0;   // 0: stress, 1: griffith
  double energy_released = 0.0, energy_needed = 0.0;  // J (griffith; 0 for stress)
  double delay = 0.0;       // s after the collision of the state judged (0: sustained contact alone, judged statically)
  double piece_a = -1.0, piece_b = -1.0;  // numbers of the two pieces (-1: no split)
};
inline constexpr int kFractureEventColumns = 17;
static_assert(sizeof(FractureEventRow) == kFractureEventColumns * sizeof(double));
inline constexpr const char* kFractureEventColumnNames[kFractureEventColumns] = {
    "time", "floe", "x", "y", "direction", "load", "stress", "x0", "y0", "x1", "y1",
    "criterion", "energy_released", "energy_needed", "delay", "piece_a", "piece_b"};

// One pair's share of one collision solve (an LCP at the start of a step, a
// sub-step event, a jam's time step): a row of /events/collisions.
struct CollisionEventRow {
  double time = 0.0;    // s, the end of the step the solve fell in
  double floe_a = 0.0, floe_b = 0.0;  // the floes' numbers (floe_a < floe_b, or floe_b static)
  double normal = 0.0;  // N s, the normal impulse of the pair's contacts, summed (compression + restitution)
  double x = 0.0, y = 0.0;  // m, world: the contact point (impulse-weighted mean of the pair's points)
  double resting = 0.0;  // 1: every contact of the pair rested (approached no faster than rest_speed), 0: an impact
};
inline constexpr int kCollisionEventColumns = 7;
static_assert(sizeof(CollisionEventRow) == kCollisionEventColumns * sizeof(double));
inline constexpr const char* kCollisionEventColumnNames[kCollisionEventColumns] = {
    "time", "floe_a", "floe_b", "normal", "x", "y", "resting"};

inline constexpr int kSubstepColumns = 9;
inline constexpr const char* kSubstepColumnNames[kSubstepColumns] = {
    "clusters", "substeps", "time_steps", "largest_cluster", "joined", "merges", "rejected", "floor_steps",
    "rebuilt"};

struct LcpCounters {
  double solves = 0, pivots = 0, failures = 0, fallbacks = 0;  // cumulative
  std::array<double, kSubstepColumns> substeps{};  // /diagnostics/substeps, kSubstepColumnNames
};

// How a RunWriter writes its file ([run] crash_safe_output, docs/formats.md
// "A killed run's file").
//   crash_safe: two copies on disk, the file published whole at each flush
//     (core/detail/h5_published.hpp): a run killed at any instant leaves a
//     whole file; every byte is written twice and the disk holds the file
//     twice while it is written.
//   in_place: one copy, HDF5 writing in place: half the disk and the writes;
//     a run killed during a flush may leave a file that no longer opens.
// The file's content is the same either way.
enum class RunFileWriting { crash_safe, in_place };

class RunWriter {
public:
  // Creates (truncates) the file and writes the static parts. Throws
  // RunError if the file cannot be created or written (it is then removed).
  // expected_records (0: unknown) sizes the chunks of the per-record datasets
  // (more records still fit).
  //
  // A full disk: every write is preceded by a reservation of the disk space
  // it may take (h5::reserve), so a disk that fills (or a file-size limit)
  // is met before HDF5 writes, never in the middle of a flush. record(),
  // note_floes() and record_fracture() then throw RunError and write nothing;
  // finish() can still mark the run failed and close the file, which keeps
  // every record written before. On a file system that cannot preallocate,
  // the failed write itself is reported (the file may then be damaged).
  RunWriter(const std::string& path, const Floes& floes, const std::string& config_toml,
            std::vector<std::string> energy_columns, const SeaGridInfo& sea = {},
            std::size_t expected_records = 0, RunFileWriting writing = RunFileWriting::crash_safe);
  // Continues the run file `path` from its checkpoint `c` (read_checkpoint):
  // the records, fracture and collision events and floe numbers after it are dropped (a
  // run that went on past its last checkpoint), and record() appends after
  // it. The status is "running" again and `config_toml` replaces the config
  // attribute. Throws InputError if the file's datasets do not hold what the
  // checkpoint counts, or its energy columns are not `energy_columns`.
  struct Resume {};
  RunWriter(Resume, const std::string& path, const Checkpoint& c, const std::string& config_toml,
            const std::vector<std::string>& energy_columns, const SeaGridInfo& sea = {},
            RunFileWriting writing = RunFileWriting::crash_safe);
  ~RunWriter();  // closes; leaves status "running" unless finish() was called
  RunWriter(const RunWriter&) = delete;
  RunWriter& operator=(const RunWriter&) = delete;

  // Appends one record and flushes the file. `energy` has one value per
  // column; `eta` is the sea elevation on the grid (row-major, y slowest), or
  // empty when there is no sea. Floes new since the last call are added to
  // the /floes tables first (note_floes).
  void record(double t, const Floes& floes, std::span<const double> energy,
              const LcpCounters& lcp, std::span<const double> eta = {});
  // The same with the floes' states taken from `states` (one per floe of
  // `floes`, which gives the numbers, outlines and constants): the writer
  // rank's copy gathered from the floes' owners (docs/parallel.md).
  void record(double t, const Floes& floes, std::span<const FloeState> states, std::span<const double> energy,
              const LcpCounters& lcp, std::span<const double> eta = {});
  // Adds to the /floes tables the floes with numbers not seen yet (call it
  // after every step that may create floes, so none is missed).
  void note_floes(const Floes& floes);
  // Appends rows to /events/fracture and flushes.
  void record_fracture(std::span<const FractureEventRow> events);
  // Appends rows to /events/collisions (flushed with the next record or
  // fracture event; a run killed midway may lose the rows since).
  void record_collisions(std::span<const CollisionEventRow> events);

  // Fills in c's counts of this file (records, fracture events, floes per
  // record) as they are now: call it when the records of the state `c`
  // holds are written, and none of a later state.
  void count_into(Checkpoint& c) const;
  // Writes `c` as /checkpoint, replacing the last one once it is whole.
  // Throws RunError if the file cannot be written.
  void write_checkpoint(const Checkpoint& c);

  // Marks the run complete, or failed with a reason, writes the XDMF and
  // closes the file. Never throws: returns "" or what could not be written
  // (after a full disk: the status, or the XDMF, which is then removed rather
  // than left describing other records than the file holds).
  std::string finish(const std::string& status);

  // True once a write was refused or failed: the file holds records() records.
  bool failed() const;
  std::size_t records() const;
  const std::string& path() const;
  std::string xdmf_path() const;

private:
  void start(const Floes& floes, const std::string& config_toml, unsigned long long rows);
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// A summary of a run file, for `floesim info`.
struct RunInfo {
  std::string format, status, config;
  std::size_t records = 0, floes = 0, vertices = 0;
  double t_first = 0.0, t_last = 0.0;
  double checkpoint_time = -1.0;        // s, of /checkpoint (< 0: none)
  std::vector<std::string> energy_columns;
  std::vector<double> energy_last;      // last record
  std::array<double, 4> lcp_last{};     // solves, pivots, failures, fallbacks
  std::array<double, kSubstepColumns> substeps_last{};  // kSubstepColumnNames (0 for files without them)
  std::vector<std::pair<std::string, std::vector<unsigned long long>>> datasets;  // path, shape
};
// Reads a run file's summary; a file that crashes the HDF5 library is
// refused (InputError), having been read first in a child process.
RunInfo read_run_info(const std::string& path);
RunInfo read_run_info_in_process(const std::string& path);  // the same, in this process only

// One numeric dataset of a run file (any stored type, converted to double),
// row-major with its shape, and its `columns` attribute if it has one. For
// scripts (the Python module) and tools. Throws InputError naming the file
// and the dataset when either is missing or unreadable.
struct RunDataset {
  std::vector<unsigned long long> shape;
  std::vector<double> values;
  std::vector<std::string> columns;
};
RunDataset read_run_dataset(const std::string& path, const std::string& dataset);

// Regression comparison of two run files: every numeric dataset of A must
// exist in B with the same shape and |a - b| <= atol + rtol |b| element-wise
// (NaN equals NaN). Attributes other than format are not compared.
struct CompareOptions {
  double rtol = 1e-6;
  double atol = 1e-9;
};
// Throws InputError unless rtol and atol are finite and >= 0: a NaN tolerance
// makes every element differ, a negative one every element but exact equals.
// compare_runs calls it; `floesim regress` too, before any run.
void validate(const CompareOptions& options);
struct DatasetDifference {
  std::string dataset, what;   // what: "missing in B", "shape", or "values"
  std::size_t count = 0;       // elements out of tolerance
  double max_abs = 0.0;        // largest |a - b|
  std::size_t at = 0;          // flat index of the largest difference
};
struct CompareResult {
  std::size_t datasets_compared = 0;
  std::vector<DatasetDifference> differences;
  bool equal() const { return differences.empty(); }
};
CompareResult compare_runs(const std::string& a, const std::string& b, const CompareOptions& options);

}  // namespace floesim
