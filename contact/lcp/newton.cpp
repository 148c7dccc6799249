#include "contact/lcp/newton.hpp"

#include <Eigen/UmfPackSupport>
#include <algorithm>
#include <cmath>
#include <string>

#include "core/error.hpp"

namespace floesim::lcp {

namespace {

// M_AA + delta I for the unknowns `active` (ascending), from M by columns.
SparseMatrix principal_block(const SparseMatrix& M, const std::vector<Index>& active,
                             const std::vector<Index>& position, double delta) {
  const Index k = static_cast<Index>(active.size());
  SparseMatrix B(k, k);
  std::vector<Eigen::Triplet<double>> trip;
  trip.reserve(static_cast<std::size_t>(k) * 8);
  for (Index c = 0; c < k; ++c) {
    trip.emplace_back(static_cast<int>(c), static_cast<int>(c), delta);
    for (SparseMatrix::InnerIterator it(M, active[static_cast<std::size_t>(c)]); it; ++it) {
      const Index r = position[static_cast<std::size_t>(it.index())];
      if (r >= 0) trip.emplace_back(static_cast<int>(r), static_cast<int>(c), it.value());
    }
  }
  B.setFromTriplets(trip.begin(), trip.end());
  B.makeCompressed();
  return B;
}

double merit(const Vector& z, const Vector& w) { return 0.5 * z.cwiseMin(w).squaredNorm(); }

}  // namespace

Result solve_newton(const Lcp& lcp, const NewtonOptions& options, NewtonStats* stats) {
  check_lcp(lcp);
  const Index n = lcp.size();
  check_start("Newton LCP solver", n, options.start, options.start_point);
  NewtonStats local;
  NewtonStats& st = stats ? *stats : local;
  const SparseMatrix M = sparse_copy(lcp);
  const Vector& q = lcp.q;
  const double q_scale = 1.0 + q.norm();
  const double delta = options.regularisation * std::max(1.0, M.diagonal().cwiseAbs().maxCoeff());

  Vector z = options.start_point.size() == n ? Vector(options.start_point.cwiseMax(0.0)) : Vector::Zero(n);
  Vector w = M * z + q;
  std::vector<std::uint8_t> active(static_cast<std::size_t>(n), 0);
  for (Index i = 0; i < n; ++i)
    active[static_cast<std::size_t>(i)] = options.start ? ((*options.start)[static_cast<std::size_t>(i)] != 0)
                                                        : static_cast<std::uint8_t>(w(i) < z(i));
  Result result;
  result.status = Status::pivot_limit;
  std::vector<Index> list, position;
  Eigen::UmfPackLU<SparseMatrix> lu;
  for (int iteration = 1; iteration <= options.max_iterations; ++iteration) {
    result.iterations = iteration;
    // The point (1) of the header for the present active set.
    const Index k = select_unknowns(active, list, position);
    Vector target = Vector::Zero(n);
    if (k > 0) {
      SparseMatrix B = principal_block(M, list, position, delta);
      lu.compute(B);
      ++st.factorisations;
      if (lu.info() != Eigen::Success) {
        result.status = Status::failed;
        break;
      }
      for (Index c = 0; c < k; ++c) B.coeffRef(c, c) -= delta;  // M_AA itself for the residual
      Vector x(k), rhs(k);
      for (Index c = 0; c < k; ++c) {
        x(c) = z(list[static_cast<std::size_t>(c)]);
        rhs(c) = -q(list[static_cast<std::size_t>(c)]);
      }
      double last_defect = INFINITY;
      for (int r = 0; r < options.max_refinements; ++r) {
        const Vector defect = rhs - B * x;
        const double size = defect.lpNorm<Eigen::Infinity>();
        // Converged, or stalled: an inconsistent (1), whose x only drifts.
        if (size <= options.refine_tolerance * q_scale || size > 0.5 * last_defect) break;
        last_defect = size;
        x += lu.solve(defect);
        ++st.refinements;
      }
      for (Index c = 0; c < k; ++c) target(list[static_cast<std::size_t>(c)]) = x(c);
    }
    if (!target.allFinite()) {
      result.status = Status::failed;
      break;
    }
    // Damped step towards it (Armijo on phi; w is affine in z).
    const Vector target_w = M * target + q;
    const Vector dz = target - z, dw = target_w - w;
    const double phi = merit(z, w);
    double t = 1.0;
    int halvings = 0;
    while (halvings <= options.max_backtracks &&
           merit(z + t * dz, w + t * dw) > (1.0 - 2.0 * options.armijo * t) * phi) {
      t *= 0.5;
      ++halvings;
    }
    if (halvings > options.max_backtracks) {  // no step length decreased phi: the full step
      t = 1.0;
      ++st.full_steps;
    } else {
      st.backtracks += halvings;
    }
    if (t == 1.0) {
      z = target;
      w = target_w;
    } else {
      z += t * dz;
      w = M * z + q;
    }
    // Judged as returned: z >= 0.
    result.z = z.cwiseMax(0.0);
    finish(lcp, result);
    if (result.residual <= options.tolerance) {
      result.status = Status::solved;
      break;
    }
    // The next active set, read off F at z.
    const std::vector<std::uint8_t> previous = active;
    for (Index i = 0; i < n; ++i) active[static_cast<std::size_t>(i)] = w(i) < z(i);
    long changed = 0;
    for (std::size_t i = 0; i < active.size(); ++i) changed += active[i] != previous[i];
    st.changed += changed;
    if (changed == 0 && t == 1.0) {  // the same point again: (1) has no exact solution for this set
      result.status = Status::failed;
      break;
    }
  }
  if (result.z.size() != n) {
    result.z = z.cwiseMax(0.0);
    finish(lcp, result);
  }
  result.z_basic = active;
  return result;
}

}  // namespace floesim::lcp
