// The per-floe structures' memory report (core/floe_bytes.hpp; docs/
// parallel.md, "The arrays held by band: measured (mem27)"): what a held
// mask says the held floes' entries take is what the same structures
// built for those floes alone take, and a serial Simulation holds every
// floe; the coupling's per-floe arrays are counted by their groups
// (coupling/floe_sea_arrays.hpp), each of which lists all its arrays.
#include <doctest/doctest.h>

#include <sstream>
#include <string>
#include <tuple>
#include <vector>

#include "contact/shapes.hpp"
#include "core/config.hpp"
#include "coupling/drift.hpp"
#include "coupling/floe_sea.hpp"
#include "coupling/floe_sea_arrays.hpp"
#include "coupling/scenario.hpp"
#include "coupling/simulation.hpp"

using namespace floesim;

namespace {
// Nine floes in a row: squares, pentagons and non-convex L shapes (two
// convex parts each), so that the floes' vertex, part and point counts vary.
std::string varied_floes() {
  std::ostringstream t;
  t << "[run]\ndt_max = 1\nt_end = 2\nthreads = 1\n";
  for (int k = 0; k < 9; ++k) {
    const double x = 30.0 * k;
    t << "[[floes.floe]]\nvertices = [";
    if (k % 3 == 0)
      t << "[" << x << ", 0], [" << x + 10 << ", 0], [" << x + 10 << ", 10], [" << x << ", 10]";
    else if (k % 3 == 1)
      t << "[" << x << ", 0], [" << x + 10 << ", 0], [" << x + 13 << ", 8], [" << x + 5 << ", 14], [" << x - 3
        << ", 8]";
    else
      t << "[" << x << ", 0], [" << x + 12 << ", 0], [" << x + 12 << ", 4], [" << x + 4 << ", 4], [" << x + 4
        << ", 12], [" << x << ", 12]";
    t << "]\nvelocity = [0.1, 0.0]\n";
  }
  return t.str();
}

// The same floes on a small periodic spectral sea.
std::string varied_floes_on_sea(const char* integrator) {
  return varied_floes() +
         "[sea]\nmodel = \"spectral\"\ndims = 2\nsize = [300.0, 40.0]\ncells = [64, 16]\ndepth = 20.0\n"
         "[coupling]\nstiffness = 100.0\nintegrator = \"" +
         integrator + "\"\n";
}

// A group with an array its list leaves out.
struct LeftOut {
  std::vector<double> a;
  std::vector<Vec2> b;
  std::vector<std::uint8_t> c;
  static auto arrays(auto& g) { return std::tie(g.a, g.b); }
};
}  // namespace

TEST_CASE("floe memory: the held floes' entries are those of the held floes built alone") {
  const Scenario s = build_scenario(parse_config(varied_floes(), "varied.toml", "."));
  const Floes& f = s.floes;
  REQUIRE(f.size() == 9);
  std::vector<std::uint8_t> mask(f.size(), 0);
  std::vector<std::size_t> which;
  for (const std::size_t i : {1u, 2u, 5u, 8u}) {
    mask[i] = 1;
    which.push_back(i);
  }
  const Floes alone = f.select(which);

  const Floes::Memory whole = f.memory(mask), held_alone = alone.memory({});
  CHECK(whole.constants.held == held_alone.constants.held);
  CHECK(whole.vertices.held == held_alone.vertices.held);
  CHECK(whole.state.held == held_alone.state.held);
  // Every floe held: the held entries are the arrays' sizes, at most their capacity.
  const Floes::Memory every = f.memory({});
  CHECK(every.vertices.held == (f.size() + 1) * sizeof(std::size_t) + f.body.size() * sizeof(Vec2));
  CHECK(every.vertices.held <= every.vertices.whole);
  CHECK(whole.vertices.held < every.vertices.held);

  const contact::CollisionShapes shapes = contact::build_collision_shapes(f),
                                 shapes_alone = contact::build_collision_shapes(alone);
  CHECK(shapes.vertex_offsets.size() - 1 > f.size());  // the L shapes have two parts
  CHECK(shapes.memory(mask).held == shapes_alone.memory({}).held);
  CHECK(shapes.memory({}).held <= shapes.memory({}).whole);

  const FootprintQuadrature q = build_footprint_quadrature(f, 1), q_alone = build_footprint_quadrature(alone, 1);
  CHECK(q.memory(mask).held == q_alone.memory({}).held);
  CHECK(q.memory({}).held <= q.memory({}).whole);
  // 6 points a fan triangle, 4 sub-triangles each at level 1: 24 a vertex.
  CHECK(q.memory({}).held == (f.size() + 1) * sizeof(std::size_t) + 24 * f.body.size() * (sizeof(Vec2) + sizeof(double)));
}

