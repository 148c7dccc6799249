#include "contact/lcp/lemke.hpp"

#include "contact/lcp/basis_repair.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "contact/lcp/lemke_basis.hpp"
#include "core/error.hpp"

namespace floesim::lcp {

namespace {

using detail::LemkeBasis;

// Keeps the candidates whose key is minimal within the relative tie tolerance:
// key_i - min <= tol * max(|key_i|, |min|).
void keep_minimal(std::vector<Index>& rows, const std::vector<double>& keys, double tol) {
  const double lo = *std::min_element(keys.begin(), keys.end());
  std::size_t kept = 0;
  for (std::size_t c = 0; c < rows.size(); ++c)
    if (keys[c] - lo <= tol * std::max(std::abs(keys[c]), std::abs(lo))) rows[kept++] = rows[c];
  rows.resize(kept);
}

class Lemke {
public:
  Lemke(const Lcp& lcp, const LemkeOptions& options, LemkeStats& stats)
      : lcp_(lcp), opt_(options), stats_(stats), n_(lcp.size()), M_(sparse_copy(lcp)),
        d_(options.covering.size() ? options.covering : Vector::Ones(n_)) {
    if (opt_.start) {
      // d = B 1 for the start basis B: columns e_i (w_i basic) and -M e_j (z_j basic).
      const std::vector<std::uint8_t>& s = *opt_.start;
      for (Index i = 0; i < n_; ++i) d_(i) = s[static_cast<std::size_t>(i)] ? 0.0 : 1.0;
      for (Index j = 0; j < n_; ++j)
        if (s[static_cast<std::size_t>(j)])
          for (SparseMatrix::InnerIterator it(M_, j); it; ++it) d_(it.index()) -= it.value();
    }
  }

  Result run();

private:
  detail::FactorPolicy factor_policy() const;
  Index first_leaving() const;
  Index ratio_test(const Vector& u, double x_zero);
  Index lexicographic(std::vector<Index> tied, const Vector& u);
  Result finish_solved(LemkeBasis& basis);
  Vector read_z(const LemkeBasis& basis, const Vector& x) const;

