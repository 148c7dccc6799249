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

// W and b of the header, in the order (n_0, t_0, n_1, t_1, ...).
struct ContactForm {
  SparseMatrix W;
  Vector b;
  std::vector<std::array<double, 4>> block;  // W_kk: nn, nt, tn, tt
};

ContactForm contact_form(const Lcp& lcp, std::size_t m) {
  const SparseMatrix M = sparse_copy(lcp);
  const Index mi = static_cast<Index>(m);
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
  check_lcp(lcp);
  const std::size_t m = layout.contacts;
  const Index mi = static_cast<Index>(m);
  if (m == 0 || lcp.size() != 4 * mi)
    throw RunError("contact-wise Gauss–Seidel: the LCP has " + std::to_string(lcp.size()) +
                     " unknowns, not 4 per contact for " + std::to_string(m) + " contacts");
  if (start.size() != 0 && start.size() != lcp.size())
    throw RunError("contact-wise Gauss–Seidel: the start point must have n entries");
  const ContactForm f = contact_form(lcp, m);
  const double mu = layout.friction;

  Vector r = Vector::Zero(2 * mi);  // (lambda_k, beta_k)
  if (start.size() != 0)
    for (Index k = 0; k < mi; ++k) {
      r(2 * k) = std::max(0.0, start(k));
      r(2 * k + 1) = start(mi + 2 * k) - start(mi + 2 * k + 1);
    }
  Vector u = f.W * r + f.b;

  Result result;
  auto to_z = [&] {
    result.z = Vector::Zero(lcp.size());
    for (Index k = 0; k < mi; ++k) {
      result.z(k) = r(2 * k);
      result.z(mi + 2 * k) = std::max(0.0, r(2 * k + 1));
      result.z(mi + 2 * k + 1) = std::max(0.0, -r(2 * k + 1));
      result.z(3 * mi + k) = std::abs(u(2 * k + 1));
    }
  };
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
