#pragma once
// The response of an elastic floe (elastic.hpp) to point loads: static forces
// and impulses (percussions), with the floe's rigid motion removed (inertia
// relief).
//
// Statics. The load is made self-equilibrated, f_r = relieve(f) (the rigid
// acceleration it would give is balanced by the floe's own inertia), and
//   (K + eps M) u = f_r,   eps = 1e-6 (c / D)^2
// with one step of iterative refinement. The small shift eps M makes the
// matrix positive definite (K alone has the three rigid modes in its kernel)
// without touching the elastic solution: in the modal basis each elastic
// mode is scaled by lambda / (lambda + eps), lambda >= ~(c / D)^2, i.e. by
// 1 - O(1e-6), and the refinement step squares that error; rigid components
// stay zero because Phi^T f_r = 0. c is the plate wave speed, D the diameter.
//
// Dynamics (impulses). An impulse J is applied as the force
//   F(t) = J pi / (2 tau) sin(pi t / tau),  0 <= t <= tau  (integral J),
// tau = `duration`. With Phi the rigid modes, u = Phi q + w, Phi^T M w = 0,
// the elastic part obeys exactly (linear theory)
//   M w'' + C w' + K w = relieve(f(t)),
// so inertia relief is not an approximation here. Integrated by Newmark's
// average acceleration (trapezoidal rule: unconditionally stable, no
// numerical damping, second order) with the force averaged over each step
// (so the impulse delivered is exactly J however coarse the step), and light
// stiffness-proportional damping C = beta K: the modal damping ratio is
// zeta(omega) = beta omega / 2, and beta = 2 zeta_h / omega_h sets it to
// zeta_h = `damping` (5% by default) at the mesh's shortest wave,
// omega_h = pi c / s (s the mesh size); it falls in proportion to the
// frequency below that (0.3% for a 10 ms pulse, 0.1% at a 100 m floe's first
// modes with s = 2 m). It calms the mesh-scale ringing that the undamped
// trapezoidal rule keeps. One matrix, (1 + 2 beta / dt) K + 4 M / dt^2, is
// factorised once per floe and reused at every step and every percussion.
// Step dt = min(tau / 20, D / (4 c)); the response is followed until
// 2 tau + 1.5 D / c (the pulse, then its crossing of the floe and the
// reflection from the far side), at most `max_steps` steps (dt grows if
// needed).
//
// Static and dynamic loads superpose (linear): u(t) = u_static + u_dyn(t).

#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <span>
#include <vector>

#include "contact/fracture/elastic.hpp"
#include "contact/fracture/spd_factor.hpp"

namespace floesim::fracture {

struct PointLoad {
  Vec2 point = Vec2::Zero();  // m, in the mesh's frame
  Vec2 value = Vec2::Zero();  // N (force) or N s (impulse)
  bool impulse = false;
};

struct ResponseOptions {
  double duration = 0.01;     // s, tau
  double load_radius = 2.0;   // m, loads are spread over the nodes this close
  double damping = 0.05;      // modal damping ratio at the mesh's shortest wave (omega = pi c / s)
  int steps_per_pulse = 20;
  int max_steps = 800;
};

// The floe at one instant of its response.
struct Snapshot {
  double time = 0.0;             // s from the start of the loading
  double max_principal = -std::numeric_limits<double>::infinity();  // Pa, largest sigma_1 over nodes
  std::size_t node = 0;          // where it is
  double angle = 0.0;            // rad, direction of that sigma_1 from +x
  double strain_energy = 0.0;    // J
  Eigen::VectorXd u;             // m, elastic displacement
};

struct Response {
  Snapshot peak_stress;   // the instant of the largest sigma_1
  Snapshot peak_energy;   // the instant of the largest strain energy
  int steps = 0;          // dynamic steps run (0: static loads only)
  double dt = 0.0;        // s
  // The time loop stopped after `steps` because sigma_1 could no longer reach
  // the level asked (respond's `level`): the peaks are those of the steps run,
  // and `later_bound` (Pa) bounds sigma_1 at every later step.
  bool cut_short = false;
  double later_bound = std::numeric_limits<double>::infinity();
};

// Called at every instant with the time and the elastic displacement.
using Observer = std::function<void(double t, const Eigen::VectorXd& u)>;

class Responder {
public:
  Responder(const ElasticModel& model, const ResponseOptions& options);
  ~Responder();

  const ElasticModel& model() const { return model_; }
  const ResponseOptions& options() const { return options_; }
  double time_step() const { return dt_; }
  double end_time() const { return t_end_; }
  double shift() const { return eps_; }
  // Wall time (s) so far in assembling K and factorising (both factors, on their first use).
  double factor_seconds() const { return factor_seconds_; }

