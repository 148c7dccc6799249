#pragma once
// The floe–sea penalty laws (MODEL.md §4; Destuynder & Fabre, seed 000 eq. 12,
// 13 and 17) as functions of the penetration delta = eta - z_b (m) and its
// rate delta' (m/s), per unit area:
//
//   strong  p = kappa [delta]^+,                kappa = K rho_w g
//           (a spring: conserves energy; as K -> inf, an elastic contact, e -> 1)
//   weak    Lambda = c [delta]^+, p = dLambda/dt = c delta' 1[delta > 0],
//           c = K rho_w sqrt(g d)
//           (the penalty on the first integral in time, seed eq. 17: a damper
//           while in contact; as K -> inf it absorbs the impact, e -> 0. Lambda
//           >= 0 always; p may pull while delta decreases, as in eq. 17)
//   blend   p = s strong + (1 - s) weak, s in [0, 1].
//
// The seed's model is dimensionless: eq. 13 penalises a time integral of
// delta, eq. 17 delta itself, with the same 1/epsilon. Our weak coefficient c
// uses the time scale sqrt(d / g) of the floe's heave (d = its draft), so that
// one K serves both laws: on a floe of draft d the damping ratio of the blend
// is zeta = (1 - s) sqrt(K / s) / 2, independent of d.
//
// Calibration (MODEL.md §4): a rigid mass on a spring (natural frequency
// sqrt(g / d), at rest a height d above the obstacle, released from 2 d) hits
// the penalised obstacle; e = exit speed / entry speed. The map s -> e at a
// given K is tabulated, increasing in s (s = 1 gives e = 1: the strong law
// conserves energy), and inverted for a requested e.

#include <vector>

namespace floesim {

struct PenaltyLawParams {
  double stiffness = 1000.0;  // K
  double strong_share = 1.0;  // s
};

// The law's force held over one step of the implicit integrator (coupling/
// floe_sea.hpp) on a piece whose penetration goes from d0 to d1, and its
// derivative in d1 (>= 0): the spring's discrete gradient of c / 2 [d]^+^2,
// c ([d1]^+^2 - [d0]^+^2) / (2 (d1 - d0)), so that f (d1 - d0) is exactly
// the spring energy's change; plus the damper's impulse over the step,
// cd ([d1]^+ - [d0]^+) with cd = (damper coefficient) / h (Lambda = c [delta]^+,
// seed eq. 17), which only absorbs. The cases avoid the quotient's
// cancellation where both ends are in the water.
struct StepForce {
  double f = 0.0, df = 0.0;
};
StepForce step_force(double spring, double damper_per_step, double d0, double d1);

// Restitution of the obstacle problem above for a share s and stiffness K
// (the contact phase in closed form: the continuous law).
double obstacle_restitution(double strong_share, double stiffness);

// The same obstacle problem stepped as the implicit floe–sea integrator steps
// a floe ([coupling] integrator = "implicit", coupling/floe_sea.hpp), with
// the step `dt` in units of sqrt(d / g): the implicit midpoint rule with the
// spring's discrete gradient and the damper's impulse over the step,
// c ([delta1]^+ - [delta0]^+) (the seed's eq. 17 on the step). Entering at
// the surface with the speed of the continuous problem, e is the speed the
// mass would have on returning to the surface, from its energy once it is
// out of contact. Monotone in s only down to where the contact lasts about
// a step (calibrate_blend keeps that branch).
double stepped_obstacle_restitution(double strong_share, double stiffness, double dt);

struct BlendCalibration {
  double stiffness = 0.0;
  double step = 0.0;  // the stepped problem's dt (units of sqrt(d / g)); 0: the continuous law
  std::vector<double> share, restitution;  // increasing in both
  // The share s that gives restitution e (monotone cubic interpolation).
  double share_for(double e) const;
};
// The table s -> e of the continuous law (step = 0) or of the stepped one
// (its monotone branch from s = 1 down: lower e are out of reach at that step,
// and share_for gives the branch's end).
BlendCalibration calibrate_blend(double stiffness, int points = 61, double step = 0.0);

}  // namespace floesim
