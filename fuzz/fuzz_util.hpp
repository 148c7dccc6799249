#pragma once
// Shared by the fuzz targets: a scratch file per process for the readers that
// take a path, and the rule every target enforces: a reader may refuse its
// input only with floesim::InputError; any other exception escapes
// LLVMFuzzerTestOneInput, which libFuzzer reports as a crash (an uncaught
// exception is what ends floesim with exit 134).

#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <string>

namespace floesim::fuzz {

// A file in $TMPDIR (default /tmp) named after the target and the process, so
// that parallel fuzzing jobs (-jobs=N) do not share it. Removed at exit.
inline const std::string& scratch_path(const char* target, const char* ext) {
  static const std::string path = [&] {
    const char* dir = std::getenv("TMPDIR");
    std::string p = std::string(dir && *dir ? dir : "/tmp") + "/floesim-fuzz-" + target + "-" +
                    std::to_string(::getpid()) + ext;
    static std::string removed;
    removed = p;
    std::atexit([] { std::remove(removed.c_str()); });
    return p;
  }();
  return path;
}

// Writes the bytes to `path` (truncating); aborts if it cannot, since a
// target that silently reads a stale file would fuzz nothing.
inline void write_file(const std::string& path, const std::uint8_t* data, std::size_t size) {
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (!f || (size && std::fwrite(data, 1, size, f) != size) || std::fclose(f) != 0) {
    std::perror(path.c_str());
    std::abort();
  }
}

// Called with each refusal: prints it when FLOESIM_FUZZ_VERBOSE is set (to see
// why a seed is refused; silent while fuzzing).
inline void refused(const std::exception& e) {
  static const bool verbose = std::getenv("FLOESIM_FUZZ_VERBOSE") != nullptr;
  if (verbose) std::fprintf(stderr, "refused: %s\n", e.what());
}

}  // namespace floesim::fuzz
