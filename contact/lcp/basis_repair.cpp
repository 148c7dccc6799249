#include "contact/lcp/basis_repair.hpp"

#include <Eigen/OrderingMethods>
#include <Eigen/SparseQR>
#include <algorithm>

namespace floesim::lcp {

std::vector<std::uint8_t> repair_basis(const SparseMatrix& M, const std::vector<std::uint8_t>& z_basic,
                                       const BasisRepairOptions& options, long* dropped) {
  std::vector<std::uint8_t> flags = z_basic;
  long count = 0;
  std::vector<Index> list, position;
  for (int round = 0; round < options.rounds; ++round) {
    const Index k = select_unknowns(flags, list, position);
    if (k == 0) break;
    std::vector<Eigen::Triplet<double>> trip;
    double largest = 0.0;
    for (Index c = 0; c < k; ++c) {
      double norm2 = 0.0;
      for (SparseMatrix::InnerIterator it(M, list[static_cast<std::size_t>(c)]); it; ++it) {
        const Index r = position[static_cast<std::size_t>(it.index())];
        if (r < 0) continue;
        trip.emplace_back(static_cast<int>(r), static_cast<int>(c), it.value());
        norm2 += it.value() * it.value();
      }
      largest = std::max(largest, norm2);
    }
    SparseMatrix B(k, k);
    B.setFromTriplets(trip.begin(), trip.end());
    B.makeCompressed();
    Eigen::SparseQR<SparseMatrix, Eigen::COLAMDOrdering<int>> qr;
    qr.setPivotThreshold(options.tolerance * std::sqrt(largest));
    qr.compute(B);
    if (qr.info() != Eigen::Success) break;
    const Index rank = qr.rank();
    if (rank >= k) break;
    const auto& perm = qr.colsPermutation().indices();
    for (Index j = rank; j < k; ++j) {
      flags[static_cast<std::size_t>(list[static_cast<std::size_t>(perm(j))])] = 0;
      ++count;
    }
  }
  if (dropped) *dropped = count;
  return flags;
}

}  // namespace floesim::lcp
