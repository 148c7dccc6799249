#include "contact/lcp/pgs.hpp"

#include <algorithm>

namespace floesim::lcp {

Result solve_pgs(const Lcp& lcp, const PgsOptions& options) {
  check_lcp(lcp);
  const Index n = lcp.size();
  const SparseMatrix M = sparse_copy(lcp);
  const Vector diagonal = M.diagonal();
  Result result;
  result.z = Vector::Zero(n);
  if (!(diagonal.array() > 0.0).all()) {
    result.status = Status::failed;
    finish(lcp, result);
    return result;
  }
  Vector w = lcp.q;  // M z + q for the current z
  const int check_every = std::max(1, options.check_every);
  result.status = Status::pivot_limit;
  for (long sweep = 1; sweep <= options.max_iterations; ++sweep) {
    for (Index i = 0; i < n; ++i) {
      const double zi = std::max(0.0, result.z(i) - options.relaxation * w(i) / diagonal(i));
      const double dz = zi - result.z(i);
      if (dz == 0.0) continue;
      result.z(i) = zi;
      for (SparseMatrix::InnerIterator it(M, i); it; ++it) w(it.index()) += dz * it.value();
    }
    result.iterations = sweep;
    if (sweep % check_every == 0 || sweep == options.max_iterations) {
      if (residual(lcp, result.z) <= options.tolerance) {
        result.status = Status::solved;
        break;
      }
    }
  }
  finish(lcp, result);
  return result;
}

}  // namespace floesim::lcp
