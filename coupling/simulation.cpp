#include "coupling/simulation.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "core/error.hpp"

namespace floesim {

Simulation::Simulation(Scenario scenario) : scenario_(std::move(scenario)) {
  const Config& c = scenario_.config;
  drift_params_ = DriftParams{c.sea.rho, c.forcing.ocean_drag, c.forcing.air_density, c.forcing.air_drag,
                              c.forcing.coriolis};
  quadrature_ = build_footprint_quadrature(scenario_.floes);
}

double Simulation::step(double t_stop) {
  StepContext ctx;
  { PhaseTimer _(profile_, Phase::choose_dt); ctx = choose_dt(t_stop); }
  { PhaseTimer _(profile_, Phase::forcing);   sample_forcing(ctx); }
  { PhaseTimer _(profile_, Phase::drift);     drift(ctx); }
  { PhaseTimer _(profile_, Phase::check);     check_state(ctx); }
  // Land exactly on t_stop when the step was cut to reach it.
  t_ = ctx.dt == t_stop - ctx.t ? t_stop : ctx.t + ctx.dt;
  ++steps_;
  return ctx.dt;
}

StepContext Simulation::choose_dt(double t_stop) const {
  StepContext ctx;
  ctx.t = t_;
  const double remaining = t_stop - t_;
  ctx.dt = std::min(scenario_.config.run.dt_max, remaining);
  // Do not leave a sliver of a step before t_stop: split the rest evenly.
  if (remaining > ctx.dt && remaining < 1.5 * ctx.dt) ctx.dt = 0.5 * remaining;
  if (!(ctx.dt > 0.0)) throw RunError("step requested with no time left (t = " + std::to_string(t_) + ")");
  return ctx;
}

void Simulation::sample_forcing(StepContext& ctx) const {
  // Forcing is held over the step at its value at mid-step (second-order
  // accurate for a smooth series).
  ctx.forcing = scenario_.forcing.at(ctx.t + 0.5 * ctx.dt);
}

void Simulation::drift(const StepContext& ctx) {
  const Vec2 current{ctx.forcing.current[0], ctx.forcing.current[1]};
  const Vec2 wind{ctx.forcing.wind[0], ctx.forcing.wind[1]};
  drift_step(scenario_.floes, quadrature_, drift_params_, current, wind, ctx.dt, 0, scenario_.floes.size());
}

void Simulation::check_state(const StepContext& ctx) const {
  const Floes& f = scenario_.floes;
  for (std::size_t i = 0; i < f.size(); ++i) {
    const double* s = reinterpret_cast<const double*>(&f.state[i]);
    for (int k = 0; k < kStateColumns; ++k)
      if (!std::isfinite(s[k])) {
        std::ostringstream m;
        m << "floe " << i << ": " << kStateColumnNames[k] << " is not finite after the step from t = "
          << ctx.t << " s with dt = " << ctx.dt << " s";
        throw RunError(m.str());
      }
  }
}

Energies Simulation::energies() const {
  const Floes& f = scenario_.floes;
  double horizontal = 0.0;
  for (std::size_t i = 0; i < f.size(); ++i) {
    if (f.is_static[i]) continue;
    const FloeState& s = f.state[i];
    horizontal += 0.5 * f.mass[i] * (s.vx * s.vx + s.vy * s.vy) + 0.5 * f.inertia_z[i] * s.yaw_rate * s.yaw_rate;
  }
  return {{"floes_horizontal_kinetic", "total"}, {horizontal, horizontal}};
}

}  // namespace floesim
