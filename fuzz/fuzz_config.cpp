// libFuzzer target: the TOML configuration loader (core/config.cpp). The input
// is the file's text, parsed with relative paths resolved in an empty scratch
// folder. A configuration that loads must also load again from its own
// resolved form (resolved_toml, the text echoed into every run file): a
// refusal there is reported as a crash.
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <string>
#include <string_view>

#include "core/config.hpp"
#include "core/error.hpp"
#include "fuzz/fuzz_util.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace floesim;
  static const std::string base = [] {
    std::string d = fuzz::scratch_path("config", ".d");
    std::filesystem::create_directories(d);
    return d;
  }();
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  Config c;
  try {
    c = parse_config(text, "fuzz.toml", base);
  } catch (const InputError& e) {
    fuzz::refused(e);
    return 0;
  }
  const std::string resolved = resolved_toml(c);
  try {
    (void)parse_config(resolved, "resolved.toml", base);
  } catch (const InputError& e) {
    std::fprintf(stderr, "the resolved configuration is refused: %s\n--- resolved:\n%s\n", e.what(),
                 resolved.c_str());
    __builtin_trap();
  }
  return 0;
}
