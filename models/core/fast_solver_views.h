// The fast solvers' views of a mechanical system (part 3 of the interface
// map in models/core/mechanical_system.h): the same forces as the physics
// interface evaluates, in the forms that projective dynamics, XPBD and
// quasi-Newton's initial Hessian solve (docs/integrators.md "Fast
// solvers"). They are not physics every method may use, so they are not
// MechanicalSystem's: a system that has them implements FastSolverViews and
// hands it out through MechanicalSystem::fast_solver_views(); a system that
// does not returns nullptr there, and the fast solvers refuse it.
//
// Each form is false, with the reason where the solver shows one, when the
// system's forces have no such form (the solver then refuses the scene with
// it and names implicit-euler).
#pragma once

#include <Eigen/Core>
#include <memory>
#include <string>
#include <vector>

#include "models/core/mechanical_system.h"
#include "models/core/refusal.h"

namespace springlab {

// A distance constraint |x_a - x_b| = length of stiffness k (compliance
// 1/k): what the fast solvers (projective dynamics, XPBD) see of a stiff
// conservative force that has this form. a is a free particle (its unknowns
// at a * dim); b a free particle, or -1 with `anchor` the fixed position it
// is tied to.
struct DistanceConstraint {
  int a = 0;
  int b = -1;
  Eigen::Vector3d anchor = Eigen::Vector3d::Zero();
  double stiffness = 0.0;
  double length = 0.0;
};

// A half-space n.x >= offset that free particles must not enter, as the
// fast solvers see a contact plane (docs/integrators.md "Fast solvers", "Contact with
// planes"): with the penalty, a constraint of compliance 1/stiffness active
// where the gap is negative; the barrier has stiffness 0 (xpbd refuses it).
// `friction` is the plane's Coulomb mu.
struct PlaneConstraint {
  Eigen::Vector3d normal = Eigen::Vector3d::UnitY();  // unit
  double offset = 0.0;                                // n.point
  double stiffness = 0.0;                             // k_c; 0: the barrier
  double friction = 0.0;
};

// An element energy of projective form (Bouaziz et al., "Projective
// dynamics: fusing constraint projections for fast simulation", ACM TOG
// 2014, sec. 4-5), as projective dynamics sees it (docs/integrators.md "Fast solvers"):
//   E = w/2 |F - project(F)|^2,  F = sum_j x_j g_j^T (dim x k),
// project(F) a nearest point of F on a constraint set (the rotations: the
// as-rigid-as-possible strain energy; the matrices of J = 1: the volume
// constraint). Its global matrix gets w g_i . g_j
// for nodes i, j (the same for every coordinate); its local step is
// project(F). A fixed node has index -1 and its place in `fixed`.
// (Its matrices have at most 4 nodes and 3 x 3 entries: on the stack, so
// the fast solvers' local steps allocate nothing.)
struct ProjectiveElement {
  using Gradients = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, 4, 3>;
  using Deformation = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, 3, 3>;
  std::vector<int> nodes;               // internal indices; -1: a fixed node
  std::vector<Eigen::Vector3d> fixed;   // each node's position where fixed
  Gradients G;                          // nodes x k, rows g_j
  double weight = 0.0;                  // w
  // The projection, dim x k (models/materials/kernels/kinematics.h: polar's R,
  // nearest_unit_volume).
  Deformation (*project)(const Deformation& F) = nullptr;
};

// Constraints that a position-based solver (xpbd, docs/integrators.md
// "Fast solvers") cannot list once, because which particles they couple
// changes with the state (a fluid's density constraints: one per particle,
// over its neighbours), so the model projects them itself. In each substep
// the solver calls
//   begin(x)               at the predicted positions (the free unknowns):
//                          finds what stays fixed for the substep (the
//                          neighbours) and zeroes the multipliers;
//   project(x, h_s)        once per iteration: moves x toward the
//                          constraints, compliance a~ = alpha / h_s^2
//                          (XPBD, Macklin, Mueller and Chentanez 2016);
//   correct_velocity(x, v) after v = (x - x_prev) / h_s: a velocity filter
//                          the constraints come with (none by default).
class PositionProjection {
 public:
  virtual ~PositionProjection() = default;
  virtual void begin(const Vector& x) = 0;
  virtual void project(Vector& x, double hs) = 0;
  virtual void correct_velocity(const Vector& /*x*/, Vector& /*v*/, double /*hs*/) {}
};

class VertexBlockView;  // models/vertex_blocks.h

class FastSolverViews {
 public:
  virtual ~FastSolverViews() = default;

  // Vertex block descent's per-particle view (models/vertex_blocks.h), or
  // nullptr when the system has none.
  virtual const VertexBlockView* vertex_block_view() const { return nullptr; }

  // Projective dynamics' view: the stiff conservative forces as distance
  // constraints and projective elements (above), and F minus their forces
  // and every element's (external_force: gravity, drag, wind, spring
  // damping, treated explicitly). False, with `why` (one sentence for the
  // user), when some stiff force has neither form. The distance constraints
  // come in the scene's order of its springs: XPBD's Gauss-Seidel pass
  // projects them in this order.
  virtual bool projective_form(std::vector<DistanceConstraint>& constraints,
                               std::vector<ProjectiveElement>& elements,
                               Refusal& why) const = 0;
  // The position-based solvers' view (xpbd): projective_form's, where a
  // stiff force without that form may come instead as a PositionProjection
  // (appended to `projections`, which the solver then owns). The default
  // has none.
  virtual bool position_based_form(std::vector<DistanceConstraint>& constraints,
                                   std::vector<ProjectiveElement>& elements,
                                   std::vector<std::unique_ptr<PositionProjection>>& projections,
                                   Refusal& why) const {
    projections.clear();
    return projective_form(constraints, elements, why);
  }
  // Quasi-Newton's initial Hessian: the distance constraints and, for
  // elements of any material, the Laplacian part of a projective element
  // (no projection): weight w = (lambda + 2 mu) W. False when some stiff
  // conservative force has neither form.
  virtual bool laplacian_form(std::vector<DistanceConstraint>& constraints,
                              std::vector<ProjectiveElement>& elements) const = 0;

  // The contact planes as constraints (empty without planes). Their forces,
  // and friction's, are not in external_force: a fast solver that reads
  // projective_form must solve these too, or refuse the system.
  virtual void plane_constraints(std::vector<PlaneConstraint>& out) const = 0;
  // f = F(t, x, v) minus the forces of the constraints, elements,
  // projections and planes above: what a fast solver applies explicitly.
  virtual void external_force(double t, const Vector& x, const Vector& v, Vector& f) const = 0;
  // The dimension d of a free particle (dofs = free particles x d): the
  // fast solvers work per particle.
  virtual int dimension_of_state() const = 0;
};

}  // namespace springlab
