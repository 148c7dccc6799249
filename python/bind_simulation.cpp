// A Simulation (coupling/simulation.hpp) driven from Python: built from a
// configuration text, stepped, run to a time on the output schedule of
// `floesim run`, or run to the end into a run file; its floes, energies, LCP
// counters and sea surface come back as NumPy arrays and dicts.
#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include <cmath>
#include <limits>
#include <optional>
#include <memory>
#include <string>

#include "core/checkpoint.hpp"
#include "core/config.hpp"
#include "core/error.hpp"
#include "coupling/run.hpp"
#include "coupling/scenario.hpp"
#include "coupling/simulation.hpp"
#include "python/bindings.hpp"

namespace py = pybind11;

namespace floesim::python {

namespace {

using Array = py::array_t<double>;

py::dict energies_dict(const Energies& e) {
  py::dict d;
  for (std::size_t k = 0; k < e.names.size(); ++k) d[py::str(e.names[k])] = e.values[k];
  return d;
}

Array per_floe(const std::vector<double>& v) {
  Array a(static_cast<py::ssize_t>(v.size()));
  std::copy(v.begin(), v.end(), a.mutable_data());
  return a;
}

// Advances to time t landing on every output time on the way, exactly as
// run_simulation (coupling/run.cpp) does for `floesim run --until t`: records
// at k * output_interval, and a record within 1e-9 s of the end merges with
// it. So the states at those times equal the run file's records.
void run_until(Simulation& sim, double t) {
  if (!std::isfinite(t)) throw InputError("run_until: expected a finite time, got " + std::to_string(t));
  const double interval = sim.scenario().config.run.output_interval;
  while (sim.time() < t) {
    double next = std::floor(sim.time() / interval) + 1.0;
    if (next * interval <= sim.time()) next += 1.0;
    double t_record = std::min(next * interval, t);
    if (t - t_record < 1e-9 * std::max(1.0, t)) t_record = t;
    while (sim.time() < t_record) {
      sim.step(t_record);
      if (PyErr_CheckSignals() != 0) throw py::error_already_set();  // Ctrl-C
    }
  }
}

py::dict run_to_file(Simulation& sim, const std::string& output, double until) {
  // until < 0 (the default): to [run] t_end, already bounded at load. Otherwise the
  // checks of `floesim run --until` (apps/cmd_run.cpp): finite, and the records bound.
  if (std::isnan(until) || std::isinf(until))
    throw InputError("run: until: expected a finite time >= 0 (s), or -1 for [run] t_end, got " + std::to_string(until));
  if (until >= 0.0)
    if (const std::string problem = record_count_problem(until, sim.scenario().config.run.output_interval);
        !problem.empty())
      throw InputError("run: until = " + std::to_string(until) + ": " + problem);
  RunOptions options;
  options.output = output;
  options.until = until;
  bool interrupted = false;
  options.should_stop = [&interrupted] { return interrupted = interrupted || PyErr_CheckSignals() != 0; };
  const RunSummary s = run_simulation(sim, options);
  if (interrupted) throw py::error_already_set();  // the file holds the records so far
  py::dict d;
  d["output"] = s.output;
  d["xdmf"] = s.xdmf;
  d["status"] = s.status;
  d["steps"] = s.steps;
  d["records"] = s.records;
  d["t_end"] = s.t_end;
  d["wall_seconds"] = s.wall_seconds;
  d["energy_first"] = energies_dict(s.energy_first);
  d["energy_last"] = energies_dict(s.energy_last);
  d["notes"] = s.notes;
  d["warnings"] = s.warnings;
  return d;
}

}  // namespace

void bind_simulation(py::module_& m) {
  py::class_<Simulation>(m, "Simulation", "A running simulation (floesim.Simulation wraps it).")
      .def(py::init([](const std::string& text, const std::string& name, const std::string& base_dir) {
             return std::make_unique<Simulation>(build_scenario(parse_config(text, name, base_dir)));
           }),
           py::arg("text"), py::arg("name"), py::arg("base_dir"))
      .def_property_readonly("time", &Simulation::time, "Simulated time (s).")
      .def_property_readonly("steps", &Simulation::steps, "Steps taken so far.")
      .def_property_readonly("floe_count", [](const Simulation& s) { return s.floes().size(); })
      .def(
          "step",
          [](Simulation& s, std::optional<double> t_stop) {
            // Without t_stop: at most dt_max ahead (a finite stop, so that limits
            // that share the time left into equal steps still apply).
            return s.step(t_stop ? *t_stop : s.time() + s.scenario().config.run.dt_max);
          },
          py::arg("t_stop") = py::none(), "One step, of at most dt_max and not past t_stop; returns dt (s).")
      .def(
          "_restore",
          [](Simulation& s, const std::string& path) { s.restore(read_checkpoint(path)); },
          py::arg("path"), "Puts the simulation at the checkpoint of a run file of its configuration.")
      .def("run_until", &run_until, py::arg("t"))
      .def("run", &run_to_file, py::arg("output"), py::arg("until") = -1.0)
      .def_property_readonly("state",
                             [](const Simulation& s) {
                               const auto& st = s.floes().state;
                               Array a({static_cast<py::ssize_t>(st.size()), static_cast<py::ssize_t>(kStateColumns)});
                               if (!st.empty()) std::copy_n(&st[0].x, st.size() * kStateColumns, a.mutable_data());
                               return a;
                             })
      .def("polygons",
           [](const Simulation& s) {
             py::list out;
             const Floes& f = s.floes();
             for (std::size_t i = 0; i < f.size(); ++i) {
               const auto w = f.world_vertices(i);
               Array a({static_cast<py::ssize_t>(w.size()), py::ssize_t{2}});
               auto r = a.mutable_unchecked<2>();
               for (std::size_t k = 0; k < w.size(); ++k) {
                 r(static_cast<py::ssize_t>(k), 0) = w[k].x();
                 r(static_cast<py::ssize_t>(k), 1) = w[k].y();
               }
               out.append(a);
             }
             return out;
           })
      .def_property_readonly("ids",
                             [](const Simulation& s) {
                               const auto& v = s.floes().id;
                               py::array_t<long long> a(static_cast<py::ssize_t>(v.size()));
                               std::copy(v.begin(), v.end(), a.mutable_data());
                               return a;
                             },
                             "Each floe's number in the run file (the floe axis of /floes/state); "
                             "a floe that splits ends and its pieces get new numbers.")
      .def("take_fracture_events",
           [](Simulation& s) {
             const std::vector<FractureEventRow> rows = s.take_fracture_events();
             Array a({static_cast<py::ssize_t>(rows.size()), static_cast<py::ssize_t>(kFractureEventColumns)});
             if (!rows.empty()) std::copy_n(&rows[0].time, rows.size() * kFractureEventColumns, a.mutable_data());
             return a;
           },
           "Fracture initiations since the last call, rows of FRACTURE_EVENT_COLUMNS.")
      .def("take_collision_events",
           [](Simulation& s) {
             const std::vector<CollisionEventRow> rows = s.take_collision_events();
             Array a({static_cast<py::ssize_t>(rows.size()), static_cast<py::ssize_t>(kCollisionEventColumns)});
             if (!rows.empty()) std::copy_n(&rows[0].time, rows.size() * kCollisionEventColumns, a.mutable_data());
             return a;
           },
           "Collisions since the last call ([run] record_collisions), rows of COLLISION_EVENT_COLUMNS: "
           "one per solve and pair of floes.")
      .def_property_readonly("mass", [](const Simulation& s) { return per_floe(s.floes().mass); })
      .def_property_readonly("thickness", [](const Simulation& s) { return per_floe(s.floes().thickness); })
      .def_property_readonly("area", [](const Simulation& s) { return per_floe(s.floes().area); })
      .def_property_readonly("inertia", [](const Simulation& s) { return per_floe(s.floes().inertia_z); })
      .def_property_readonly("is_static",
                             [](const Simulation& s) {
                               const auto& v = s.floes().is_static;
                               py::array_t<bool> a(static_cast<py::ssize_t>(v.size()));
                               for (std::size_t i = 0; i < v.size(); ++i) a.mutable_data()[i] = v[i] != 0;
                               return a;
                             })
      .def("energies", [](const Simulation& s) { return energies_dict(s.energies()); })
      .def("lcp",
           [](const Simulation& s) {
             const LcpCounters c = s.lcp_counters();
             py::dict d;
             d["solves"] = c.solves;
             d["pivots"] = c.pivots;
             d["failures"] = c.failures;
             d["fallbacks"] = c.fallbacks;
             return d;
           })
      .def("momentum",
           [](const Simulation& s) {
             const Vec2 p = s.momentum();
             return py::make_tuple(p.x(), p.y());
           })
      .def("momentum_budget",
           [](const Simulation& s) {
             const auto& b = s.momentum_budget();
             py::dict d;
             d["external"] = py::make_tuple(b.external.x(), b.external.y());
             d["collisions"] = py::make_tuple(b.collisions.x(), b.collisions.y());
             return d;
           })
      .def_property_readonly("has_sea", &Simulation::has_sea)
      .def("sea_grid",
           [](const Simulation& s) {
             const SeaGridInfo g = s.sea_grid();
             py::dict d;
             d["dims"] = g.dims;
             d["cells"] = py::make_tuple(g.cells[0], g.cells[1]);
             d["size"] = py::make_tuple(g.size[0], g.size[1]);
             return d;
           })
      .def("sea_elevation",
           [](Simulation& s) {
             const SeaGridInfo g = s.sea_grid();
             const auto eta = s.sea_elevation();
             if (g.dims == 0) return Array(0);
             Array a = g.dims == 2 ? Array({static_cast<py::ssize_t>(g.cells[1]), static_cast<py::ssize_t>(g.cells[0])})
                                   : Array(static_cast<py::ssize_t>(g.cells[0]));
             if (static_cast<std::size_t>(a.size()) != eta.size())
               throw RunError("sea elevation has " + std::to_string(eta.size()) + " values for a grid of " +
                              std::to_string(a.size()));
             std::copy(eta.begin(), eta.end(), a.mutable_data());
             return a;
           })
      .def("warnings",
           [](const Simulation& s) {
             std::vector<std::string> w = s.notes();
             for (const std::string& x : s.warnings()) w.push_back(x);
             return w;
           })
      .def("profile",
           [](const Simulation& s) {
             py::dict d;
             for (std::size_t k = 0; k < kPhaseNames.size(); ++k) d[kPhaseNames[k]] = s.profile().seconds[k];
             return d;
           })
      .def("resolved_toml", [](const Simulation& s) { return resolved_toml(s.scenario().config); });
}

}  // namespace floesim::python
