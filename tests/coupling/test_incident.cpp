// The incident waves for drag (coupling/incident.hpp): the orbital velocity
// read between two snapshots tau apart against the same sea stepped to the
// very time asked. Reference: linear interpolation of a wave of frequency
// omega errs by at most (omega tau)^2 / 8 of its amplitude.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "core/params.hpp"
#include "coupling/incident.hpp"
#include "fluid/sea.hpp"

using namespace floesim;

TEST_SUITE_BEGIN("coupling");

TEST_CASE("incident waves: snapshots tau apart, read in between, within (omega tau)^2 / 8 of the wave") {
  SeaParams p;
  p.model = SeaModel::spectral;
  p.dims = 2;
  p.size = {100.0, 50.0};
  p.cells = {64, 32};
  p.depth = 20.0;
  p.sigma = 0.0;
  p.waves.kind = WaveKind::regular;
  p.waves.amplitude = 0.5;
  p.waves.wavelength = 25.0;
  const double tau = IncidentSea::interval_for(p);
  const fluid::Dispersion d = fluid::Dispersion::of(p);
  const double omega = d.omega(2.0 * std::numbers::pi / 25.0);
  CHECK(tau == doctest::Approx(2.0 * std::numbers::pi / omega / 40.0));
  IncidentSea incident(fluid::make_sea(p, 1, {}), tau);
  std::unique_ptr<fluid::Sea> exact = fluid::make_sea(p, 1, {});
  // The orbital velocity's amplitude: a omega coth(k H) at the surface.
  const double k = 2.0 * std::numbers::pi / 25.0;
  const double amplitude = 0.5 * omega / std::tanh(k * 20.0);
  double worst = 0.0;
  int intervals = 0;
  for (double t = 0.0, h = 0.013; t < 12.0; t += h) {  // steps that do not divide tau
    if (t > 0.0) exact->flow(h);
    incident.advance_to(t);
    const double w = incident.weight(t);
    const auto u = exact->field(fluid::Field::velocity_x).all();
    for (std::size_t c = 0; c < u.size(); c += 7)
      worst = std::max(worst, std::abs((1.0 - w) * incident.u0()[c] + w * incident.u1()[c] - u[c]));
    intervals = static_cast<int>(t / tau);
  }
  const double bound = std::pow(omega * tau, 2) / 8.0 * amplitude;
  MESSAGE("tau = " << tau << " s over " << intervals << " intervals: worst error " << worst << " m/s, bound "
                   << bound << " m/s (amplitude " << amplitude << " m/s)");
  CHECK(worst > 0.0);
  CHECK(worst <= 1.05 * bound);
}

TEST_CASE("incident waves: no interval without a wave period") {
  SeaParams p;
  p.model = SeaModel::spectral;
  CHECK(IncidentSea::interval_for(p) == 0.0);
  p.waves.kind = WaveKind::jonswap;
  p.waves.tp = 10.0;
  CHECK(IncidentSea::interval_for(p) == doctest::Approx(0.25));
}

TEST_SUITE_END();
