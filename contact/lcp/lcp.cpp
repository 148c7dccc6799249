#include "contact/lcp/lcp.hpp"

#include <cmath>
#include <string>

#include "core/error.hpp"

namespace floesim::lcp {

Vector affine_map(const Lcp& lcp, const Vector& z) {
  return std::visit([&](const auto& M) -> Vector { return M * z + lcp.q; }, lcp.M);
}

SparseMatrix sparse_copy(const Lcp& lcp) {
  if (const auto* S = std::get_if<SparseMatrix>(&lcp.M)) {
    SparseMatrix copy = *S;
    copy.makeCompressed();
    return copy;
  }
  return std::get<DenseMatrix>(lcp.M).sparseView(0.0, 0.0);
}

Index nonzeros(const Lcp& lcp) {
  if (const auto* S = std::get_if<SparseMatrix>(&lcp.M)) return S->nonZeros();
  const auto& D = std::get<DenseMatrix>(lcp.M);
  return (D.array() != 0.0).count();
}

void check_start(std::string_view solver, Index n, const std::vector<std::uint8_t>* flags, const Vector& point) {
  if (flags && static_cast<Index>(flags->size()) != n)
    throw RunError(std::string(solver) + ": the warm start has " + std::to_string(flags->size()) + " flags for " +
                   std::to_string(n) + " unknowns");
  if (point.size() != 0 && point.size() != n)
    throw RunError(std::string(solver) + ": the start point has " + std::to_string(point.size()) + " entries for " +
                   std::to_string(n) + " unknowns");
}

Index select_unknowns(const std::vector<std::uint8_t>& flags, std::vector<Index>& list, std::vector<Index>& position) {
  list.clear();
  position.assign(flags.size(), -1);
  for (std::size_t i = 0; i < flags.size(); ++i)
    if (flags[i]) {
      position[i] = static_cast<Index>(list.size());
      list.push_back(static_cast<Index>(i));
    }
  return static_cast<Index>(list.size());
}

void check_lcp(const Lcp& lcp) {
  const Index n = lcp.size();
  const auto [rows, cols] = std::visit(
      [](const auto& M) { return std::pair<Index, Index>{M.rows(), M.cols()}; }, lcp.M);
  if (n < 1) throw RunError("LCP: q is empty (n must be at least 1)");
  if (rows != n || cols != n)
    throw RunError("LCP: M is " + std::to_string(rows) + " x " + std::to_string(cols) +
                     " but q has " + std::to_string(n) + " entries");
  if (!lcp.q.allFinite()) throw RunError("LCP: q has a non-finite entry");
  const bool finite = std::visit(
      [](const auto& M) {
        if constexpr (std::is_same_v<std::decay_t<decltype(M)>, SparseMatrix>)
          return Eigen::Map<const Vector>(M.valuePtr(), M.nonZeros()).allFinite();
        else
          return M.allFinite();
      },
      lcp.M);
  if (!finite) throw RunError("LCP: M has a non-finite entry");
}

std::string_view to_string(Status status) {
  switch (status) {
    case Status::solved: return "solved";
    case Status::ray: return "ray";
    case Status::pivot_limit: return "pivot_limit";
    case Status::failed: return "failed";
  }
  return "failed";
}

namespace {

// || min(z, w) ||_2 / (1 + || q ||_2), +inf when anything is not finite.
double scaled_natural_residual(const Vector& z, const Vector& w, const Vector& q) {
  const double r = z.cwiseMin(w).norm() / (1.0 + q.norm());
  return std::isfinite(r) ? r : INFINITY;
}

}  // namespace

double residual(const Lcp& lcp, const Vector& z) {
  if (z.size() != lcp.size()) return INFINITY;
  return scaled_natural_residual(z, affine_map(lcp, z), lcp.q);
}

void finish(const Lcp& lcp, Result& result) {
  result.w = affine_map(lcp, result.z);
  result.residual = scaled_natural_residual(result.z, result.w, lcp.q);
}

}  // namespace floesim::lcp
