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

// Reads and checks a configuration file.
Config load_config(const std::string& path);

// Same from text; `name` is used in messages, `base_dir` resolves relative paths.
Config parse_config(std::string_view text, const std::string& name, const std::string& base_dir);

// The resolved configuration (every key with the value in force) as TOML text:
// echoed into the run file's `config` attribute.
std::string resolved_toml(const Config& config);

}  // namespace floesim
