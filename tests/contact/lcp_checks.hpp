#pragma once
// Shared by the contact tests: data paths, and a check of an LCP solution that
// does not trust any solver code (it recomputes w = M z + q itself).

#include <doctest/doctest.h>

#include <cstdint>
#include <fstream>
#include <string>
#include <vector>

#include "contact/lcp/lcp.hpp"

namespace floesim::lcp::testing {

inline std::string lcp_data(const std::string& name) {
  return std::string(FLOESIM_DATA_DIR) + "/lcp/" + name;
}

// A warm start of data/lcp/jam (NAME.guess: one 0/1 flag per unknown, which z
// were basic in the previous LCP of the same contacts).
inline std::vector<std::uint8_t> read_guess(const std::string& path) {
  std::ifstream in(path);
  REQUIRE(in.good());
  std::vector<std::uint8_t> flags;
  for (int v = 0; in >> v;) flags.push_back(static_cast<std::uint8_t>(v != 0));
  return flags;
}

// Asserts z >= 0, w >= 0 and z_i w_i = 0 within `tol`, relative to the scale
// of the problem (1 + max |q|, and |z_i| |w_i| against max(1, |z_i|) (1 + max|q|)).
inline void check_complementary(const Lcp& lcp, const Vector& z, double tol) {
  REQUIRE(z.size() == lcp.size());
  const Index n = lcp.size();
  Vector w = lcp.q;
  if (const auto* D = std::get_if<DenseMatrix>(&lcp.M)) {
    for (Index j = 0; j < n; ++j)
      for (Index i = 0; i < n; ++i) w(i) += (*D)(i, j) * z(j);
  } else {
    const auto& S = std::get<SparseMatrix>(lcp.M);
    for (Index j = 0; j < n; ++j)
      for (SparseMatrix::InnerIterator it(S, j); it; ++it) w(it.index()) += it.value() * z(j);
  }
  const double scale = 1.0 + lcp.q.cwiseAbs().maxCoeff();
  double worst_z = 0.0, worst_w = 0.0, worst_zw = 0.0;
  for (Index i = 0; i < n; ++i) {
    worst_z = std::max(worst_z, -z(i));
    worst_w = std::max(worst_w, -w(i) / scale);
    worst_zw = std::max(worst_zw, std::abs(z(i) * w(i)) / (std::max(1.0, std::abs(z(i))) * scale));
  }
  CHECK(worst_z <= tol);
  CHECK(worst_w <= tol);
  CHECK(worst_zw <= tol);
}

}  // namespace floesim::lcp::testing
