#include "contact/impulse.hpp"

#include <Eigen/Sparse>
#include <algorithm>
#include <numeric>
#include <unordered_map>

namespace floesim::contact {

namespace {

// Union–find over floe indices.
struct Components {
  std::vector<std::uint32_t> parent;
  explicit Components(std::size_t n) : parent(n) { std::iota(parent.begin(), parent.end(), 0u); }
  std::uint32_t find(std::uint32_t i) {
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
  }
  void join(std::uint32_t a, std::uint32_t b) { parent[find(a)] = find(b); }
};

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

std::vector<ContactImpulse> resolve_collisions(Floes& floes, const std::vector<ContactPoint>& contacts,
                                               const ImpulseOptions& opt, CollisionStats& stats) {
  std::vector<ContactImpulse> impulses(contacts.size());
  if (contacts.empty()) return impulses;

  // Contact graph over dynamic floes.
  Components comp(floes.size());
  for (const ContactPoint& c : contacts)
    if (!floes.is_static[c.a] && !floes.is_static[c.b]) comp.join(c.a, c.b);
  std::unordered_map<std::uint32_t, std::vector<std::size_t>> groups;  // root -> contacts
  for (std::size_t j = 0; j < contacts.size(); ++j) {
    const ContactPoint& c = contacts[j];
    const std::uint32_t owner = floes.is_static[c.a] ? c.b : c.a;
    groups[comp.find(owner)].push_back(j);
  }
  std::vector<std::vector<std::size_t>> ordered;
  ordered.reserve(groups.size());
  for (auto& [root, list] : groups) ordered.push_back(std::move(list));
  std::sort(ordered.begin(), ordered.end());  // deterministic order of solves

  for (const std::vector<std::size_t>& list : ordered) {
    // Local numbering of the dynamic floes of the component.
    std::unordered_map<std::uint32_t, int> local;
    std::vector<std::uint32_t> global;
    auto index_of = [&](std::uint32_t f) -> int {
      if (floes.is_static[f]) return -1;
      auto [it, fresh] = local.emplace(f, static_cast<int>(global.size()));
      if (fresh) global.push_back(f);
      return it->second;
    };
    const std::size_t m = list.size();
    std::vector<Row> rows(3 * m);
    for (std::size_t k = 0; k < m; ++k) {
      const ContactPoint& c = contacts[list[k]];
      const int la = index_of(c.a), lb = index_of(c.b);
      const FloeState &sa = floes.state[c.a], &sb = floes.state[c.b];
      const Vec2 T{-c.normal.y(), c.normal.x()};
      rows[k] = make_row(c, c.normal, sa, sb, la, lb);
      rows[m + 2 * k] = make_row(c, T, sa, sb, la, lb);
      rows[m + 2 * k + 1] = make_row(c, -T, sa, sb, la, lb);
    }
    const std::size_t nf = global.size();
    Eigen::VectorXd W(3 * nf), Ainv(3 * nf);
    for (std::size_t f = 0; f < nf; ++f) {
      const FloeState& s = floes.state[global[f]];
      W.segment<3>(3 * static_cast<Eigen::Index>(f)) << s.vx, s.vy, s.yaw_rate;
      Ainv.segment<3>(3 * static_cast<Eigen::Index>(f)) << floes.inv_mass(global[f]), floes.inv_mass(global[f]),
          floes.inv_inertia_z(global[f]);
    }
    auto apply = [&](const Row& r, const Eigen::VectorXd& v) {
      double s = 0.0;
      if (r.fa >= 0) s += r.ga.dot(v.segment<3>(3 * r.fa));
      if (r.fb >= 0) s += r.gb.dot(v.segment<3>(3 * r.fb));
      return s;
    };
    // Normal velocity each contact must reach (>= 0 plus the gap stabilisation).
    std::vector<double> target(m, 0.0);
    for (std::size_t k = 0; k < m; ++k) {
      const double g = contacts[list[k]].gap;
      if (g < opt.min_gap) target[k] = (opt.min_gap - g) / opt.relaxation_time;
    }
    // q = (Gn W - target, Gt W, 0); returns its most negative normal entry
    // (the fastest approach, once the targets are met: nothing to do if >= 0).
    lcp::Lcp problem;
    auto fill_q = [&] {
      problem.q = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(4 * m));
      for (std::size_t r = 0; r < 3 * m; ++r) problem.q[static_cast<Eigen::Index>(r)] = apply(rows[r], W);
      double worst = 0.0;
      for (std::size_t k = 0; k < m; ++k) {
        problem.q[static_cast<Eigen::Index>(k)] -= target[k];
        worst = std::min(worst, problem.q[static_cast<Eigen::Index>(k)]);
      }
      return worst;
    };
    if (!(fill_q() < -opt.approach_tolerance)) continue;

    // Delassus blocks G A^-1 G^T: rows interact through shared floes.
    std::vector<std::vector<std::size_t>> rows_of(nf);
    for (std::size_t r = 0; r < rows.size(); ++r) {
      if (rows[r].fa >= 0) rows_of[static_cast<std::size_t>(rows[r].fa)].push_back(r);
      if (rows[r].fb >= 0) rows_of[static_cast<std::size_t>(rows[r].fb)].push_back(r);
    }
    auto block = [&](const Row& r, int f) -> const Eigen::Vector3d* {
      if (r.fa == f) return &r.ga;
      if (r.fb == f) return &r.gb;
      return nullptr;
    };
    // Scaling: impulses of contact k are solved for in units of s_k = 1 / D_kk
    // (D = Gn A^-1 Gn^T, so s_k is the effective mass at the contact): the
    // columns of lambda_k and beta_k are multiplied by s_k, and the friction
    // row of contact k, mu lambda_k - beta_k+ - beta_k-, is divided by s_k,
    // which leaves it unchanged. Without this, inverse masses of 1e-7 next to
    // the O(1) friction rows defeat the pivoting tolerances.
    std::vector<double> scale(m, 1.0);
    for (std::size_t k = 0; k < m; ++k) {
      double dkk = 0.0;
      const Row& r = rows[k];
      if (r.fa >= 0) dkk += r.ga.cwiseProduct(Ainv.segment<3>(3 * r.fa)).dot(r.ga);
      if (r.fb >= 0) dkk += r.gb.cwiseProduct(Ainv.segment<3>(3 * r.fb)).dot(r.gb);
      if (dkk > 0.0) scale[k] = 1.0 / dkk;
    }
    auto contact_of = [m](std::size_t r) { return r < m ? r : (r - m) / 2; };
    const std::size_t n = 4 * m;
    std::vector<Eigen::Triplet<double>> trip;
    trip.reserve(n * 8);
    for (std::size_t f = 0; f < nf; ++f) {
      const Eigen::Vector3d ai = Ainv.segment<3>(3 * static_cast<Eigen::Index>(f));
      for (std::size_t r1 : rows_of[f])
        for (std::size_t r2 : rows_of[f]) {
          const Eigen::Vector3d& g1 = *block(rows[r1], static_cast<int>(f));
          const Eigen::Vector3d& g2 = *block(rows[r2], static_cast<int>(f));
          trip.emplace_back(static_cast<int>(r1), static_cast<int>(r2),
                            g1.cwiseProduct(ai).dot(g2) * scale[contact_of(r2)]);
        }
    }
    for (std::size_t k = 0; k < m; ++k) {
      const int a = static_cast<int>(3 * m + k);
      trip.emplace_back(static_cast<int>(m + 2 * k), a, 1.0);       // E
      trip.emplace_back(static_cast<int>(m + 2 * k + 1), a, 1.0);
      trip.emplace_back(a, static_cast<int>(k), opt.friction);        // mu
      trip.emplace_back(a, static_cast<int>(m + 2 * k), -1.0);       // -E^T
      trip.emplace_back(a, static_cast<int>(m + 2 * k + 1), -1.0);
    }
    lcp::SparseMatrix S(static_cast<int>(n), static_cast<int>(n));
    S.setFromTriplets(trip.begin(), trip.end());  // duplicates (same floe twice) are summed
    if (n <= opt.dense_max) problem.M = lcp::DenseMatrix(S);
    else problem.M = std::move(S);

    // Pass 0: compression LCP on W^-, then Poisson's decompression. Poisson's
    // law applied to several contacts at once can leave a contact that was
    // separating before the collision approaching after it; pass 1 then
    // solves a compression LCP (restitution 0) from W^+ so that no contact
    // ends approaching.
    Eigen::VectorXd total = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(3 * m));  // impulses applied
    for (int pass = 0; pass < 2; ++pass) {
      const double e = pass == 0 ? opt.restitution : 0.0;
      if (pass == 1 && !(fill_q() < -opt.approach_tolerance)) break;  // pass 0 uses the q above
      const lcp::FallbackResult res = lcp::solve_with_fallbacks(problem, opt.solver);
      ++stats.lcps;
      stats.contacts += static_cast<long>(m);
      stats.pivots += res.result.pivots;
      stats.largest = std::max(stats.largest, static_cast<long>(n));
      stats.total_size += static_cast<long>(n);
      if (res.attempts.size() > 1) ++stats.fallbacks;
      if (res.flagged) ++stats.flagged;
      if (!res.solved()) {
        ++stats.failures;
        break;  // leave these velocities as they are: counted and reported
      }
      // W += (1 + e) A^-1 G^T z.
      Eigen::VectorXd z = (1.0 + e) * res.result.z.head(static_cast<Eigen::Index>(3 * m));
      for (std::size_t r = 0; r < 3 * m; ++r) z[static_cast<Eigen::Index>(r)] *= scale[contact_of(r)];
      total += z;
      Eigen::VectorXd p = Eigen::VectorXd::Zero(3 * static_cast<Eigen::Index>(nf));
      for (std::size_t r = 0; r < 3 * m; ++r) {
        const double zr = z[static_cast<Eigen::Index>(r)];
        if (zr == 0.0) continue;
        if (rows[r].fa >= 0) p.segment<3>(3 * rows[r].fa) += zr * rows[r].ga;
        if (rows[r].fb >= 0) p.segment<3>(3 * rows[r].fb) += zr * rows[r].gb;
      }
      W += Ainv.cwiseProduct(p);
    }
    for (std::size_t f = 0; f < nf; ++f) {
      FloeState& s = floes.state[global[f]];
      s.vx = W[3 * static_cast<Eigen::Index>(f)];
      s.vy = W[3 * static_cast<Eigen::Index>(f) + 1];
      s.yaw_rate = W[3 * static_cast<Eigen::Index>(f) + 2];
    }
    for (std::size_t k = 0; k < m; ++k) {
      ContactImpulse& ci = impulses[list[k]];
      ci.normal = total[static_cast<Eigen::Index>(k)];
      ci.tangential = total[static_cast<Eigen::Index>(m + 2 * k)] - total[static_cast<Eigen::Index>(m + 2 * k + 1)];
      const ContactPoint& c = contacts[list[k]];
      ci.vector = ci.normal * c.normal + ci.tangential * Vec2{-c.normal.y(), c.normal.x()};
      ci.point = c.point;
    }
  }
  return impulses;
}

}  // namespace floesim::contact
