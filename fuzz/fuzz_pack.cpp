// libFuzzer target: the pack file reader (core/pack.cpp), both formats
// (floesim-pack-1 and FloeDyn input, told apart by the reader), followed by
// the floe check every loaded floe goes through (make_floe_shape). The input
// is an HDF5 recipe or a raw HDF5 file (fuzz/h5_recipe.hpp). Built twice,
// as fuzz_pack and fuzz_floedyn, which differ only in their seed corpus.
#include <cstdint>

#include "core/error.hpp"
#include "core/floe.hpp"
#include "core/pack.hpp"
#include "fuzz/fuzz_util.hpp"
#include "fuzz/h5_recipe.hpp"

#ifndef FLOESIM_FUZZ_NAME
#define FLOESIM_FUZZ_NAME "pack"
#endif

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace floesim;
  const std::string& path = fuzz::scratch_path(FLOESIM_FUZZ_NAME, ".h5");
  if (!fuzz::build_h5(path, data, size)) return 0;
  Pack pack;
  try {
    pack = read_pack_in_process(path);
  } catch (const InputError& e) {
    fuzz::refused(e);
    return 0;
  }
  if (pack.format != "floesim-pack-1" && pack.format != "floedyn") __builtin_trap();
  for (const FloeInput& f : pack.floes) {
    try {
      (void)make_floe_shape(f);
    } catch (const InputError& e) {
      fuzz::refused(e);
    }
  }
  return 0;
}
