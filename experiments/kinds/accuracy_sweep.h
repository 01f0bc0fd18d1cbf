// Accuracy sweeps, shared by the convergence and work-precision experiments:
// each integrator over its own sweep (fixed-step methods: base_dt by their
// order and `halvings` - 1 halvings of it; adaptive ones: the `tolerances`),
// the final positions compared with a reference (the oscillator's exact
// solution, or a tight fixed-step run).
#pragma once

#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "experiments/kinds/definition.h"
#include "experiments/driver/simulation.h"
#include "integrators/core/integrator.h"
#include "models/model/model.h"

namespace springlab {

// One integrator's accuracy sweep: dt values (fixed-step) or rtol values
// (adaptive), largest first. Shared by convergence and work-precision.
struct SweepMethod {
  std::string name;
  IntegratorInfo info;
  std::vector<double> values;
};
// {"integrators": [...], "sweeps": {name: {adaptive, parameter, values}}}
nlohmann::json sweeps_json(const std::vector<SweepMethod>& methods);

// The methods a definition sweeps ("integrators", default all) with their
// values, the smallest fixed step among them (0 without a fixed-step method:
// a reference run's step must be below it), and "atol_factor" (adaptive
// runs use atol = rtol * atol_factor).
struct AccuracySweep {
  std::vector<SweepMethod> methods;
  double finest_dt = 0.0;
  double atol_factor = 1e-2;
};
AccuracySweep read_accuracy_sweep(const DefinitionObject& d);

// Fixed-step methods' dt by order: "base_dt": {"1": .., "2": .., "4": ..},
// picking the entry for the largest order key <= the method's order.
double base_dt_for_order(const DefinitionObject& o, const char* key, int order);

// The reference (see accuracy_sweep.cc), the sweep of one method, one point.
nlohmann::json accuracy_reference(const DefinitionObject& o, const char* key, const Scene& scene,
                                  double finest_dt);
Vector accuracy_reference_positions(const nlohmann::json& reference, const Model& model,
                                    const Scene& scene, double t_end,
                                    const IntegratorOptions& options, const std::string& where);
std::vector<double> accuracy_sweep_values(const DefinitionObject& d, const IntegratorInfo& info);
RunResult accuracy_run(const Model& model, const std::string& integrator, bool adaptive,
                       double value, double t_end, const IntegratorOptions& options,
                       double atol_factor);

// The exact solution of a scene that is the oscillator (one free particle on
// one undamped spring from a fixed one, released at rest, no other force):
// positions of the free unknowns at t. nullopt when the scene is not one.
std::optional<Vector> exact_oscillator_positions(const Scene& scene, double t);

// max over particles and axes of |x - x_ref|, the error measure the report names.
double position_error(const Vector& x, const Vector& x_ref);

// Least-squares slope of log(y) against log(x) over points with finite y > floor.
std::optional<double> log_log_slope(const std::vector<double>& x, const std::vector<double>& y,
                                    double floor = 0.0);

}  // namespace springlab
