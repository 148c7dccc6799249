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
//   /sea/x [nx], /sea/y [ny], /sea/eta [T, ny, nx] (dims 2) or [T, nx] (dims 1)
//   /diagnostics/energy [T, k] (columns attribute; the last column is "total")
//   /diagnostics/lcp [T, 4]: solves, pivots, failures, fallbacks (cumulative)
//   /xdmf/vertices [T, V, 3]: world vertex positions (x, y, heave) for ParaView
//   /xdmf/topology [E]: XDMF mixed-polygon connectivity

#include <array>
#include <memory>
#include <span>
#include <string>
#include <vector>

namespace floesim {

struct Floes;

inline constexpr const char* kRunFormat = "floesim-1";

// The sea grid recorded in /sea (cell centres).
struct SeaGridInfo {
  int dims = 0;                       // 0: no sea recorded
  std::array<int, 2> cells{};         // nx, ny (ny ignored for dims 1)
  std::array<double, 2> size{};       // m
};

struct LcpCounters {
  double solves = 0, pivots = 0, failures = 0, fallbacks = 0;  // cumulative
};

class RunWriter {
public:
  // Creates (truncates) the file and writes the static parts. Throws
  // InputError if the file cannot be created. expected_records (0: unknown)
  // sizes the chunks of the per-record datasets (more records still fit).
  RunWriter(const std::string& path, const Floes& floes, const std::string& config_toml,
            std::vector<std::string> energy_columns, const SeaGridInfo& sea = {},
            std::size_t expected_records = 0);
  ~RunWriter();  // closes; leaves status "running" unless finish() was called
  RunWriter(const RunWriter&) = delete;
  RunWriter& operator=(const RunWriter&) = delete;

  // Appends one record and flushes the file. `energy` has one value per
  // column; `eta` is the sea elevation on the grid (row-major, y slowest), or
  // empty when there is no sea.
  void record(double t, const Floes& floes, std::span<const double> energy,
              const LcpCounters& lcp, std::span<const double> eta = {});

  // Marks the run complete, or failed with a reason, and writes the XDMF.
  void finish(const std::string& status);

  std::size_t records() const;
  const std::string& path() const;
  std::string xdmf_path() const;

private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// A summary of a run file, for `floesim info`.
struct RunInfo {
  std::string format, status, config;
  std::size_t records = 0, floes = 0, vertices = 0;
  double t_first = 0.0, t_last = 0.0;
  std::vector<std::string> energy_columns;
  std::vector<double> energy_last;      // last record
  std::array<double, 4> lcp_last{};     // solves, pivots, failures, fallbacks
  std::vector<std::pair<std::string, std::vector<unsigned long long>>> datasets;  // path, shape
};
RunInfo read_run_info(const std::string& path);

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
