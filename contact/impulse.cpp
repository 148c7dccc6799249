#include "contact/impulse.hpp"


#include <Eigen/Sparse>
#include <algorithm>
#include <cmath>
#include <numeric>
#include <cstdlib>
#include <sstream>
#include <tuple>
#include <unordered_map>
#include <utility>

#include "contact/impulse_detail.hpp"
#include "contact/lcp/siconos_io.hpp"
#include "core/error.hpp"

namespace floesim::contact {

using detail::approach;
using detail::Components;

namespace {

// One row of G: up to two floe blocks (local floe index, 3 coefficients).
struct Row {
  int fa = -1, fb = -1;  // local indices (-1: static or absent)
  Eigen::Vector3d ga, gb;
};

Row make_row(const ContactPoint& c, const Vec2& u, const FloeState& sa, const FloeState& sb, int la, int lb) {
  const Vec2 ra = c.point - Vec2{sa.x, sa.y};
  const Vec2 rb = c.point - (Vec2{sb.x, sb.y} + c.shift);
  Row r;
  r.fa = la;
  r.fb = lb;
  r.ga = -Eigen::Vector3d(u.x(), u.y(), cross(ra, u));
  r.gb = Eigen::Vector3d(u.x(), u.y(), cross(rb, u));
  return r;
}

}  // namespace

namespace {
// The largest complementarity error of z over the rows of the scaled LCP,
// in m/s (impulse.hpp, "accepted within velocity_tolerance"). Every row of
// contact k is in units of velocity times s_k (w' = s_k w, z' = z / s_k for
// lambda and beta, the alpha row and alpha the other way round), so
// |min(z'_i, w'_i)| / s_k is a velocity: how far the contact's velocity is
// from its law, or the velocity change its impulse error makes.
double velocity_error(const lcp::Lcp& problem, const Eigen::VectorXd& z, const std::vector<double>& scale) {
  const std::size_t m = scale.size();
  const Eigen::VectorXd w = lcp::affine_map(problem, z);
  double worst = 0.0;
  for (std::size_t i = 0; i < 4 * m; ++i) {
    const std::size_t k = i < m ? i : i < 3 * m ? (i - m) / 2 : i - 3 * m;
    const auto r = static_cast<Eigen::Index>(i);
    worst = std::max(worst, std::abs(std::min(z[r], w[r])) / scale[k]);
  }
  return worst;
}


std::uint64_t pair_key(std::uint32_t a, std::uint32_t b) { return (std::uint64_t{a} << 32) | b; }
Vec2 body_point(const Floes& floes, std::uint32_t a, const Vec2& p) {
  const FloeState& s = floes.state[a];
  return rotate(p - Vec2{s.x, s.y}, -s.yaw);
}
Vec2 body_direction(const Floes& floes, std::uint32_t a, const Vec2& v) { return rotate(v, -floes.state[a].yaw); }
// A contact point as a feature pair, in body frames that do not change while
// the floes move: its vertex, in the body frame of the floe it belongs to
// (vertex_of_b: b's, from b's own image), and its normal, in the body frame
// of the floe whose edge it is on. The point itself (the mid-point of the
// vertex and its closest boundary point) slides with the floes.
struct Feature {
  Vec2 vertex, normal;
};
Feature feature(const Floes& floes, const ContactPoint& c) {
  if (c.vertex_of_b)
    return {body_point(floes, c.b, c.point + 0.5 * c.gap * c.normal - c.shift), body_direction(floes, c.a, c.normal)};
  return {body_point(floes, c.a, c.point - 0.5 * c.gap * c.normal), body_direction(floes, c.b, c.normal)};
}

// The guess for the LCP of the contacts `list` (unknowns ordered as in
// impulse.hpp: lambda [m], beta [2m], alpha [m]).
std::vector<std::uint8_t> warm_guess(const WarmStart& warm, const Floes& floes,
                                     const std::vector<ContactPoint>& contacts, const std::vector<std::size_t>& list) {
  const std::size_t m = list.size();
  std::vector<std::uint8_t> basic(4 * m, 0);
  // One entry per contact at most: two contacts at one point (a corner against a corner
  // gives two normals there) must not both take the flags of one, or their two lambdas
  // could both be basic on nearly equal rows, a singular start.
  std::unordered_map<const WarmStart::Entry*, std::uint8_t> taken;
  for (std::size_t k = 0; k < m; ++k) {
    const ContactPoint& c = contacts[list[k]];
    const auto it = warm.pairs.find(pair_key(c.a, c.b));
    if (it == warm.pairs.end()) continue;
    const Feature f = feature(floes, c);
    const WarmStart::Entry* best = nullptr;
    double best_d = warm.match_distance;
    for (const WarmStart::Entry& e : it->second.entries) {
      // The same vertex (within match_distance) on the same edge (normals within about 0.1 rad).
      if (e.vertex_of_b != c.vertex_of_b) continue;
      const double d = (e.body_point - f.vertex).norm() + 10.0 * warm.match_distance * (e.body_normal - f.normal).norm();
      if (d <= best_d && !taken.contains(&e)) {
        best_d = d;
        best = &e;
      }
    }
    if (!best) continue;
    taken.emplace(best, 1);
    basic[k] = best->basic[0];
    basic[m + 2 * k] = best->basic[1];
    basic[m + 2 * k + 1] = best->basic[2];
    basic[3 * m + k] = best->basic[3];
  }
  return basic;
}

// Stores the final basis of the LCP of `list` (which z's were basic),
// replacing what its pairs had.
void warm_store(WarmStart& warm, const Floes& floes, const std::vector<ContactPoint>& contacts,
                const std::vector<std::size_t>& list, const std::vector<std::uint8_t>& z_basic) {
  const std::size_t m = list.size();
  for (std::size_t k = 0; k < m; ++k) {
    const ContactPoint& c = contacts[list[k]];
    WarmStart::Pair& pair = warm.pairs[pair_key(c.a, c.b)];
    pair.entries.clear();
    pair.stored = warm.clock;
    if (warm.log) warm.written.push_back(pair_key(c.a, c.b));
  }
  auto on = [&](std::size_t i) -> std::uint8_t { return z_basic[i]; };
  for (std::size_t k = 0; k < m; ++k) {
    const ContactPoint& c = contacts[list[k]];
    const Feature f = feature(floes, c);
    warm.pairs[pair_key(c.a, c.b)].entries.push_back(
        {f.vertex, f.normal, {on(k), on(m + 2 * k), on(m + 2 * k + 1), on(3 * m + k)}, c.vertex_of_b});
  }
}

// Writes a failed LCP as DIR/failed_lcp_<number>.dat ([contact] dump_failed_lcps).
void dump_failed(const lcp::Lcp& problem, std::size_t m, double friction, const lcp::FallbackResult& res,
                 long number, const std::string& dir) {
  std::ostringstream c;
  c << "floesim collision LCP that the fallback chain did not solve (contact/impulse.hpp): " << m
    << " contacts, friction " << friction << ", unknowns (lambda[m], beta[2m], alpha[m]), scaled per contact\n"
    << "attempts (method status pivots residual):";
  for (const lcp::Attempt& a : res.attempts)
    c << " " << lcp::to_string(a.method) << " " << lcp::to_string(a.status) << " " << a.pivots << " " << a.residual << ";";
  lcp::write_siconos_lcp(problem, dir + "/failed_lcp_" + std::to_string(number) + ".dat", c.str());
}

}  // namespace

double normal_target(const ContactPoint& c, const ImpulseOptions& opt) {
  const double h = std::max(opt.speculative_step, opt.step_floor);
  double target = 0.0;
  if (c.speculative) target = -0.9 * (c.gap - 0.5 * opt.collision_distance) / h;
  else if (c.gap < opt.min_gap) target = (opt.min_gap - c.gap) / opt.relaxation_time;
  // What the floes' turning closes beyond the linear gap (jam time steps).
  if (opt.speculative_step > 0.0) target += c.turning / h;
  return target;
}

double target_shortfall(const Floes& floes, const ContactPoint& c, const ImpulseOptions& opt) {
  return normal_target(c, opt) + approach(floes, floes.state, c.a, c.b, c.point, c.point - c.shift, c.normal);
}

namespace {

// The collision LCP of one contact component (impulse.hpp), assembled as
// data: G's rows, the floes' velocities and inverse masses, the per-contact
// scaling, targets and restitutions, and the scaled LCP itself.
struct ComponentLcp {
  std::vector<std::size_t> list;     // the component's contacts (indices into the caller's list)
  std::vector<std::uint32_t> global; // its dynamic floes, in local order
  std::vector<Row> rows;             // 3m rows: normals [m], then +T, -T per contact
  Eigen::VectorXd W, Ainv;           // 3 per floe: (vx, vy, omega), (1/m, 1/m, 1/I)
  std::vector<double> target;        // m/s, the normal velocity each contact must reach
  std::vector<double> scale;         // s_k = 1 / sqrt(D_kk)
  std::vector<double> restitution;   // e_k
  lcp::Lcp problem;                  // scaled, M' = S M S, q' = S q (q from W, refreshed by fill_q)
  double fastest = 0.0;              // m/s, the most negative normal entry of q at assembly (fill_q)

