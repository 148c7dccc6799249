#include "coupling/simulation.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "core/error.hpp"
#include "fluid/sea.hpp"

namespace floesim {

Simulation::Simulation(Scenario scenario) : scenario_(std::move(scenario)) {
  const Config& c = scenario_.config;
  drift_params_ = DriftParams{c.sea.rho, c.forcing.ocean_drag, c.forcing.air_density, c.forcing.air_drag,
                              c.forcing.coriolis};
  quadrature_ = build_footprint_quadrature(scenario_.floes);
  sea_ = fluid::make_sea(c.sea, c.run.seed);
}

Simulation::~Simulation() = default;
Simulation::Simulation(Simulation&&) noexcept = default;

double Simulation::step(double t_stop) {
  StepContext ctx;
  { PhaseTimer _(profile_, Phase::choose_dt); ctx = choose_dt(t_stop); }
  { PhaseTimer _(profile_, Phase::forcing);   sample_forcing(ctx); }
  { PhaseTimer _(profile_, Phase::sea);       sea_flow(ctx); }
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
  const double dt_max = scenario_.config.run.dt_max;
  // Land on t_stop without leaving a sliver of a step before it: take the rest
  // when it is within round-off of dt_max, split it in two when it is short of
  // 1.5 dt_max.
  if (remaining <= dt_max * (1.0 + 1e-9)) ctx.dt = remaining;
  else if (remaining < 1.5 * dt_max) ctx.dt = 0.5 * remaining;
  else ctx.dt = dt_max;
  if (!(ctx.dt > 0.0)) throw RunError("step requested with no time left (t = " + std::to_string(t_) + ")");
  return ctx;
}

void Simulation::sample_forcing(StepContext& ctx) const {
  // Forcing is held over the step at its value at mid-step (second-order
  // accurate for a smooth series).
  ctx.forcing = scenario_.forcing.at(ctx.t + 0.5 * ctx.dt);
}

void Simulation::sea_flow(const StepContext& ctx) {
  // Free evolution, exact per mode. Floe pressures (half kicks around this
  // flow, MODEL.md §5) arrive with the floe–sea coupling.
  if (sea_) sea_->flow(ctx.dt);
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
  Energies e{{"floes_horizontal_kinetic"}, {horizontal}};
  if (sea_) {
    const fluid::SeaEnergy se = sea_->energy();
    e.names.insert(e.names.end(), {"sea_kinetic", "sea_potential"});
    e.values.insert(e.values.end(), {se.kinetic, se.potential});
  }
  double total = 0.0;
  for (double v : e.values) total += v;
  e.names.push_back("total");
  e.values.push_back(total);
  return e;
}

SeaGridInfo Simulation::sea_grid() const {
  if (!sea_) return {};
  const fluid::SurfaceGrid& g = sea_->grid();
  return {g.dims, {g.nx, g.ny}, {g.lx, g.ly}};
}

std::span<const double> Simulation::sea_elevation() {
  if (!sea_) return {};
  return sea_->elevation();
}

}  // namespace floesim
