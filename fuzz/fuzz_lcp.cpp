// libFuzzer target: the Siconos Numerics LCP text reader
// (contact/lcp/siconos_io.cpp). The input is the file's text. A problem that
// is read must pass check_lcp (the reader's promise: sizes consistent, every
// number finite) and its sparse copy and M z + q must be computable.
#include <cstdint>
#include <string_view>

#include "contact/lcp/lcp.hpp"
#include "contact/lcp/siconos_io.hpp"
#include "core/error.hpp"
#include "fuzz/fuzz_util.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace floesim;
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  lcp::Lcp p;
  try {
    p = lcp::parse_siconos_lcp(text, "fuzz.dat");
  } catch (const InputError& e) {
    fuzz::refused(e);
    return 0;
  }
  lcp::check_lcp(p);  // an InputError here escapes: the reader let a bad problem through
  (void)lcp::nonzeros(p);
  (void)lcp::sparse_copy(p);
  (void)lcp::affine_map(p, lcp::Vector::Ones(p.q.size()));
  return 0;
}
