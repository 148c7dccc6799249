#include "contact/lcp/fallback.hpp"

#include <algorithm>
#include <cmath>

namespace floesim::lcp {

std::string_view to_string(Method method) {
  switch (method) {
    case Method::newton: return "newton";
    case Method::contact_newton: return "contact_newton";
    case Method::lemke_warm: return "lemke_warm";
    case Method::lemke_warm_normal: return "lemke_warm_normal";
    case Method::lemke: return "lemke";
    case Method::lemke_other_covering: return "lemke_other_covering";
    case Method::lemke_regularised: return "lemke_regularised";
    case Method::coulomb_gs: return "coulomb_gs";
    case Method::pgs: return "pgs";
  }
  return "lemke";
}

namespace {

Lcp regularised(const Lcp& lcp, double relative_shift) {
  Lcp shifted;
  shifted.q = lcp.q;
  SparseMatrix M = sparse_copy(lcp);
  const double scale = std::max(1.0, M.diagonal().cwiseAbs().maxCoeff());
  SparseMatrix I(M.rows(), M.cols());
  I.setIdentity();
  shifted.M = SparseMatrix(M + relative_shift * scale * I);
  if (!lcp.is_sparse()) shifted.M = DenseMatrix(std::get<SparseMatrix>(shifted.M));
  return shifted;
}

}  // namespace

FallbackResult solve_with_fallbacks(const Lcp& lcp, const FallbackOptions& options) {
  FallbackResult out;
  // Records an attempt, judged on the original LCP; true when it is accepted.
  // The first tries (Newton, the warm start) are kept only when accepted:
  // the best failed attempt, which the Gauss–Seidel step starts from and the
  // chain returns when nothing succeeds, is one of the steps from scratch.
  bool from_scratch = false;  // out.result holds a step from scratch
  auto record = [&](Method method, Result result) {
    finish(lcp, result);
    if (result.status == Status::solved && result.residual > options.accept_residual)
      result.status = Status::failed;
    out.attempts.push_back({method, result.status, std::max(result.pivots, result.iterations),
                            result.residual});
    const bool accepted = result.status == Status::solved;
    const bool first_try =
        method == Method::newton || method == Method::contact_newton || method == Method::lemke_warm ||
        method == Method::lemke_warm_normal;
    if (accepted || out.attempts.size() == 1 || (!first_try && !from_scratch) ||
        result.residual < out.result.residual) {
      from_scratch = from_scratch || !first_try;
      out.result = std::move(result);
      out.method = method;
    }
    return accepted;
  };

  if (options.newton_min_size > 0 && lcp.size() >= options.newton_min_size) {
    NewtonOptions newton = options.newton;
    newton.tolerance = std::min(newton.tolerance, options.accept_residual);
    if (record(Method::newton, solve_newton(lcp, newton))) return out;
  }
  if (options.friction.contacts > 0 && options.contact_newton_min_size > 0 &&
      lcp.size() >= options.contact_newton_min_size) {
    ContactNewtonOptions contact = options.contact_newton;
    contact.tolerance = std::min(contact.tolerance, options.accept_residual);
    if (!contact.start) contact.start = options.lemke.start;
    if (record(Method::contact_newton, solve_contact_newton(lcp, options.friction, contact))) return out;
  }
  LemkeOptions cold = options.lemke;
  if (cold.start) {
    if (record(Method::lemke_warm, solve_lemke(lcp, options.lemke))) return out;
    const std::size_t m = options.friction.contacts;
    if (options.warm_normal_retry && m > 0 && lcp.size() == static_cast<Index>(4 * m)) {
      std::vector<std::uint8_t> normal(cold.start->begin(), cold.start->end());
      std::fill(normal.begin() + static_cast<std::ptrdiff_t>(m), normal.end(), std::uint8_t{0});
      if (normal != *cold.start && std::find(normal.begin(), normal.end(), 1) != normal.end()) {
        LemkeOptions again = options.lemke;
        again.start = &normal;
        if (record(Method::lemke_warm_normal, solve_lemke(lcp, again))) return out;
      }
    }
    cold.start = nullptr;
  }
  if (record(Method::lemke, solve_lemke(lcp, cold))) return out;

  if (options.friction.contacts > 0) {
    CoulombGsOptions gs = options.coulomb_gs;
    gs.tolerance = std::min(gs.tolerance, options.accept_residual);
    if (record(Method::coulomb_gs, solve_coulomb_gs(lcp, options.friction, out.result.z, gs))) return out;
  }

  LemkeOptions other = cold;
  other.covering.resize(lcp.size());
  for (Index i = 0; i < lcp.size(); ++i) other.covering(i) = 1.0 + static_cast<double>(i % 7) / 7.0;
  if (record(Method::lemke_other_covering, solve_lemke(lcp, other))) return out;

  const Lcp shifted = regularised(lcp, options.regularisation);
  if (record(Method::lemke_regularised, solve_lemke(shifted, cold))) return out;

  if (options.allow_pgs) {
    PgsOptions pgs = options.pgs;
    pgs.tolerance = std::min(pgs.tolerance, options.accept_residual);
    record(Method::pgs, solve_pgs(lcp, pgs));
    out.flagged = out.method == Method::pgs;
  }
  return out;
}

}  // namespace floesim::lcp
