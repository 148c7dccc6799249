#pragma once
// The run configuration: a TOML file (ARCHITECTURE.md, docs/config.md) read
// into the plain parameter structs of core/params.hpp.
//
// Every key has a default; an unknown key, a wrong type or an out-of-range
// value throws InputError naming the file, the line and the key. Relative
// paths inside the file are resolved against the file's folder.

#include <string>
#include <string_view>
#include <vector>

#include "core/floe.hpp"
#include "core/pack.hpp"
#include "core/params.hpp"

namespace floesim {

struct FloesConfig {
  std::string pack;               // absolute path of a pack file, or empty
  PackDefaults defaults;          // [floes] thickness, density
  std::vector<FloeInput> floes;   // inline [[floes.floe]], in file order
};

struct Config {
  std::string file;               // the configuration file ("" when parsed from text)
  RunParams run;
  SeaParams sea;
  FloesConfig floes;
  ContactParams contact;
  CouplingParams coupling;
  ForcingParams forcing;
  FractureParams fracture;
};

// At most this many records in a run file (t = 0, one every output_interval, t_end):
// it bounds the file's size and the steps shortened to land on output times
// (output_interval = 1e-320 would write records without end).
inline constexpr double kMaxRecords = 1e7;
// The most cells a sea grid may have ([sea] cells, nx * ny for dims = 2).
inline constexpr double kMaxSeaCells = 16777216.0;
// [sea] model = "bem", dims = 2: surface cells at most (a dense LU of about
// three times as many panels: 2048 cells took 4 min and 0.75 GB, docs/sea.md).
inline constexpr double kMaxBem3dCells = 4096.0;
// The same with only the lowest modes kept ([sea] bem_modes > 0): the dense LU
// of the panels is then the bound (4608 cells took 19 min and 2.3 GB; 6144,
// about 20000 panels, extrapolate to 45 min and 4 GB; docs/sea.md).
inline constexpr double kMaxBem3dLowestCells = 6144.0;

// The rule on the number of records, in one place for [run] t_end and for
// `floesim run --until`: "" if a run to t_end writes at most kMaxRecords records
// at output_interval (both > 0 and finite), else what was expected.
std::string record_count_problem(double t_end, double output_interval);
// At most this many steps of dt_max up to t_end: more would be a run without
// end in practice (1e9 steps at 1e5 steps/s take three hours); dt_max =
// 1e-300 s made `floesim run` hang.
inline constexpr double kMaxSteps = 1e9;
// The same rule for steps: "" if t_end / dt_max (both > 0) is at most kMaxSteps.
std::string step_count_problem(double t_end, double dt_max);

// The largest configuration file read: 64 MiB (some hundred thousand inline
// floes); a larger one, or a device that never ends, is refused.
inline constexpr std::size_t kMaxConfigBytes = std::size_t{64} << 20;

// Reads and checks a configuration file.
Config load_config(const std::string& path);

// Same from text; `name` is used in messages, `base_dir` resolves relative paths.
Config parse_config(std::string_view text, const std::string& name, const std::string& base_dir);

// The resolved configuration (every key with the value in force) as TOML text:
// echoed into the run file's `config` attribute.
std::string resolved_toml(const Config& config);

// What differs between two resolved configurations (resolved_toml texts, e.g.
// the `config` attribute of a run file and a configuration now) in the keys
// that change a run's results: one "key: run value -> value now" line per
// key, e.g. "[coupling] stiffness: 1000.0 -> 500.0". Left out: [run] t_end
// and checkpoint_interval (where a run stops and when it saves itself).
// Throws InputError (naming `run_name`) if the first text is not TOML.
std::vector<std::string> physics_differences(std::string_view run_toml, std::string_view now_toml,
                                             const std::string& run_name);

}  // namespace floesim