  // Nodal loads (N or N s per dof) of a set of point loads of one kind.
  Eigen::VectorXd nodal_loads(std::span<const PointLoad> loads, bool impulses) const;
  // Static solution for a nodal load (made self-equilibrated first).
  Eigen::VectorXd solve_static(const Eigen::VectorXd& f);
  // The factor of K + eps M (built on first use), e.g. to copy and downdate.
  const SpdFactor& static_factor();

  // The response to the loads over [0, end_time()]. With a finite `level`
  // (Pa), the time loop stops as soon as neither the steps run nor any later
  // one can have sigma_1 >= level (Response::cut_short; the energy bound
  // below). Whether sigma_1 reaches the level is then decided exactly as by
  // the whole loop; the peaks reported are those of the steps run.
  //
  // The energy bound. Newmark's average acceleration with C = beta K keeps
  // M a_n + C v_n + K u_n = f_n at every step and u_{n+1} - u_n = dt v_bar,
  // v_{n+1} - v_n = dt a_bar (bars: means of the two ends), so the energy
  // E_n = (v_n^T M v_n + u_n^T K u_n) / 2 of the elastic part changes by
  //   E_{n+1} - E_n = dt (v_bar^T f_bar - beta v_bar^T K v_bar) <= dt v_bar^T f_bar
  // exactly (the trapezoidal rule conserves quadratic invariants of linear
  // systems; damping only removes energy). With f_n = (phi_n / dt) j_r
  // (phi_n the pulse's fraction delivered in step n, j_r the relieved
  // nodal impulses) and |M^1/2 v_bar| <= (sqrt(2 E_n) + sqrt(2 E_{n+1})) / 2,
  //   sqrt(E_{n+1}) - sqrt(E_n) <= (phi_n + phi_{n+1}) / 2 sqrt(U),
  //   U = j_r^T M^-1 j_r / 2,
  // hence for every later step m > n
  //   sqrt(E_m) <= sqrt(E_n) + sqrt(U) (phi_n / 2 + sum_{k > n} phi_k).
  // Once the pulse has passed, E_m <= E_n: the energy it left is all later
  // steps can have. The strain energy of u_m is at most E_m, and a linear
  // triangle of area A whose largest principal stress is s holds at least
  // A h s^2 (1 - nu^2) / (2 E) (the least of (s^2 + s2^2 - 2 nu s s2) / (2 E)
  // over the other principal stress s2, at s2 = nu s). The nodal stress of
  // node n is the mean of its triangles' stresses weighted by A_t / A_n
  // (A_n = sum of the A_t around n, its patch); sigma_1 is convex, so by
  // Jensen's inequality
  //   sigma_1(n) <= sum (A_t / A_n) sigma_1(t) <= sqrt(sum (A_t / A_n) sigma_1(t)^2)
  //              <= sqrt(2 E E_m / ((1 - nu^2) h A_n)),
  // and no node has sigma_1 above that with A_n the smallest patch of the
  // mesh (at least the smallest triangle, usually several times it).
  // sigma_1 of a sum is at most the sum of the sigma_1 (subadditive), so the
  // static forces' largest nodal sigma_1 plus that bounds every later step.
  // The loop stops when that bound, raised by 1e-6 of itself (round-off), and
  // the largest sigma_1 so far are below the level.
  Response respond(std::span<const PointLoad> loads, const Observer& observe = {},
                   double level = -std::numeric_limits<double>::infinity());

  // An upper bound of the largest sigma_1 that respond(loads) finds, at the
  // cost of a static solve (none without static forces) instead of its time
  // loop: a load case whose bound is below the strength cannot initiate by
  // the stress criterion, so skipping it changes nothing. It is the energy
  // bound of respond() taken before the first step (E_0 = 0, the whole
  // pulse to come):
  //   bound = max over nodes of sigma_1(u_static) + sqrt(2 E U / ((1 - nu^2) h A_patch)),
  //   U = j_r^T M^-1 j_r / 2,  j_r = relieve(nodal impulses)
  // (U is also the energy the elastic modes would take from the impulses
  // given at once: each mode, driven by a pulse of one sign, never holds more).
  double stress_bound(std::span<const PointLoad> loads);

private:
  const ElasticModel& model_;
  ResponseOptions options_;
  double dt_ = 0.0, t_end_ = 0.0, beta_ = 0.0, eps_ = 0.0;
  double min_patch_ = 0.0;  // m^2, the smallest area of the triangles around a node (stress_bound)
  int steps_ = 0;
  double factor_seconds_ = 0.0;
  // Pa: the largest nodal sigma_1 the mesh can have with strain energy `energy` (J).
  double stress_of_energy(double energy) const;
  std::unique_ptr<SpdFactor> static_, dynamic_;
};

}  // namespace floesim::fracture