  const Lcp& lcp_;
  const LemkeOptions& opt_;
  LemkeStats& stats_;
  Index n_;
  SparseMatrix M_;
  Vector d_;
  LemkeBasis* basis_ = nullptr;
  Vector x_;  // basic values x_B = B^-1 q, by position
  // The ratio test's candidates (positions) and their ratios, kept between
  // pivots so that a pivot allocates nothing.
  std::vector<Index> rows_;
  std::vector<double> ratios_;
};

detail::FactorPolicy Lemke::factor_policy() const {
  switch (opt_.factorization) {
    case Factorization::dense: return {std::numeric_limits<Index>::max(), 0.0, opt_.sparse_lu};
    case Factorization::sparse: return {0, 1.0, opt_.sparse_lu};
    case Factorization::automatic: break;
  }
  return {opt_.sparse_min_size, opt_.sparse_max_density, opt_.sparse_lu};
}

// z0 enters at max_i (-q_i / d_i); the row attaining it leaves. Ties: with q
// perturbed to q + (eps, ..., eps^n), -(q_i + eps^i) / d_i is largest for the
// largest tied index.
Index Lemke::first_leaving() const {
  std::vector<Index> rows(static_cast<std::size_t>(n_));
  std::vector<double> keys(static_cast<std::size_t>(n_));
  for (Index i = 0; i < n_; ++i) {
    rows[i] = i;
    keys[i] = lcp_.q(i) / d_(i);  // minimal q_i / d_i == maximal -q_i / d_i
  }
  keep_minimal(rows, keys, opt_.tie_tolerance);
  return rows.back();
}

// Minimum-ratio test on the entering column u = B^-1 a: returns the leaving
// position, or -1 for a ray. x_zero: basic values up to it count as 0.
Index Lemke::ratio_test(const Vector& u, double x_zero) {
  const double umax = u.cwiseAbs().maxCoeff();
  if (!(umax > 0.0) || !std::isfinite(umax)) return -1;
  const double pivot_min = opt_.pivot_tolerance * umax;
  std::vector<Index>& rows = rows_;
  std::vector<double>& ratios = ratios_;
  rows.clear();
  ratios.clear();
  // A candidate whose ratio t exceeds the smallest so far, m, beyond the tie
  // tolerance can never tie with the final minimum lo <= m: the ratios are >= 0,
  // so t - lo >= t - m and max(t, lo) <= max(t, m) (in floating point too, each
  // operation being monotone). It is dropped as it comes; keep_minimal then
  // sorts out the few left and keeps the same rows, in the same order, as it
  // would from every candidate.
  const double tol = opt_.tie_tolerance;
  double smallest = std::numeric_limits<double>::infinity();
  for (Index p = 0; p < n_; ++p) {
    const double up = u(p);
    if (up <= pivot_min) continue;
    const double x = x_(p) <= x_zero ? 0.0 : x_(p);  // degenerate rows are exactly 0
    const double t = x / up;
    if (t - smallest > tol * std::max(std::abs(t), std::abs(smallest))) continue;
    smallest = std::min(smallest, t);
    rows.push_back(p);
    ratios.push_back(t);
  }
  if (rows.empty()) return -1;
  keep_minimal(rows, ratios, opt_.tie_tolerance);
  if (rows.size() == 1) return rows.front();
  const Index z0_pos = basis_->position_of(basis_->z0_var());
  if (std::find(rows.begin(), rows.end(), z0_pos) != rows.end()) return z0_pos;
  ++stats_.tie_breaks;
  return lexicographic(rows, u);
}

// Lexicographic rule on the tied positions: compare (B^-1)_{p, j} / u_p for
// j = 0, 1, ... keeping the minimal ones until a single position remains.
// Entries of B^-1 come from one transposed solve per tied row (few ties: the
// usual case) or from one solve per column consulted (many ties); entries below
// zero_tolerance times their row's (column's) largest count as 0. Column
// solves go on only while they are fewer than the rows still tied: then the
// tied rows are solved for instead, so a tie-break costs at most about twice
// the cheaper of the two ways. (In a jam's degenerate LCPs 70 to 90 rows
// stayed tied for 300 to 550 columns: data/lcp/jam/jam500_n2396.)
Index Lemke::lexicographic(std::vector<Index> tied, const Vector& u) {
  constexpr std::size_t kMaxRowSolves = 8;
  std::vector<std::pair<Index, Vector>> rows;  // (position p, row p of B^-1)
  auto row_of = [&](Index p) -> const Vector& {
    return std::find_if(rows.begin(), rows.end(), [p](const auto& r) { return r.first == p; })
        ->second;
  };
  auto clean = [&](Vector& v) {
    const double zero = opt_.zero_tolerance * v.cwiseAbs().maxCoeff();
    v = (v.array().abs() <= zero).select(0.0, v);
  };
  Vector y(n_);
  std::vector<double> keys;
  std::size_t column_solves = 0;
  for (Index j = 0; j < n_ && tied.size() > 1; ++j) {
    const Index p = basis_->position_of(basis_->w_var(j));
    if (p >= 0) {
      // B^-1 e_j = e_p: row p has 1 / u_p > 0 there, the others 0.
      tied.erase(std::remove(tied.begin(), tied.end(), p), tied.end());
      continue;
    }
    if (rows.empty() && (tied.size() <= kMaxRowSolves || tied.size() <= column_solves)) {
      for (Index t : tied) {
        y.setZero();
        y(t) = 1.0;
        basis_->solve_transposed(y);
        clean(y);
        rows.emplace_back(t, y);
      }
    }
    keys.clear();
    if (!rows.empty()) {
      for (Index t : tied) keys.push_back(row_of(t)(j) / u(t));
    } else {
      y.setZero();
      y(j) = 1.0;
      basis_->solve(y);
      ++column_solves;
      clean(y);
      for (Index t : tied) keys.push_back(y(t) / u(t));
    }
    keep_minimal(tied, keys, opt_.tie_tolerance);
  }
  // Ties that survive every column (only possible within the tolerances): the
  // largest pivot is the stablest.
  return *std::max_element(tied.begin(), tied.end(),
                           [&](Index a, Index b) { return u(a) < u(b); });
}

// z0 has left: the basis is complementary. Recompute x_B = B^-1 q from a fresh
// factorisation with one step of iterative refinement, read off z.
Result Lemke::finish_solved(LemkeBasis& basis) {
  Result result;
  result.status = Status::solved;
  if (!basis.refactor()) result.status = Status::failed;
  Vector x = lcp_.q;
  basis.solve(x);
  Vector r;
  basis.multiply(x, r);
  r = lcp_.q - r;
  basis.solve(r);
  x += r;
  result.z = read_z(basis, x);
  result.z_basic.assign(static_cast<std::size_t>(n_), 0);
  for (Index j = 0; j < n_; ++j) result.z_basic[static_cast<std::size_t>(j)] = basis.position_of(basis.z_var(j)) >= 0;
  return result;
}

// z from basic values x (by position): z_j = x at z_j's position, 0 if non-basic;
// rounding-level negatives are cut to 0.
Vector Lemke::read_z(const LemkeBasis& basis, const Vector& x) const {
  Vector z = Vector::Zero(n_);
  for (Index j = 0; j < n_; ++j) {
    const Index p = basis.position_of(basis.z_var(j));
    if (p >= 0) z(j) = std::max(x(p), 0.0);
  }
  return z;
}

Result Lemke::run() {
  Result result;
  result.z = Vector::Zero(n_);
  if ((lcp_.q.array() >= 0.0).all()) {
    result.status = Status::solved;
    return result;
  }
  const long max_pivots = opt_.max_pivots > 0 ? opt_.max_pivots : 50 * (n_ + 1) + 1000;
  LemkeBasis basis(M_, d_, factor_policy(), std::max(1, opt_.refactor_interval));
  basis_ = &basis;
  stats_.refactorisations = basis.refactorisations();

  // First pivot: z0 enters at row r; with B = I, u = B^-1 (-d) = -d.
  Index r = -1;
  Vector u = -d_;
  x_ = lcp_.q;
  if (opt_.start) {
    // Warm start: B is the given basis, B^-1 (-d) = -1; z0 enters where B^-1 q is least.
    if (!basis.start_from(*opt_.start)) {
      result.status = Status::failed;
      return result;
    }
    basis.solve(x_);
    u = -Vector::Ones(n_);
    x_.minCoeff(&r);
    if (x_(r) >= 0.0) {
      result = finish_solved(basis);
      return result;
    }
  } else {
    r = first_leaving();
  }
  int entering = basis.complement(basis.variable_at(r));
  bool ok = basis.replace(r, basis.z0_var(), u);
  const double theta0 = x_(r) / u(r);
  x_ -= theta0 * u;
  x_(r) = theta0;
  long pivots = 1;

  rows_.reserve(static_cast<std::size_t>(n_));
  ratios_.reserve(static_cast<std::size_t>(n_));
  while (ok) {
    if (pivots >= max_pivots) {
      result.status = Status::pivot_limit;
      break;
    }
    basis.column(entering, u);
    basis.solve(u);
    const double x_zero = opt_.zero_tolerance * x_.cwiseAbs().maxCoeff();
    const Index p = ratio_test(u, x_zero);
    if (p < 0) {
      // A degenerate end: z0 is still basic but (nearly) at zero, so the
      // almost-complementary point reached, with z0 dropped, solves the LCP
      // (w = M z + q + d z0). Rounding in the lexicographic ties can leave z0
      // in the basis at value ~0 on the Stewart–Trinkle LCPs of jammed packs.
      // Accepted only if that point's residual (lcp.hpp) is within
      // ray_accept_residual.
      result.status = Status::ray;
      result.z = read_z(basis, x_);  // the point reached (z0 > 0 there unless accepted below)
      if (basis.position_of(basis.z0_var()) >= 0 && opt_.ray_accept_residual > 0.0) {
        // The point as reached, and refined from a fresh factorisation (which
        // may fail on a nearly singular basis): the better one is kept.
        Result end;
        end.z = result.z;
        double best = residual(lcp_, end.z);
        Result refined = finish_solved(basis);
        if (refined.status == Status::solved) {
          const double refined_residual = residual(lcp_, refined.z);
          if (refined_residual < best) {
            best = refined_residual;
            end.z = refined.z;
          }
        }
        if (best <= opt_.ray_accept_residual) {
          end.status = Status::solved;
          result = end;
        }
      }
      break;
    }
    const int leaving = basis.variable_at(p);
    // x <- E^-1 x: the entering variable takes the ratio, the others move along u.
    const double theta = x_(p) <= x_zero ? 0.0 : x_(p) / u(p);
    x_ -= theta * u;
    x_(p) = theta;
    ok = basis.replace(p, entering, u);
    ++pivots;
    if (ok && basis.refactorisations() > stats_.refactorisations) {
      // Fresh factorisation: recompute the basic values to shed drift.
      stats_.refactorisations = basis.refactorisations();
      x_ = lcp_.q;
      basis.solve(x_);
    }
    if (leaving == basis.z0_var()) {
      result = finish_solved(basis);
      break;
    }
    entering = basis.complement(leaving);
  }
  if (!ok) result.status = Status::failed;
  if (result.status != Status::solved && result.status != Status::ray) {
    // Report the point reached (z0 > 0 there, so it does not solve the LCP).
    result.z = read_z(basis, x_);
  }
  result.pivots = pivots;
  stats_.solves = basis.solves();
  stats_.refactorisations = basis.refactorisations();
  stats_.sparse_refactorisations = basis.sparse_refactorisations();
  return result;
}

}  // namespace

Result solve_lemke(const Lcp& lcp, const LemkeOptions& options, LemkeStats* stats) {
  check_lcp(lcp);
  if (options.covering.size() != 0 &&
      (options.covering.size() != lcp.size() || !(options.covering.array() > 0.0).all() ||
       !options.covering.allFinite()))
    throw RunError("Lemke: the covering vector must have n positive finite entries");
  if (options.start && options.start->size() != static_cast<std::size_t>(lcp.size()))
    throw RunError("Lemke: the start basis must have n entries");
  LemkeStats local;
  if (stats) *stats = {};
  Result result = Lemke(lcp, options, stats ? *stats : local).run();
  if (options.start && options.repair_start.rounds > 0 && result.status == Status::failed && result.pivots == 0) {
    // The start basis was singular (basis_repair.hpp): start again from its repair.
    const std::vector<std::uint8_t> repaired = repair_basis(sparse_copy(lcp), *options.start, options.repair_start);
    if (repaired != *options.start) {
      LemkeOptions again = options;
      again.start = &repaired;
      result = Lemke(lcp, again, stats ? *stats : local).run();
    }
  }
  finish(lcp, result);
  return result;
}

}  // namespace floesim::lcp
