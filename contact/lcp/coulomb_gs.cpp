#include "contact/lcp/coulomb_gs.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "core/error.hpp"

namespace floesim::lcp {

namespace {

// The contact's own 2x2 Coulomb problem, the others held: u = W_kk r + c.
std::array<double, 2> local_solve(const std::array<double, 4>& B, double cn, double ct, double mu) {
  const double nn = B[0], nt = B[1], tn = B[2], tt = B[3];
  if (cn >= 0.0) return {0.0, 0.0};  // separates with no force
  // Sticking: u = 0.
  const double det = nn * tt - nt * tn;
  if (det > 0.0) {
    const double l = (-cn * tt + ct * nt) / det;
    const double b = (-ct * nn + cn * tn) / det;
    if (l > 0.0 && std::abs(b) <= mu * l) return {l, b};
  }
  // Sliding in direction s (u_t s >= 0), friction -s mu lambda, u_n = 0.
  std::array<double, 2> best{0.0, 0.0};
  double best_violation = std::numeric_limits<double>::infinity();
  for (const double s : {ct < 0.0 ? -1.0 : 1.0, ct < 0.0 ? 1.0 : -1.0}) {
    const double denominator = nn - s * mu * nt;
    if (!(denominator > 0.0)) continue;
    const double l = -cn / denominator;
    const double ut = (tn - s * mu * tt) * l + ct;
    const double violation = std::max(0.0, -s * ut);
    if (violation < best_violation) {
      best_violation = violation;
      best = {l, -s * mu * l};
    }
    if (violation == 0.0) break;
  }
  return best;
}

}  // namespace

Result solve_coulomb_gs(const Lcp& lcp, const FrictionLayout& layout, const Vector& start,
                        const CoulombGsOptions& options) {
  const ContactForm f = contact_form(lcp, layout, "contact-wise Gauss–Seidel");
  const std::size_t m = layout.contacts;
  const Index mi = static_cast<Index>(m);
  if (start.size() != 0 && start.size() != lcp.size())
    throw RunError("contact-wise Gauss–Seidel: the start point must have n entries");
  const double mu = layout.friction;

  Vector r = start.size() != 0 ? contact_impulses(start, m) : Vector(Vector::Zero(2 * mi));  // (lambda_k, beta_k)
  Vector u = f.W * r + f.b;

  Result result;
  auto to_z = [&] { result.z = lcp_point(r, u); };
  const int check_every = std::max(1, options.check_every);
  to_z();  // the start, should no sweep run
  result.status = Status::pivot_limit;
  for (long sweep = 1; sweep <= options.max_sweeps; ++sweep) {
    for (Index k = 0; k < mi; ++k) {
      const auto& B = f.block[static_cast<std::size_t>(k)];
      const double l0 = r(2 * k), b0 = r(2 * k + 1);
      const double cn = u(2 * k) - (B[0] * l0 + B[1] * b0);
      const double ct = u(2 * k + 1) - (B[2] * l0 + B[3] * b0);
      const auto [l, b] = local_solve(B, cn, ct, mu);
      const double dl = l - l0, db = b - b0;
      if (dl != 0.0) {
        for (SparseMatrix::InnerIterator it(f.W, 2 * k); it; ++it) u(it.index()) += dl * it.value();
        r(2 * k) = l;
      }
      if (db != 0.0) {
        for (SparseMatrix::InnerIterator it(f.W, 2 * k + 1); it; ++it) u(it.index()) += db * it.value();
        r(2 * k + 1) = b;
      }
    }
    result.iterations = sweep;
    if (sweep % check_every == 0 || sweep == options.max_sweeps) {
      u = f.W * r + f.b;  // shed the drift of the column updates
      to_z();
      if (!std::isfinite(r.squaredNorm())) {
        result.status = Status::failed;
        break;
      }
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
