// floesim._floesim: the compiled module behind `import floesim`.
#include <pybind11/pybind11.h>

#include "core/error.hpp"
#include "core/floes.hpp"
#include "core/run_file.hpp"
#include "python/bindings.hpp"

namespace py = pybind11;

PYBIND11_MODULE(_floesim, m) {
  m.doc() = "floesim's compiled core; use the floesim package, not this module.";
  // Bad input and numerical failure keep their C++ messages (file, key, what was expected).
  py::register_exception<floesim::InputError>(m, "InputError", PyExc_ValueError);
  py::register_exception<floesim::RunError>(m, "RunError", PyExc_RuntimeError);
  m.attr("__version__") = FLOESIM_VERSION;
  py::tuple columns(floesim::kStateColumns);
  for (int k = 0; k < floesim::kStateColumns; ++k) columns[static_cast<std::size_t>(k)] = floesim::kStateColumnNames[k];
  m.attr("STATE_COLUMNS") = columns;
  m.attr("LCP_COLUMNS") = py::make_tuple("solves", "pivots", "failures", "fallbacks");
  py::tuple events(floesim::kFractureEventColumns);
  for (int k = 0; k < floesim::kFractureEventColumns; ++k)
    events[static_cast<std::size_t>(k)] = floesim::kFractureEventColumnNames[k];
  m.attr("FRACTURE_EVENT_COLUMNS") = events;
  py::tuple collisions(floesim::kCollisionEventColumns);
  for (int k = 0; k < floesim::kCollisionEventColumns; ++k)
    collisions[static_cast<std::size_t>(k)] = floesim::kCollisionEventColumnNames[k];
  m.attr("COLLISION_EVENT_COLUMNS") = collisions;
  floesim::python::bind_config(m);
  floesim::python::bind_simulation(m);
  floesim::python::bind_run_file(m);
}
