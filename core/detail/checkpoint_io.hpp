#pragma once
// The /checkpoint group of a run file (core/checkpoint.hpp), for the run-file
// writer: written under `name` in the open file (RunWriter writes a new one,
// then replaces the old).
#include <string>

#include "core/checkpoint.hpp"
#include "core/detail/h5.hpp"

namespace floesim {
void write_checkpoint_group(hid_t file, const std::string& name, const Checkpoint& c);
}  // namespace floesim
