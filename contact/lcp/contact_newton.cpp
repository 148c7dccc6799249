#include "contact/lcp/contact_newton.hpp"

#include <Eigen/UmfPackSupport>
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "contact/lcp/coulomb_gs.hpp"
#include "core/error.hpp"

namespace floesim::lcp {

namespace {

enum class State : std::uint8_t { separated, stick, slide_plus, slide_minus };

// The state the Alart–Curnier rule (header) picks for contact k at (r, u).
State choose(const Vector& r, const Vector& u, Index k, double cn, double ct, double mu) {
  const double aug_n = r(2 * k) - cn * u(2 * k);
  if (!(aug_n > 0.0)) return State::separated;
  const double aug_t = r(2 * k + 1) - ct * u(2 * k + 1);
  if (std::abs(aug_t) <= mu * aug_n) return State::stick;
  return aug_t > 0.0 ? State::slide_plus : State::slide_minus;
}

// The states a Lemke basis implies (header, "Start").
State from_flags(const std::vector<std::uint8_t>& flags, Index k, Index m) {
  auto f = [&](Index i) { return flags[static_cast<std::size_t>(i)] != 0; };
  if (!f(k)) return State::separated;
  if (f(3 * m + k)) {
    if (f(m + 2 * k)) return State::slide_plus;
    if (f(m + 2 * k + 1)) return State::slide_minus;
  }
  return State::stick;
}

// Unknowns (and equations) per state: lambda and beta sticking, lambda sliding.
int unknowns(State s) { return s == State::separated ? 0 : (s == State::stick ? 2 : 1); }

double slide_sign(State s) { return s == State::slide_plus ? 1.0 : -1.0; }

// The system of the states: (W + eps I) restricted to their rows, with each
// sliding beta column folded into its lambda column (beta = s mu lambda).
SparseMatrix state_system(const SparseMatrix& W, const std::vector<State>& state, const std::vector<Index>& first,
                          Index size, double mu, double eps) {
  std::vector<Eigen::Triplet<double>> trip;
  trip.reserve(static_cast<std::size_t>(W.nonZeros()) + static_cast<std::size_t>(size));
  auto row_of = [&](Index i) -> Index {
    const State s = state[static_cast<std::size_t>(i / 2)];
    if (s == State::separated || (s != State::stick && i % 2 == 1)) return -1;
    return first[static_cast<std::size_t>(i / 2)] + i % 2;
  };
  for (Index c = 0; c < W.outerSize(); ++c) {
    const State s = state[static_cast<std::size_t>(c / 2)];
    if (s == State::separated) continue;
    const Index var = first[static_cast<std::size_t>(c / 2)] + (s == State::stick ? c % 2 : 0);
    const double factor = (s == State::stick || c % 2 == 0) ? 1.0 : slide_sign(s) * mu;
    for (SparseMatrix::InnerIterator it(W, c); it; ++it) {
      const Index row = row_of(it.index());
      if (row >= 0) trip.emplace_back(static_cast<int>(row), static_cast<int>(var), factor * it.value());
    }
  }
  for (Index i = 0; i < size; ++i) trip.emplace_back(static_cast<int>(i), static_cast<int>(i), eps);
  SparseMatrix K(size, size);
  K.setFromTriplets(trip.begin(), trip.end());
  K.makeCompressed();
  return K;
}

std::vector<std::uint8_t> basis_of(const std::vector<State>& state, const Vector& r, Index m) {
  std::vector<std::uint8_t> basic(static_cast<std::size_t>(4 * m), 0);
  for (Index k = 0; k < m; ++k) {
    const State s = state[static_cast<std::size_t>(k)];
    if (s == State::separated) continue;
    basic[static_cast<std::size_t>(k)] = 1;
    const double beta = s == State::stick ? r(2 * k + 1) : slide_sign(s);
    if (beta > 0.0) basic[static_cast<std::size_t>(m + 2 * k)] = 1;
    if (beta < 0.0) basic[static_cast<std::size_t>(m + 2 * k + 1)] = 1;
    if (s != State::stick) basic[static_cast<std::size_t>(3 * m + k)] = 1;
  }
  return basic;
}

}  // namespace

Result solve_contact_newton(const Lcp& lcp, const FrictionLayout& layout, const ContactNewtonOptions& options,
                            ContactNewtonStats* stats) {
  const ContactForm f = contact_form(lcp, layout, "contact Newton method");
  const Index n = lcp.size(), m = n / 4;
  const double mu = layout.friction;
  check_start("contact Newton method", n, options.start, options.start_point);
  ContactNewtonStats local;
  ContactNewtonStats& st = stats ? *stats : local;

  const double scale = std::max(1.0, f.W.diagonal().cwiseAbs().maxCoeff());
  const double eps_min = options.proximal * scale, eps_max = options.proximal_max * scale;
  std::vector<double> cn(static_cast<std::size_t>(m)), ct(static_cast<std::size_t>(m));
  for (Index k = 0; k < m; ++k) {
    const auto& B = f.block[static_cast<std::size_t>(k)];
    cn[static_cast<std::size_t>(k)] = 1.0 / std::max(B[0], 1e-12 * scale);
    ct[static_cast<std::size_t>(k)] = 1.0 / std::max(B[3], 1e-12 * scale);
  }

  Vector r = options.start_point.size() == n ? contact_impulses(options.start_point, static_cast<std::size_t>(m))
                                             : Vector(Vector::Zero(2 * m));
  if (options.gs_sweeps > 0) {
    CoulombGsOptions gs;
    gs.max_sweeps = options.gs_sweeps;
    gs.check_every = static_cast<int>(std::max<long>(1, options.gs_sweeps));
    gs.tolerance = options.tolerance;
    const Result g = solve_coulomb_gs(lcp, layout, lcp_point(r, f.W * r + f.b), gs);
    if (g.status == Status::solved) return g;
    r = contact_impulses(g.z, static_cast<std::size_t>(m));
  }
  Vector u = f.W * r + f.b;
  std::vector<State> state(static_cast<std::size_t>(m));
  for (Index k = 0; k < m; ++k)
    state[static_cast<std::size_t>(k)] =
        options.start && options.gs_sweeps == 0 ? from_flags(*options.start, k, m)
                      : choose(r, u, k, cn[static_cast<std::size_t>(k)], ct[static_cast<std::size_t>(k)], mu);

  Result result;
  result.z = lcp_point(r, u);
  result.status = residual(lcp, result.z) <= options.tolerance ? Status::solved : Status::pivot_limit;
  double eps = std::clamp(options.proximal_start * scale, eps_min, eps_max);
  std::vector<Index> first(static_cast<std::size_t>(m));
  SparseMatrix K;  // the factorised system (UMFPACK's solves read it again)
  Eigen::UmfPackLU<SparseMatrix> lu;
  bool factorised = false;  // lu holds the system of `state` at `eps`
  Index size = 0;
  Vector center = r;        // the proximal centre r_k
  int inner = 0;            // solves around the present centre
  bool done = result.status == Status::solved;  // the start solves it
  while (!done && st.solves < options.max_iterations) {
    ++st.solves;
    result.iterations = static_cast<long>(st.solves);
    if (!factorised) {
      size = 0;
      for (Index k = 0; k < m; ++k) {
        first[static_cast<std::size_t>(k)] = size;
        size += unknowns(state[static_cast<std::size_t>(k)]);
      }
      if (size > 0) {
        K = state_system(f.W, state, first, size, mu, eps);
        lu.compute(K);
        ++st.factorisations;
        if (lu.info() != Eigen::Success) {
          if (eps >= eps_max) {
            result.status = Status::failed;
            break;
          }
          eps = std::min(eps_max, eps * options.proximal_growth);
          ++st.rejected;
          continue;
        }
      }
      factorised = true;
    }
    // The present states' system around the centre (header).
    Vector next = Vector::Zero(2 * m);
    if (size > 0) {
      Vector rhs(size);
      for (Index k = 0; k < m; ++k) {
        const State s = state[static_cast<std::size_t>(k)];
        const Index p = first[static_cast<std::size_t>(k)];
        if (s == State::separated) continue;
        rhs(p) = -f.b(2 * k) + eps * center(2 * k);
        if (s == State::stick) rhs(p + 1) = -f.b(2 * k + 1) + eps * center(2 * k + 1);
      }
      const Vector x = lu.solve(rhs);
      for (Index k = 0; k < m; ++k) {
        const State s = state[static_cast<std::size_t>(k)];
        const Index p = first[static_cast<std::size_t>(k)];
        if (s == State::separated) continue;
        next(2 * k) = x(p);
        next(2 * k + 1) = s == State::stick ? x(p + 1) : slide_sign(s) * mu * x(p);
      }
    }
    if (!std::isfinite(next.squaredNorm())) {
      result.status = Status::failed;
      break;
    }
    r = next;
    u = f.W * r + f.b;
    ++inner;
    // The states of the regularised problem at the new point: its velocities
    // are u + eps (r - centre).
    const Vector u_reg = u + eps * (r - center);
    long changes = 0;
    for (Index k = 0; k < m; ++k) {
      const State s = choose(r, u_reg, k, cn[static_cast<std::size_t>(k)], ct[static_cast<std::size_t>(k)], mu);
      if (s != state[static_cast<std::size_t>(k)]) {
        state[static_cast<std::size_t>(k)] = s;
        ++changes;
      }
    }
    st.state_changes += changes;
    if (changes > 0) factorised = false;
    if (changes == 0 || inner >= options.max_inner) {
      // The regularised problem solved (or given up): judge the point, move the centre.
      result.z = lcp_point(r, u);
      const double res_now = residual(lcp, result.z);
      if (res_now <= options.tolerance) {
        result.status = Status::solved;
        done = true;
      }
      if (changes > 0 && eps < eps_max) {  // the states cycle: a larger eps damps the steps
        eps = std::min(eps_max, eps * options.proximal_growth);
        ++st.rejected;
        factorised = false;
      } else if (changes == 0 && inner <= options.shrink_after && eps > eps_min) {
        eps = std::max(eps_min, eps / options.proximal_growth);  // the states hold: take longer steps
        factorised = false;
      }
      center = r;
      inner = 0;
    }
  }
  result.z_basic = basis_of(state, r, m);
  finish(lcp, result);
  return result;
}

}  // namespace floesim::lcp
