#include "contact/lcp/contact_form.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "core/error.hpp"

namespace floesim::lcp {

ContactForm contact_form(const Lcp& lcp, const FrictionLayout& layout, const char* who) {
  check_lcp(lcp);
  const std::size_t m = layout.contacts;
  const Index mi = static_cast<Index>(m);
  if (m == 0 || lcp.size() != 4 * mi)
    throw RunError(std::string(who) + ": the LCP has " + std::to_string(lcp.size()) +
                   " unknowns, not 4 per contact for " + std::to_string(m) + " contacts");
  const SparseMatrix M = sparse_copy(lcp);
  // LCP index -> contact-form index: normal rows/columns k -> 2k, +T ones m + 2k -> 2k + 1,
  // the -T and alpha ones -> -1 (not part of W).
  auto map = [mi](Index i) -> Index {
    if (i < mi) return 2 * i;
    if (i < 3 * mi && (i - mi) % 2 == 0) return 2 * ((i - mi) / 2) + 1;
    return -1;
  };
  ContactForm f;
  std::vector<Eigen::Triplet<double>> trip;
  for (Index j = 0; j < M.outerSize(); ++j) {
    const Index c = map(j);
    if (c < 0) continue;
    for (SparseMatrix::InnerIterator it(M, j); it; ++it) {
      const Index r = map(it.index());
      if (r >= 0) trip.emplace_back(static_cast<int>(r), static_cast<int>(c), it.value());
    }
  }
  f.W.resize(2 * mi, 2 * mi);
  f.W.setFromTriplets(trip.begin(), trip.end());
  f.b.resize(2 * mi);
  f.block.assign(m, {0.0, 0.0, 0.0, 0.0});
  for (Index k = 0; k < mi; ++k) {
    f.b(2 * k) = lcp.q(k);
    f.b(2 * k + 1) = lcp.q(mi + 2 * k);
    auto& B = f.block[static_cast<std::size_t>(k)];
    B = {f.W.coeff(2 * k, 2 * k), f.W.coeff(2 * k, 2 * k + 1), f.W.coeff(2 * k + 1, 2 * k),
         f.W.coeff(2 * k + 1, 2 * k + 1)};
  }
  return f;
}

Vector lcp_point(const Vector& r, const Vector& u) {
  const Index mi = r.size() / 2;
  Vector z = Vector::Zero(4 * mi);
  for (Index k = 0; k < mi; ++k) {
    z(k) = std::max(0.0, r(2 * k));
    z(mi + 2 * k) = std::max(0.0, r(2 * k + 1));
    z(mi + 2 * k + 1) = std::max(0.0, -r(2 * k + 1));
    z(3 * mi + k) = std::abs(u(2 * k + 1));
  }
  return z;
}

Vector contact_impulses(const Vector& z, std::size_t contacts) {
  const Index mi = static_cast<Index>(contacts);
  Vector r(2 * mi);
  for (Index k = 0; k < mi; ++k) {
    r(2 * k) = std::max(0.0, z(k));
    r(2 * k + 1) = z(mi + 2 * k) - z(mi + 2 * k + 1);
  }
  return r;
}

}  // namespace floesim::lcp