  std::size_t contacts() const { return list.size(); }
  std::size_t contact_of(std::size_t r) const {
    const std::size_t m = contacts();
    return r < m ? r : (r - m) / 2;
  }
  double row_times(const Row& r, const Eigen::VectorXd& v) const {
    double s = 0.0;
    if (r.fa >= 0) s += r.ga.dot(v.segment<3>(3 * r.fa));
    if (r.fb >= 0) s += r.gb.dot(v.segment<3>(3 * r.fb));
    return s;
  }
  // q' = S (Gn W - target, Gt W, 0); returns the most negative unscaled
  // normal entry (the fastest approach once the targets are met: nothing to
  // do if it is >= 0).
  double fill_q() {
    const std::size_t m = contacts();
    problem.q = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(4 * m));
    double worst = 0.0;
    for (std::size_t r = 0; r < 3 * m; ++r) {
      double q = row_times(rows[r], W);
      if (r < m) {
        q -= target[r];
        worst = std::min(worst, q);
      }
      problem.q[static_cast<Eigen::Index>(r)] = scale[contact_of(r)] * q;
    }
    return worst;
  }
};

// Assembles the LCP of the contacts `list` from the floes' present
// velocities (impulse.hpp). M is dense up to opt.dense_max unknowns.
ComponentLcp assemble(const Floes& floes, const std::vector<ContactPoint>& contacts, std::vector<std::size_t> list,
                      const ImpulseOptions& opt, std::span<const std::uint8_t> resting) {
  ComponentLcp a;
  a.list = std::move(list);
  const std::size_t m = a.list.size();
  // Local numbering of the dynamic floes of the component.
  std::unordered_map<std::uint32_t, int> local;
  auto index_of = [&](std::uint32_t f) -> int {
    if (floes.is_static[f]) return -1;
    auto [it, fresh] = local.emplace(f, static_cast<int>(a.global.size()));
    if (fresh) a.global.push_back(f);
    return it->second;
  };
  a.rows.resize(3 * m);
  for (std::size_t k = 0; k < m; ++k) {
    const ContactPoint& c = contacts[a.list[k]];
    const int la = index_of(c.a), lb = index_of(c.b);
    const FloeState &sa = floes.state[c.a], &sb = floes.state[c.b];
    const Vec2 T{-c.normal.y(), c.normal.x()};
    a.rows[k] = make_row(c, c.normal, sa, sb, la, lb);
    a.rows[m + 2 * k] = make_row(c, T, sa, sb, la, lb);
    a.rows[m + 2 * k + 1] = make_row(c, -T, sa, sb, la, lb);
  }
  const std::size_t nf = a.global.size();
  a.W.resize(static_cast<Eigen::Index>(3 * nf));
  a.Ainv.resize(static_cast<Eigen::Index>(3 * nf));
  for (std::size_t f = 0; f < nf; ++f) {
    const FloeState& s = floes.state[a.global[f]];
    a.W.segment<3>(3 * static_cast<Eigen::Index>(f)) << s.vx, s.vy, s.yaw_rate;
    a.Ainv.segment<3>(3 * static_cast<Eigen::Index>(f)) << floes.inv_mass(a.global[f]), floes.inv_mass(a.global[f]),
        floes.inv_inertia_z(a.global[f]);
  }
  // Normal velocity each contact must reach (>= 0 plus the gap stabilisation).
  // Speculative gaps and turning become speeds over the step, taken no
  // shorter than step_floor (impulse.hpp: round-off over a sliver).
  a.target.assign(m, 0.0);
  for (std::size_t k = 0; k < m; ++k) a.target[k] = normal_target(contacts[a.list[k]], opt);
  // Scaling (symmetric, so the LCP keeps the structure Lemke relies on):
  // with s_k = 1 / sqrt(D_kk), D = Gn A^-1 Gn^T (s_k^2 is the effective
  // mass at contact k), the unknowns are lambda_k = s_k lambda'_k,
  // beta_k = s_k beta'_k, alpha_k = alpha'_k / s_k, and the rows of contact k
  // are multiplied by s_k (normal, tangent) and 1/s_k (friction): M' = S M S,
  // q' = S q. The normal diagonal becomes 1, the E, mu and -E^T entries are
  // unchanged, and M' is copositive as M is (z'^T M' z' = (S z')^T M (S z')).
  // Unscaled, inverse masses of 1e-7 next to the O(1) friction rows defeat
  // the pivoting tolerances; scaled on one side only (M S), the Delassus
  // block loses its symmetry and Lemke ends on secondary rays in jams.
  a.scale.assign(m, 1.0);
  for (std::size_t k = 0; k < m; ++k) {
    double dkk = 0.0;
    const Row& r = a.rows[k];
    if (r.fa >= 0) dkk += r.ga.cwiseProduct(a.Ainv.segment<3>(3 * r.fa)).dot(r.ga);
    if (r.fb >= 0) dkk += r.gb.cwiseProduct(a.Ainv.segment<3>(3 * r.fb)).dot(r.gb);
    if (dkk > 0.0) a.scale[k] = 1.0 / std::sqrt(dkk);
  }
  // Restitution per contact: 0 for resting and speculative contacts (see the header).
  a.restitution.assign(m, opt.restitution);
  for (std::size_t k = 0; k < m; ++k)
    if (contacts[a.list[k]].speculative || (!resting.empty() && resting[a.list[k]])) a.restitution[k] = 0.0;

  // Delassus blocks G A^-1 G^T: rows interact through shared floes.
  std::vector<std::vector<std::size_t>> rows_of(nf);
  for (std::size_t r = 0; r < a.rows.size(); ++r) {
    if (a.rows[r].fa >= 0) rows_of[static_cast<std::size_t>(a.rows[r].fa)].push_back(r);
    if (a.rows[r].fb >= 0) rows_of[static_cast<std::size_t>(a.rows[r].fb)].push_back(r);
  }
  auto block = [&](const Row& r, int f) -> const Eigen::Vector3d* {
    if (r.fa == f) return &r.ga;
    if (r.fb == f) return &r.gb;
    return nullptr;
  };
  const std::size_t n = 4 * m;
  std::vector<Eigen::Triplet<double>> trip;
  trip.reserve(n * 8);
  for (std::size_t f = 0; f < nf; ++f) {
    const Eigen::Vector3d ai = a.Ainv.segment<3>(3 * static_cast<Eigen::Index>(f));
    for (std::size_t r1 : rows_of[f])
      for (std::size_t r2 : rows_of[f]) {
        const Eigen::Vector3d& g1 = *block(a.rows[r1], static_cast<int>(f));
        const Eigen::Vector3d& g2 = *block(a.rows[r2], static_cast<int>(f));
        trip.emplace_back(static_cast<int>(r1), static_cast<int>(r2),
                          a.scale[a.contact_of(r1)] * g1.cwiseProduct(ai).dot(g2) * a.scale[a.contact_of(r2)]);
      }
  }
  for (std::size_t k = 0; k < m; ++k) {
    const int al = static_cast<int>(3 * m + k);
    trip.emplace_back(static_cast<int>(m + 2 * k), al, 1.0);  // E
    trip.emplace_back(static_cast<int>(m + 2 * k + 1), al, 1.0);
    trip.emplace_back(al, static_cast<int>(k), opt.friction);  // mu
    trip.emplace_back(al, static_cast<int>(m + 2 * k), -1.0);  // -E^T
    trip.emplace_back(al, static_cast<int>(m + 2 * k + 1), -1.0);
  }
  lcp::SparseMatrix S(static_cast<int>(n), static_cast<int>(n));
  S.setFromTriplets(trip.begin(), trip.end());  // duplicates (same floe twice) are summed
  if (n <= opt.dense_max) a.problem.M = lcp::DenseMatrix(S);
  else a.problem.M = std::move(S);
  a.fastest = a.fill_q();
  return a;
}

// Solves a component's LCP by the fallback chain (lcp/fallback.hpp): large
// ones start from the basis in opt.warm (WarmStart), both the Newton method
// (from n >= solver.newton_min_size) and Lemke; an answer the chain did not
// accept is still taken within opt.velocity_tolerance. The statistics are
// counted here; a failure is written to opt.dump_failed_lcps.
lcp::FallbackResult solve(const ComponentLcp& a, const Floes& floes, const std::vector<ContactPoint>& contacts,
                          const ImpulseOptions& opt, CollisionStats& stats) {
  const std::size_t m = a.contacts(), n = 4 * m;
  lcp::FallbackOptions solver = opt.solver;  // with the layout, for the contact-wise Gauss–Seidel
  solver.friction = {m, opt.friction};
  if (solver.lemke.max_pivots == 0) solver.lemke.max_pivots = opt.lemke_pivots_per_unknown * static_cast<long>(n) + 1000;
  const bool use_warm = opt.warm != nullptr && n >= opt.warm_min;
  std::vector<std::uint8_t> guess;
  if (use_warm) {
    ++opt.warm->uses;
    guess = warm_guess(*opt.warm, floes, contacts, a.list);
    if (std::find(guess.begin(), guess.end(), 1) != guess.end()) {
      solver.lemke.start = &guess;
      solver.newton.start = &guess;
    }
  }
  lcp::FallbackResult res = lcp::solve_with_fallbacks(a.problem, solver);
  if (use_warm && res.solved() && !res.result.z_basic.empty())
    warm_store(*opt.warm, floes, contacts, a.list, res.result.z_basic);
  for (const lcp::Attempt& at : res.attempts) {
    if (at.method == lcp::Method::lemke_warm) ++(at.status == lcp::Status::solved ? stats.warm : stats.warm_missed);
    if (at.method == lcp::Method::lemke_warm_normal && at.status == lcp::Status::solved) ++stats.warm;
    // Lemke's pivots, of every attempt (the others count iterations or sweeps).
    if (at.method != lcp::Method::newton && at.method != lcp::Method::contact_newton &&
        at.method != lcp::Method::coulomb_gs && at.method != lcp::Method::pgs)
      stats.pivots += at.pivots;
  }
  ++stats.lcps;
  stats.contacts += static_cast<long>(m);
  stats.largest = std::max(stats.largest, static_cast<long>(n));
  stats.total_size += static_cast<long>(n);
  // A fallback: the chain went past Lemke from scratch (Newton and the warm
  // start are first tries, not fallbacks).
  const auto first_tries = std::count_if(res.attempts.begin(), res.attempts.end(), [](const lcp::Attempt& at) {
    return at.method == lcp::Method::newton || at.method == lcp::Method::contact_newton ||
           at.method == lcp::Method::lemke_warm || at.method == lcp::Method::lemke_warm_normal;
  });
  if (res.attempts.size() - static_cast<std::size_t>(first_tries) > 1) ++stats.fallbacks;
  if (res.flagged) ++stats.flagged;
  if (res.solved() && res.method == lcp::Method::coulomb_gs) ++stats.gauss_seidel;
  if (!res.solved() && res.result.z.size() == static_cast<Eigen::Index>(n) &&
      velocity_error(a.problem, res.result.z, a.scale) <= opt.velocity_tolerance) {
    res.result.status = lcp::Status::solved;  // within velocity_tolerance (impulse.hpp)
    ++stats.tolerated;
  }
  if (!res.solved()) {
    ++stats.failures;
    if (!opt.dump_failed_lcps.empty()) dump_failed(a.problem, m, opt.friction, res, stats.failures, opt.dump_failed_lcps);
  }
  return res;
}

// Applies the scaled answer z' of pass `pass` (0: compression then Poisson's
// decompression, impulse (1 + e_k) z_k; 1: compression only) to the
// component's velocities, W += A^-1 G^T z, and adds the impulses to `total`.
void apply(ComponentLcp& a, const lcp::Vector& z_scaled, int pass, Eigen::VectorXd& total) {
  const std::size_t m = a.contacts();
  Eigen::VectorXd z = z_scaled.head(static_cast<Eigen::Index>(3 * m));
  for (std::size_t r = 0; r < 3 * m; ++r) {
    const std::size_t k = a.contact_of(r);
    z[static_cast<Eigen::Index>(r)] *= a.scale[k] * (pass == 0 ? 1.0 + a.restitution[k] : 1.0);
  }
  total += z;
  Eigen::VectorXd p = Eigen::VectorXd::Zero(a.W.size());
  for (std::size_t r = 0; r < 3 * m; ++r) {
    const double zr = z[static_cast<Eigen::Index>(r)];
    if (zr == 0.0) continue;
    if (a.rows[r].fa >= 0) p.segment<3>(3 * a.rows[r].fa) += zr * a.rows[r].ga;
    if (a.rows[r].fb >= 0) p.segment<3>(3 * a.rows[r].fb) += zr * a.rows[r].gb;
  }
  a.W += a.Ainv.cwiseProduct(p);
}

}  // namespace

