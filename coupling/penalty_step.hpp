#pragma once
// The equation of the implicit floe–sea step on the area pieces, and its
// solver (coupling/floe_sea.hpp, "Implicit step"; docs/coupling.md, "The
// implicit step").
//
// Problem. Over a step of length h the floes' vertical DOFs x_i = (zeta, a)
// (heave, bottom slopes) and the sea's modes take one step of the implicit
// midpoint rule under the penalty forces f_k of the area pieces k, held over
// the step. Eliminating x1 and the sea leaves one equation for the pieces'
// penetrations d1 at t + h:
//     R(d1) = d1 - d_free + G f(d0, d1) = 0,
//     f_k = step_force(c_k, e_k, d0_k, d1_k)   (coupling/penalty_law.hpp:
//           the spring's discrete gradient c ([d1]^+^2 - [d0]^+^2) / (2 (d1 - d0))
//           plus the damper's impulse e ([d1]^+ - [d0]^+)),
//     G = G_sea + G_rigid,  G_rigid u = h^2 / 2 Phi_i M_i^-1 Phi_i^T u on body i's pieces,
// with Phi_i^T u = sum_k u_k (1, r_k) the resultant and moments of forces u
// on body i (r_k the lever of piece k), and G_sea u the sea's rise on the
// pieces under the pressure u / cell area held over h (fluid::Sea::
// midpoint_response, two FFTs), given as a function. Both parts are symmetric
// positive semi-definite, and f is non-decreasing in d1: R is the gradient of
// the convex 1/2 (d1 - d_free)^T G^-1 (d1 - d_free) + sum_k F_k(d1_k), F_k' = f_k
// (on G's range), so Newton's method with a backtracking line search on |R|
// converges.
//
// Newton step. (I + G F') s = -R, F' = diag(df_k / dd1) = S^2. With
// (I + S G S) w = -S R solved by preconditioned conjugate gradients (the
// operator is symmetric positive definite), s = -R - G S w (G S w summed
// along the iteration from the products it makes).
// Preconditioner, per body: (I + S (D + Phi C Phi^T) S)^-1, D = self_response
// (G_sea's diagonal: the sea's answer on a node to its own load), C = h^2 / 2
// M^-1, by Sherman–Morrison–Woodbury on the body's 1 to 3 DOFs:
//     P^-1 = E - E U (C^-1 + U^T E U)^-1 U^T E,  E = (I + S D S)^-1,  U = S Phi.
// It is exact for an isolated rigid body on a sea that answers only locally;
// the sea's non-local answer (its |k| operator at small omega h) is what the
// conjugate gradients iterate on.
//
// Inexact Newton. Far from the solution the linear system need not be
// solved tightly: Newton step k stops its conjugate gradients at the relative
// residual eta_k = max(cg_tolerance, min(forcing, forcing_safety * tolerance / |R_k|_inf))
// (Eisenstat & Walker 1996 choose eta by the residual's decrease; here by the
// distance to the tolerance). The conjugate gradients' residual is measured
// in the scaled norm of S R, which does not bound the Newton residual on
// barely wetted pieces; so once a step that aimed at the tolerance misses it,
// the steps that follow are solved to cg_tolerance; and an inexact step that
// keeps more than stall_ratio of the residual (the contact set changing, or
// the solve too loose) lowers the loosest tolerance by forcing_cut.
//
// Predictor. Newton starts from d1 = d_free - G f(d0, d0): the step with the
// forces at its start held over it (error O(h^3) where the contact is
// smooth), at the cost of one application of G.
//
// Reductions. Every dot product and the residual's largest |R_k| run over the
// pieces of the bodies listed, body by body: each body's terms summed in its
// pieces' order (plain doubles), then the bodies' partial sums exactly
// (ExactSum, core/exact_sum.hpp). A dot's bits thus depend neither on the
// order the bodies are listed or stored in, nor on the thread count, nor on
// how the bodies are split between processes, once the processes' ExactSums
// are merged (PenaltyStepReduction; docs/parallel.md, "The implicit step's
// serial rules (impl30)"). The conjugate gradients make two reductions an
// iteration: p . Ap, then r . z with r . r (the same r) in one call.

#include <array>
#include <cstdint>
#include <functional>
#include <span>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Cholesky>

#include "core/exact_sum.hpp"
#include "core/geometry.hpp"

