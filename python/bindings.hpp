#pragma once
// The compiled part of the floesim Python package (floesim._floesim). The
// pure-Python part (python/floesim/__init__.py) builds the user-facing Config,
// Simulation and RunFile on these. Each bind_* adds one unit's functions and
// classes to the module; InputError and RunError are registered in
// module.cpp and become floesim.InputError (a ValueError) and
// floesim.RunError (a RuntimeError) with the same messages.

#include <pybind11/pybind11.h>

namespace floesim::python {

void bind_config(pybind11::module_& m);      // TOML <-> Python values, checking a configuration
void bind_simulation(pybind11::module_& m);  // a Simulation built from a configuration text
void bind_run_file(pybind11::module_& m);    // reading and comparing run files

}  // namespace floesim::python