std::vector<ContactImpulse> resolve_collisions(Floes& floes, const std::vector<ContactPoint>& contacts,
                                               const ImpulseOptions& opt, CollisionStats& stats,
                                               std::span<const std::uint8_t> resting) {
  std::vector<ContactImpulse> impulses(contacts.size());
  if (contacts.empty()) return impulses;
  // Sustained or impact, by the approach before the solve (ImpulseRecord).
  const std::vector<std::uint8_t> slow = opt.record ? slow_contacts(floes, contacts, opt.rest_speed)
                                                    : std::vector<std::uint8_t>{};

  // Contact graph over dynamic floes.
  Components comp;
  for (const ContactPoint& c : contacts) {
    if (floes.is_static[c.a] && floes.is_static[c.b]) continue;
    if (floes.is_static[c.a]) comp.node(c.b);
    else if (floes.is_static[c.b]) comp.node(c.a);
    else comp.join(comp.node(c.a), comp.node(c.b));
  }
  std::unordered_map<std::uint32_t, std::vector<std::size_t>> groups;  // root -> contacts
  for (std::size_t j = 0; j < contacts.size(); ++j) {
    const ContactPoint& c = contacts[j];
    if (floes.is_static[c.a] && floes.is_static[c.b]) continue;
    const std::uint32_t owner = floes.is_static[c.a] ? c.b : c.a;
    groups[comp.root_of(owner)].push_back(j);
  }
  std::vector<std::vector<std::size_t>> ordered;
  ordered.reserve(groups.size());
  for (auto& [root, list] : groups) ordered.push_back(std::move(list));
  std::sort(ordered.begin(), ordered.end());  // deterministic order of solves

  for (std::vector<std::size_t>& list : ordered) {
    ComponentLcp a = assemble(floes, contacts, std::move(list), opt, resting);
    const std::size_t m = a.contacts();
    if (!(a.fastest < -opt.approach_tolerance)) continue;  // nothing approaches
    // Pass 0: compression LCP on W^-, then Poisson's decompression. Poisson's
    // law applied to several contacts at once can leave a contact that was
    // separating before the collision approaching after it; pass 1 then
    // solves a compression LCP (restitution 0) from W^+ so that no contact
    // ends approaching (only where Poisson's law acted).
    Eigen::VectorXd total = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(3 * m));  // impulses applied
    const bool elastic = std::any_of(a.restitution.begin(), a.restitution.end(), [](double e) { return e != 0.0; });
    for (int pass = 0; pass < 2; ++pass) {
      if (pass == 1 && (!elastic || !(a.fill_q() < -opt.approach_tolerance))) break;
      const lcp::FallbackResult res = solve(a, floes, contacts, opt, stats);
      if (!res.solved()) break;  // leave these velocities as they are: counted and reported
      apply(a, res.result.z, pass, total);
    }
    for (std::size_t f = 0; f < a.global.size(); ++f) {
      FloeState& s = floes.state[a.global[f]];
      s.vx = a.W[3 * static_cast<Eigen::Index>(f)];
      s.vy = a.W[3 * static_cast<Eigen::Index>(f) + 1];
      s.yaw_rate = a.W[3 * static_cast<Eigen::Index>(f) + 2];
    }
    for (std::size_t k = 0; k < m; ++k) {
      ContactImpulse& ci = impulses[a.list[k]];
      ci.normal = total[static_cast<Eigen::Index>(k)];
      ci.tangential = total[static_cast<Eigen::Index>(m + 2 * k)] - total[static_cast<Eigen::Index>(m + 2 * k + 1)];
      const ContactPoint& c = contacts[a.list[k]];
      ci.vector = ci.normal * c.normal + ci.tangential * Vec2{-c.normal.y(), c.normal.x()};
      ci.point = c.point;
    }
  }
  if (opt.record) record_impulses(*opt.record, floes, contacts, impulses, slow);
  return impulses;
}