namespace floesim {

// A rigid body's vertical inertia on (zeta, a): diag(M, J), J the 2 x 2 tilt
// inertia, with only the slopes it resists (`slopes` 0: heave only, 1: pitch,
// 2: pitch and roll); the DOFs it does not have have unit mass and zero
// inverse mass.
struct VerticalInertia {
  Eigen::Matrix3d mass = Eigen::Matrix3d::Identity();
  Eigen::Matrix3d inverse_mass = Eigen::Matrix3d::Zero();
  std::uint8_t slopes = 0;
};

struct PenaltyStepProblem {
  double step = 0.0;                         // h (s)
  // Body i's pieces are [offsets[i], offsets[i + 1]); only the bodies listed
  // in `bodies` take part (the others have no pieces, or are static, or are
  // another process's: PenaltyStepReduction), in any order. The solver
  // reads and writes every piece's entries but sums and checks only the
  // listed bodies' pieces; the sea response must give the listed bodies'
  // pieces their answer whatever the others' entries hold.
  std::span<const std::size_t> offsets;
  std::span<const std::uint32_t> bodies;
  std::span<const VerticalInertia> inertia;  // per body
  std::span<const Vec2> lever;               // per piece: r_k from the body's centroid (m)
  std::span<const double> spring;            // per piece: c_k (N/m)
  std::span<const double> damper;            // per piece: e_k, the damper per step (N/m)
  std::span<const double> start;             // per piece: d0_k, penetration at t (m)
  std::span<const double> free_end;          // per piece: d_free_k at t + h with no penalty (m)
  std::span<const double> guess;             // per piece: Newton's start without the predictor (empty: d0)
  double self_response = 0.0;                // G_sea's diagonal (m/N)
  double tolerance = 0.0;                    // on max_k |R_k| (m)
};

// out = G_sea u on the pieces (m), u the pieces' forces (N).
using SeaResponse = std::function<void(std::span<const double> u, std::span<double> out)>;

// The part of the solver's reductions over the bodies other processes hold
// (the header's "Reductions"). Empty members: this process holds every body
// (serial; no communication).
struct PenaltyStepReduction {
  // On entry each of `sums` holds this process's bodies' terms; on exit the
  // sum over every process's bodies, the same on every process (one
  // collective call: parallel::Communicator::sum adds the limbs as integers).
  std::function<void(std::span<ExactSum> sums)> sum;
  // The largest of every process's `value` (a max is exact in any order).
  std::function<double(double value)> max;
};

struct PenaltyStepOptions {
  int max_newton = 40;
  int max_cg = 500;                // per Newton step
  double cg_tolerance = 1e-10;     // the tightest relative residual of the conjugate gradients
  double forcing = 1e-2;           // the loosest (early Newton steps); cg_tolerance or below: always tight
  double forcing_safety = 0.1;     // aim the linear solve at this share of the tolerance
  double stall_ratio = 0.5;        // an inexact Newton step that keeps more of the residual (2-norm) ...
  double forcing_cut = 0.1;        // ... lowers the loosest tolerance by this factor
  bool predictor = true;           // start from d_free - G f(d0, d0) (else from d0)
  int threads = 1;                 // results do not depend on it
  PenaltyStepReduction reduction;  // across processes (empty: serial)
};

enum class PenaltyStepStatus { converged, newton_limit };

struct PenaltyStepResult {
  PenaltyStepStatus status = PenaltyStepStatus::converged;
  int newton = 0;           // Newton steps
  long cg = 0;              // conjugate-gradient iterations, all Newton steps
  long responses = 0;       // applications of G (each: one of the sea's)
  double residual = 0.0;    // max_k |R_k| at the end (m)
};

// Solves the problem; the penetrations at t + h and the forces that reach
// them stay in the solver until the next solve. Setup-free: the scratch is
// kept and reused between steps.
class PenaltyStepSolver {
public:
  PenaltyStepResult solve(const PenaltyStepProblem& problem, const SeaResponse& sea, const PenaltyStepOptions& options);
  std::span<const double> end() const { return d1_; }     // d1 (m)
  std::span<const double> force() const { return f_; }    // f(d0, d1) (N)

private:
  void apply_g(const PenaltyStepProblem& p, const SeaResponse& sea, std::span<const double> u, std::span<double> out,
               int threads);
  void residual(const PenaltyStepProblem& p, const SeaResponse& sea, std::span<const double> d,
                std::vector<double>& force, std::vector<double>& out, int threads);
  void factor_preconditioner(const PenaltyStepProblem& p, int threads);
  void precondition(const PenaltyStepProblem& p, std::span<const double> in, std::span<double> out, int threads) const;
  // Conjugate gradients on (I + S G S) w = b to the relative residual eta; returns the iterations.
  long conjugate_gradients(const PenaltyStepProblem& p, const SeaResponse& sea, double eta, int max_iterations,
                           int threads);
  // The header's "Reductions": {a . b, c . d} over the listed bodies' pieces
  // in one pass and one reduction call; dot: a . b alone. The count is the
  // caller's, not read from the spans: a process with no pieces has empty
  // ones and must make the same reduction call as the others.
  std::array<double, 2> dots(const PenaltyStepProblem& p, std::span<const double> a, std::span<const double> b,
                             std::span<const double> c, std::span<const double> d) {
    return reduce_dots(p, a, b, c, d, true);
  }
  double dot(const PenaltyStepProblem& p, std::span<const double> a, std::span<const double> b) {
    return reduce_dots(p, a, b, {}, {}, false)[0];
  }
  std::array<double, 2> reduce_dots(const PenaltyStepProblem& p, std::span<const double> a, std::span<const double> b,
                                    std::span<const double> c, std::span<const double> d, bool two);
  // max_k |x_k| over the listed bodies' pieces (every process's).
  double max_abs(const PenaltyStepProblem& p, std::span<const double> x) const;

  const PenaltyStepReduction* reduction_ = nullptr;  // the options' of the solve under way
  int threads_ = 1;
  std::vector<double> partial_;  // dots: per listed body, its partial sums

  long responses_ = 0;
  std::vector<double> d1_, f_, R_, sq_, einv_, w_, r_, z_, dir_, Ap_, tmp_, gdir_, gsw_, step_, trial_, ftrial_, Rtrial_;
  std::vector<Eigen::LDLT<Eigen::Matrix3d>> small_;
};

}  // namespace floesim
