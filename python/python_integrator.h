// Methods written in Python (docs/your-own-integrator.md, SPEC-style in
// docs/python.md "Your own integrator"):
//
//   class MyEuler(springlab.Integrator):
//       order = 1
//       symplectic = True
//       stability_limit = 2.0
//       def step(self, model, t, x, v, h):
//           v = v + h * model.force(t, x, v) / model.mass()
//           return x + h * v, v
//
// A class is registered under its `name` (default: the class name in
// kebab case, MyEuler -> my-euler) like a built-in method, so every run,
// stability search, check and experiment takes it by that name. Each run
// steps a copy of the instance it was given (copy.deepcopy), through a
// C++ Integrator whose do_step calls `step` with the GIL held: the same
// driver, divergence rule, statistics and result as a built-in.
//
// What `step` gets: `x`, `v` are read-only NumPy views of the state, shape
// (unknowns / d, d) (free particles, then each body's four rows), and
// `model` (the Model class below) gives the mass, the force, the
// Jacobians as SciPy sparse matrices (views of the library's arrays) and
// the energies, each call counted in the run's statistics.
#pragma once

#include <pybind11/pybind11.h>

#include <string>

namespace springlab::python {

// Defines springlab.Integrator (the base class) and springlab.Model (what a
// step is given) in module `m`, and sets the loader of experiment
// definitions' "python" files.
void bind_python_methods(pybind11::module_& m);

// Registers `method` (a springlab.Integrator instance, or a class, which is
// instantiated) and returns its name; a Python method already registered
// under that name is replaced. Raises TypeError for anything else and
// springlab.Error when the name is a built-in's or a plug-in's.
std::string register_python_method(const pybind11::object& method);

// The registered name of `method` when it is a Python method (registering
// it), or the string itself.
std::string method_name(const pybind11::object& method);

// The first exception a Python step raised since the last call (then
// cleared), restored as the current Python error: true when there was one.
bool restore_step_error();

}  // namespace springlab::python
