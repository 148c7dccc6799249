// libFuzzer target: the forcing time-series CSV (core/forcing.cpp). The input
// is the file's bytes; it is read with both interpolations and, when taken,
// sampled before, at, between and after its rows.
#include <cstdint>
#include <limits>

#include "core/error.hpp"
#include "core/forcing.hpp"
#include "fuzz/fuzz_util.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace floesim;
  const std::string& path = fuzz::scratch_path("forcing", ".csv");
  fuzz::write_file(path, data, size);
  for (SeriesInterpolation interp : {SeriesInterpolation::linear, SeriesInterpolation::previous}) {
    try {
      const ForcingSeries s = ForcingSeries::from_csv(path, interp);
      if (s.rows() == 0) __builtin_trap();  // "no data row" must have been refused
      for (double t : {-1e300, -1.0, 0.0, 0.5, 1.0, 60.0, 1e9, 1e300,
                       std::numeric_limits<double>::infinity()})
        (void)s.at(t);
    } catch (const InputError& e) {
      fuzz::refused(e);
    }
  }
  return 0;
}
