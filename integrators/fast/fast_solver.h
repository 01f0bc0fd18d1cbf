// What the two fast solvers of docs/integrators.md "Fast solvers" share (projective_dynamics.cc,
// xpbd.cc): the system's stiff forces as distance constraints and
// projective elements (FastSolverViews::projective_form), the other forces
// applied explicitly, the contact planes (FastSolverViews::
// plane_constraints), a refusal where the system has no such form, and the
// gap of one constraint.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "integrators/core/integrator.h"
#include "integrators/linear/constraint_laplacian.h"
#include "models/core/fast_solver_views.h"

namespace springlab {

class FastSolver : public Integrator {
 protected:
  using Integrator::Integrator;

  // Reads the distance constraints and the projective elements
  // (FastSolverViews::projective_form; with takes_projections_, its
  // position_based_form, whose projections go to position_projections_); a failure
  // that says what to use when the system has no views or its stiff forces
  // have no such form.
  StepResult do_initialize() override;

  // F minus the constraints' forces, counted as a force evaluation.
  void eval_external_force(double t, const Vector& x, const Vector& v, Vector& f);

  // d = x_a - x_b (or x_a - anchor) of constraint c at x.
  Eigen::Vector3d difference(const DistanceConstraint& c, const Vector& x) const;

  // n.x_i - offset: particle i's gap to a contact plane at x.
  double gap(const PlaneConstraint& plane, const Vector& x, Eigen::Index i) const;
  // Dynamic Coulomb friction on v_: particle i's tangential velocity loses
  // min(max_dv, |v_t|) along -v_t/|v_t| (Mueller et al. 2020, sec. 3.6).
  void slow_tangential_velocity(const PlaneConstraint& plane, Eigen::Index i, double max_dv);

  const FastSolverViews* views_ = nullptr;  // the system's (do_initialize)
  int dim_ = 2;
  std::vector<DistanceConstraint> constraints_;
  std::vector<ProjectiveElement> elements_;
  std::vector<PlaneConstraint> planes_;  // contact planes (xpbd solves them)
  // Constraints the system projects itself (FastSolverViews::
  // position_based_form): read only by a solver that sets takes_projections_.
  bool takes_projections_ = false;
  std::vector<std::unique_ptr<PositionProjection>> position_projections_;
  Vector inv_particle_mass_;  // 1/m per free particle
};

}  // namespace springlab