std::vector<std::uint8_t> slow_contacts(const Floes& floes, std::span<const ContactPoint> contacts, double rest_speed,
                                        std::span<const FloeState> velocities) {
  const std::span<const FloeState> v = velocities.empty() ? std::span<const FloeState>(floes.state) : velocities;
  std::vector<std::uint8_t> slow(contacts.size(), 0);
  for (std::size_t k = 0; k < contacts.size(); ++k) {
    const ContactPoint& c = contacts[k];
    slow[k] = approach(floes, v, c.a, c.b, c.point, c.point - c.shift, c.normal) <= rest_speed;
  }
  return slow;
}

void record_impulses(ImpulseRecord& record, const Floes& floes, std::span<const ContactPoint> contacts,
                     std::span<const ContactImpulse> impulses, std::span<const std::uint8_t> slow) {
  detail::record_impulses(record, floes, contacts, impulses, slow, nullptr);
}

void detail::record_impulses(ImpulseRecord& record, const Floes& floes, std::span<const ContactPoint> contacts,
                             std::span<const ContactImpulse> impulses, std::span<const std::uint8_t> slow,
                             std::vector<std::uint32_t>* contact_of) {
  const std::uint32_t event = record.events++;
  for (std::size_t j = 0; j < contacts.size() && j < impulses.size(); ++j) {
    const ContactImpulse& ci = impulses[j];
    if (!(ci.vector.squaredNorm() > 0.0)) continue;
    const ContactPoint& c = contacts[j];
    const bool sustained = j < slow.size() && slow[j];
    const std::pair<std::uint32_t, double> sides[2] = {{c.a, -1.0}, {c.b, 1.0}};
    for (const auto& [f, sign] : sides) {
      if (floes.is_static[f]) continue;
      const Vec2 world = sign > 0.0 ? Vec2(ci.point - c.shift) : ci.point;
      record.loads.push_back({f, event, body_point(floes, f, world), body_direction(floes, f, sign * ci.vector),
                              sustained, sign > 0.0 ? c.a : c.b, ci.normal, ci.point});
      if (contact_of) contact_of->push_back(static_cast<std::uint32_t>(j));
    }
  }
}

