// Water-height gauges on a fluid run, against a measurement (the fluid
// experiment's "gauges" part, experiments/kinds/fluid_experiment.cc): MARIN's 3-D
// dam break onto a box (Kleefsman et al. 2005, SPHERIC test 2) measured the
// water's height at fixed points of the tank's floor; the run reports the
// same quantity at the same points.
//
// The height at a gauge (x_g, z_g) on the floor (y up) is the water's
// volume per unit floor area there, smoothed by the fluid's kernel in the
// horizontal plane:
//
//   H(x_g, z_g) = sum_j V_j W_2(|(x_j - x_g, z_j - z_g)|, h),   V_j = m_j / rho0,
//
// W_2 the cubic spline normalised in the plane (sph_kernel.h) and h the
// fluid's smoothing length: a column of n layers of the lattice gives
// n l, and a splash above the gauge counts with its volume, not its
// height (a droplet does not raise it by its elevation).
//
// The definition: {"scene", "parameters", "integrator", "dt", "substeps",
// "iterations", "t_end", "sample", "reference" (a CSV next to the
// definition, header "t,<gauge>,...", '#' lines its source), "gauges":
// [{"name", "x", "z"}, ...] (a name the reference has a column for, the
// point in the scene's coordinates), "bound" (metres: the root-mean-square
// difference the comparison is held to)}.
#pragma once

#include <string>
#include <vector>

#include "experiments/kinds/definition.h"
#include "experiments/kinds/experiment.h"
#include "integrators/core/integrator_options.h"
#include "models/core/scene.h"

namespace springlab {

struct Gauge {
  std::string name;
  double x = 0.0, z = 0.0;
};

struct GaugeReference {
  std::vector<double> t;
  std::vector<std::vector<double>> height;  // per gauge, at t
  std::string source;                       // the file's '#' lines, joined
  std::string file;
};

class FluidGauges {
 public:
  explicit FluidGauges(const DefinitionObject& d, const IntegratorOptions& options);

  // The run: rows of the tables below, into out.rows[first..first + 3).
  void run(TaskOutput& out, std::size_t first) const;

  // "gauges": name, t, height, measured (the reference interpolated at t,
  // empty outside it); "gauge_summary": one row per gauge;
  // "gauge_reference": the measured points.
  static std::vector<TableSpec> tables();
  nlohmann::json settings() const;

 private:
  Scene scene_;
  IntegratorOptions options_;
  std::string integrator_;
  double dt_ = 0.0, t_end_ = 0.0, sample_ = 0.0, bound_ = 0.0;
  int substeps_ = 0, iterations_ = 0;
  std::vector<Gauge> gauges_;
  GaugeReference reference_;
};

// H at (x_g, z_g) of the first fluid of `scene`'s free particles at the
// scene positions `positions` (particle s at row s): the formula above.
double gauge_height(const Scene& scene, const Eigen::MatrixXd& positions, double x_g, double z_g);

}  // namespace springlab