TEST_CASE("floe memory: a serial run holds every floe") {
  Simulation sim(build_scenario(parse_config(varied_floes(), "varied.toml", ".")));
  sim.step(2.0);
  const Simulation::FloeMemory m = sim.floe_memory();
  CHECK(m.floes == 9);
  CHECK(m.held == 9);
  REQUIRE(!m.parts.empty());
  CHECK(m.parts.back().first == "total");
  FloeBytes sum;
  for (std::size_t k = 0; k + 1 < m.parts.size(); ++k) {
    CAPTURE(m.parts[k].first);
    CHECK(m.parts[k].second.held <= m.parts[k].second.whole);
    sum += m.parts[k].second;
  }
  CHECK(sum.whole == m.parts.back().second.whole);
  CHECK(sum.held == m.parts.back().second.held);
}

TEST_CASE("floe memory: a group of per-floe arrays is sized and counted by its list of all of them") {
  // The coupling's groups list every member (also static_asserted where
  // they are defined); a list that leaves one out is caught.
  CHECK(lists_every_array<FloeSeaConstants>());
  CHECK(lists_every_array<FloeSeaKicks>());
  CHECK(lists_every_array<FloeSeaEvaluated>());
  CHECK(lists_every_array<FloeSeaImplicit>());
  CHECK(lists_every_array<FloeSeaSerialPlaces>());
  CHECK_FALSE(lists_every_array<LeftOut>());
  CHECK(floe_entry_bytes<LeftOut>() == sizeof(double) + sizeof(Vec2));

  FloeSeaConstants g;
  fit_floes(g, 7);
  g.bottom0[3] = -0.5;
  CHECK(g.dynamic.size() == 7);
  CHECK(g.tilt.size() == 7);
  CHECK(g.body_moments.size() == 7);
  const std::size_t entry = 2 * sizeof(std::uint8_t) + sizeof(double) + sizeof(Eigen::Matrix2d);
  CHECK(floe_entry_bytes<FloeSeaConstants>() == entry);
  CHECK(floe_group_bytes(g, 7).whole == 7 * entry);  // exactly the floes' places
  CHECK(floe_group_bytes(g, 3).held == 3 * entry);
  // Grown (a split): exactly the new count's places, the entries kept.
  fit_floes(g, 10);
  CHECK(floe_group_bytes(g, 10).whole == 10 * entry);
  CHECK(g.bottom0[3] == -0.5);
  CHECK(floe_group_bytes(FloeSeaImplicit{}, 10).whole == 0);  // unused: nothing
  CHECK(floe_group_bytes(FloeSeaImplicit{}, 10).held == 0);
}

TEST_CASE("floe memory: the coupling's per-floe arrays are its groups', one entry a floe") {
  const std::size_t explicit_entry = floe_entry_bytes<FloeSeaConstants>() + floe_entry_bytes<FloeSeaKicks>() +
                                     floe_entry_bytes<FloeSeaEvaluated>();
  for (const char* integrator : {"explicit", "implicit"}) {
    CAPTURE(integrator);
    Simulation sim(build_scenario(parse_config(varied_floes_on_sea(integrator), "varied.toml", ".")));
    sim.step(2.0);
    REQUIRE(sim.floe_sea() != nullptr);
    const bool implicit = integrator[0] == 'i';
    REQUIRE(sim.floe_sea()->implicit() == implicit);
    if (implicit) REQUIRE(sim.floe_sea()->implicit_stats().steps > 0);
    // Serially: no owners (their serial places, the next owners) and every
    // floe held; the implicit step's group only with the implicit step.
    const std::size_t entry = explicit_entry + (implicit ? floe_entry_bytes<FloeSeaImplicit>() : 0);
    const FloeBytes every = sim.floe_sea()->memory({}).per_floe;
    CHECK(every.held == 9 * entry);
    CHECK(every.whole == every.held);  // sized with the floes: no spare places
    std::vector<std::uint8_t> mask(9, 0);
    mask[2] = mask[6] = 1;
    CHECK(sim.floe_sea()->memory(mask).per_floe.held == 2 * entry);
  }
}
