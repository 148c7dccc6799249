#pragma once
// The linear complementarity problem as plain data, and what every LCP solver
// returns. Solvers (Lemke in lemke.hpp, projected Gauss–Seidel in pgs.hpp, the
// fallback chain in fallback.hpp) are functions of an `Lcp` and typed options.
//
//   LCP(M, q):  find z in R^n with
//                 z >= 0,   w = M z + q >= 0,   z . w = 0     (componentwise).
//
// Nothing here knows about floes: the contact layer assembles M and q.

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <cstdint>
#include <string_view>
#include <vector>
#include <variant>

namespace floesim::lcp {

using Index = Eigen::Index;
using Vector = Eigen::VectorXd;
using DenseMatrix = Eigen::MatrixXd;
// Compressed sparse columns; the solvers read M by columns.
using SparseMatrix = Eigen::SparseMatrix<double, Eigen::ColMajor, int>;

// M is stored dense or sparse, whichever the caller has; the solvers accept both.
struct Lcp {
  std::variant<DenseMatrix, SparseMatrix> M;
  Vector q;

  Index size() const { return q.size(); }
  bool is_sparse() const { return std::holds_alternative<SparseMatrix>(M); }
};

// w = M z + q.
Vector affine_map(const Lcp& lcp, const Vector& z);

// M in compressed sparse columns (a copy; exact zeros of a dense M are dropped).
SparseMatrix sparse_copy(const Lcp& lcp);

// Number of stored non-zeros of M (for a dense M: the entries that are not 0).
Index nonzeros(const Lcp& lcp);

// Checks that M is n x n with n = q.size() >= 1 and every entry finite; throws
// floesim::RunError naming what is wrong. Every solver calls it first. An LCP
// read from a file was validated when it was read (siconos_io.hpp: InputError);
// one that fails here was built during a run (a NaN velocity reaching the
// collide phase), which is a run error: the run stops and its file says so.
void check_lcp(const Lcp& lcp);

// Checks a solver's warm start against an LCP of n unknowns: `flags` (one
// per unknown, or null) and `point` (n entries, or empty); throws
// floesim::RunError naming `solver` if a size differs.
void check_start(std::string_view solver, Index n, const std::vector<std::uint8_t>* flags, const Vector& point);

// The unknowns i with flags[i] set, ascending, into `list`, and each one's
// place in it into `position` (-1 for the others): the index maps of a
// principal block M_AA. Returns the block's size.
Index select_unknowns(const std::vector<std::uint8_t>& flags, std::vector<Index>& list, std::vector<Index>& position);

enum class Status {
  solved,       // z, w satisfy the LCP (see the residual for how well)
  ray,          // Lemke ended on a secondary ray: no solution found this way
  pivot_limit,  // the pivot (or iteration) limit was reached first
  failed,       // numerical breakdown (singular basis, non-finite values, ...)
};
std::string_view to_string(Status status);

struct Result {
  Status status = Status::failed;
  Vector z;                 // the candidate solution (z >= 0 by construction)
  Vector w;                 // M z + q, recomputed from M (never the solver's own copy)
  long pivots = 0;          // Lemke: pivots, counting the one where z0 enters
  long iterations = 0;      // iterative solvers: sweeps
  double residual = 0.0;    // residual(lcp, z), see below
  // Lemke: which z_j were basic at the end (a complementary basis when
  // solved; empty otherwise and for iterative solvers), for warm starts.
  std::vector<std::uint8_t> z_basic;
};

// The scaled complementarity residual, the same for every solver:
//
//   residual(z) = || min(z, M z + q) ||_2 / (1 + || q ||_2),
//
// the componentwise minimum being the "natural map" of the LCP: it is zero
// exactly when z >= 0, w >= 0 and z_i w_i = 0 for every i, and it measures the
// distance to a solution for a well-conditioned M. Non-finite input gives +inf.
double residual(const Lcp& lcp, const Vector& z);

// Fills result.w and result.residual from result.z.
void finish(const Lcp& lcp, Result& result);

}  // namespace floesim::lcp