void merge_step_record(ImpulseRecord& into, std::span<const RecordPart> parts) {
  // The whole call records once: one event, even with no load.
  const std::uint32_t event = into.events++;
  // (place, part, load): a place is one contact, hence one share's; its
  // loads (a's, then b's) keep their order by the load index.
  std::vector<std::tuple<ContactPlace, std::size_t, std::size_t>> order;
  for (std::size_t p = 0; p < parts.size(); ++p) {
    FLOESIM_ASSERT(parts[p].places.size() == parts[p].record->loads.size());
    for (std::size_t l = 0; l < parts[p].record->loads.size(); ++l) order.emplace_back(parts[p].places[l], p, l);
  }
  std::sort(order.begin(), order.end());
  into.loads.reserve(into.loads.size() + order.size());
  for (const auto& [place, p, l] : order) {
    into.loads.push_back(parts[p].record->loads[l]);
    into.loads.back().event = event;
  }
}

void merge_advance_record(ImpulseRecord& into, std::span<const RecordPart> parts) {
  // (place, part, event): the serial queue pops by place; the solves of one
  // pop are one share's, in its own order (its event numbers).
  std::vector<std::tuple<EventPlace, std::size_t, std::uint32_t>> order;
  std::vector<std::vector<std::size_t>> first(parts.size());  // per part, per event: its first load (then the next's)
  for (std::size_t p = 0; p < parts.size(); ++p) {
    const ImpulseRecord& record = *parts[p].record;
    FLOESIM_ASSERT(parts[p].events.size() == record.events);
    for (std::uint32_t e = 0; e < record.events; ++e) order.emplace_back(parts[p].events[e], p, e);
    // Loads are appended event by event: each event's loads are a run.
    first[p].assign(record.events + 1, record.loads.size());
    for (std::size_t l = record.loads.size(); l-- > 0;) first[p][record.loads[l].event] = l;
    for (std::size_t e = record.events; e-- > 0;) first[p][e] = std::min(first[p][e], first[p][e + 1]);
  }
  std::sort(order.begin(), order.end());
  for (const auto& [place, p, e] : order) {
    const std::uint32_t event = into.events++;
    for (std::size_t l = first[p][e]; l < first[p][e + 1]; ++l) {
      into.loads.push_back(parts[p].record->loads[l]);
      into.loads.back().event = event;
    }
  }
}

}  // namespace floesim::contact
