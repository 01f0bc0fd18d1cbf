// What a time integrator sees of a model: the second-order system
//
//     M x'' = F(t, x, v),    v = x',
//
// over the free unknowns only (fixed particles are not unknowns; an affine
// body's 12, p and the columns of A, are unknowns like a particle's), with a
// lumped (diagonal) mass M and the analytic Jacobians dF/dx, dF/dv on one
// sparsity pattern (fixed for springs, elements and bodies; a fluid's follows
// its neighbours: pattern_varies). Integrators know this interface and
// nothing of springs; models implement it and know nothing of time stepping.
//
// The interface in three parts (what belongs to the physics, and what to a
// solver's view of it):
//   1. The physics, which every method may use: dofs, mass, force,
//      jacobians, and the energy bookkeeping (derives_from_potentials, the
//      position and velocity potentials, nonconservative_power) that the
//      discrete gradient and the line searches read.
//   2. What an implicit solve needs beyond it: definite_jacobians (Newton's
//      definite matrix), jacobian_pattern, pattern_varies and pattern_version
//      (a symbolic factorization kept per pattern), jacobian_symmetric,
//      velocity_dependence, has_forbidden_states and admissible_fraction (the
//      barrier's step cap), has_trust_region and trusted_fraction (how far
//      one update may move a particle), lag_normal_forces (friction lagged
//      for one solve).
//   3. The fast solvers' views of the same forces, not in this interface:
//      FastSolverViews (models/core/fast_solver_views.h), which a system hands
//      out through fast_solver_views() (nullptr: none). projective_form
//      (projective dynamics), position_based_form (xpbd), laplacian_form
//      (quasi-Newton's initial Hessian), with plane_constraints,
//      external_force and dimension_of_state for what they solve or add
//      explicitly; each form false with the reason when the model's forces
//      have no such form (the solver then refuses the scene with it).
// A method that needs only part 1 runs every system; part 2 has defaults
// that say "none" for a system without it, and a system without part 3
// hands out no views, which the fast solvers refuse.
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <limits>
#include <memory>
#include <string>
#include <vector>

namespace springlab {

class FastSolverViews;  // models/core/fast_solver_views.h

using Vector = Eigen::VectorXd;
using SparseMatrix = Eigen::SparseMatrix<double>;  // column-major (CSC)

// How F depends on v. Up to kCoupled, F is affine in v:
// F(t, x, v) = F(t, x, 0) + dF/dv(t, x) v, which is what lets velocity Verlet
// solve its closing half-kick in one linear solve.
enum class VelocityDependence {
  kNone,       // F depends on (t, x) only
  kDiagonal,   // dF/dv is diagonal (drag, wind)
  kCoupled,    // dF/dv couples particles (spring damping)
  kNonlinear,  // F is not affine in v (Coulomb friction): dF/dv depends on v
};

// Which forces to evaluate. IMEX methods treat the stiff part (springs,
// spring damping, drag) implicitly and the rest (gravity, wind) explicitly.
enum class ForcePart { kAll, kStiff, kNonstiff };

class MechanicalSystem {
 public:
  virtual ~MechanicalSystem() = default;

  // Number of unknowns n = (free particles) x dimension.
  virtual Eigen::Index dofs() const = 0;
  // Lumped mass per degree of freedom (length n, all > 0).
  virtual const Vector& mass() const = 0;

  // f = F(t, x, v), or only its stiff / non-stiff part; f is resized to n.
  virtual void force(ForcePart part, double t, const Vector& x, const Vector& v,
                     Vector& f) const = 0;
  void force(double t, const Vector& x, const Vector& v, Vector& f) const {
    force(ForcePart::kAll, t, x, v, f);
  }

  // Fills dF/dx and/or dF/dv (either may be null) at (t, x, v), of all the
  // forces or of one part. Both come back with exactly the pattern of
  // jacobian_pattern(), so integrators can combine them value by value
  // (A = M - a dF/dv - b dF/dx) and reuse one symbolic factorization.
  virtual void jacobians(ForcePart part, double t, const Vector& x, const Vector& v,
                         SparseMatrix* dfdx, SparseMatrix* dfdv) const = 0;
  void jacobians(double t, const Vector& x, const Vector& v, SparseMatrix* dfdx,
                 SparseMatrix* dfdv) const {
    jacobians(ForcePart::kAll, t, x, v, dfdx, dfdv);
  }

  // dF/dx and dF/dv as jacobians(), except that each force replaces an
  // indefinite dF/dx by the nearest negative semidefinite one it can give
  // (a compressed spring drops its negative transverse stiffness), so that
  // M - a dF/dv - b dF/dx is positive definite for a, b >= 0: the implicit
  // methods' Newton matrix, whose steps are then descent directions of the
  // incremental potential below.
  virtual void definite_jacobians(double t, const Vector& x, const Vector& v, SparseMatrix* dfdx,
                                  SparseMatrix* dfdv) const = 0;

  // dfdx_p = dF/dx p (of the definite Jacobians with `definite`) and
  // dfdv_p = dF/dv p at (t, x, v), either may be null, without assembling
  // the Jacobians: where has_jacobian_products(), every force that has
  // Jacobians gives them (ForceTerm::add_jacobian_products). A Krylov
  // solve then needs no matrix but its preconditioner's (a fluid's
  // pressure Hessian reaches two kernel supports: assembling it cost more
  // than the conjugate gradients' products by it, docs/physics.md
  // "Implicit steps on a fluid").
  virtual bool has_jacobian_products() const { return false; }
  virtual void jacobian_products(bool /*definite*/, double /*t*/, const Vector& /*x*/,
                                 const Vector& /*v*/, const Vector& /*p*/, Vector* /*dfdx_p*/,
                                 Vector* /*dfdv_p*/) const {}

  // When every force derives from potentials,
  //   F(t, x, v) = -dV/dx (t, x) - dW/dv (t, v),
  // V the stored energy (springs, gravity) and W a dissipation potential of v
  // alone (drag: gamma |v|^2 / 2, wind: c |v - w(t)|^2 / 2), the residual of
  // an implicit step is the gradient of a scalar (its incremental potential)
  // that Newton can minimize: the merit function of its line search. False
  // when some force has no such form (spring damping depends on x and v
  // together).
  virtual bool derives_from_potentials() const = 0;
  // V(t, x), the stored energy of the forces that derive from one (springs,
  // gravity) whatever the others are, and W(t, v), zero when
  // !derives_from_potentials().
  virtual double position_potential(double t, const Vector& x) const = 0;
  virtual double velocity_potential(double t, const Vector& v) const = 0;
  // F_nc . v, the power of the forces that do not derive from V (drag,
  // wind, spring damping): F = -dV/dx + F_nc.
  virtual double nonconservative_power(double t, const Vector& x, const Vector& v) const = 0;
  // Whether some forces give their own discrete gradient of their potential
  // V_k (ForceTerm::has_discrete_gradient: g_k(x, y) with
  // g_k . (y - x) = V_k(y) - V_k(x) exactly), and, at the midpoint
  // x_m = (x + y) / 2 the caller holds, the difference those forces make
  // against their midpoint force:
  //   f += sum over them of (-g_k(x, y) - F_k(t, x_m)).
  // The discrete-gradient method adds it to F(t, x_m, v_m) (discrete_gradient.h).
  virtual bool has_own_discrete_gradients() const { return false; }
  virtual void add_own_discrete_gradient_difference(double /*t*/, const Vector& /*x*/,
                                                    const Vector& /*x_m*/, const Vector& /*y*/,
                                                    Vector& /*f*/) const {}
  // The Jacobian of that difference with respect to the midpoint, x held
  // (y = 2 x_m - x), for the discrete-gradient step's Newton matrix:
  //   out += s * sum over them of (-2 dg_k/dy (x, y) - dF_k/dx (t, x_m))
  // on the pattern of jacobians(), which out has (ForceTerm::
  // add_discrete_gradient_jacobian; not symmetric in general); with
  // `definite`, both as definite_jacobians() has them (symmetric).
  virtual void add_own_discrete_gradient_jacobian_difference(double /*t*/, const Vector& /*x*/,
                                                             const Vector& /*x_m*/,
                                                             const Vector& /*y*/,
                                                             bool /*definite*/, double /*s*/,
                                                             SparseMatrix& /*out*/) const {}

  // The shared pattern (union of both Jacobians' entries plus the full
  // diagonal), values all zero. Built once per scene, except for a system
  // whose pattern varies (below).
  virtual const SparseMatrix& jacobian_pattern() const = 0;

  // Systems whose couplings change with the state (a fluid's particles
  // change neighbours) have a pattern that varies: jacobians() and
  // definite_jacobians() may then come back on a new pattern (and
  // jacobian_pattern() is that one), and pattern_version() counts the
  // patterns so far. A solver that keeps something made for one pattern
  // (a symbolic factorization, a matrix combined value by value) keeps the
  // version it was made for and starts again when a matrix has another.
  // Springs and elements keep one pattern: version 0 throughout.
  virtual bool pattern_varies() const { return false; }
  virtual long pattern_version() const { return 0; }
  // Why it varies, as a phrase completing "the Jacobian pattern changes as
  // ..." (a solver that cannot follow it says so): "its particles change
  // neighbours (a fluid)".
  virtual std::string pattern_change() const { return "its couplings change with the state"; }

  // True when both Jacobians are symmetric at every state (no spring damping:
  // its dF/dx is not symmetric). Lets implicit methods use LDL^T.
  virtual bool jacobian_symmetric() const = 0;

  virtual VelocityDependence velocity_dependence() const = 0;

  // True when some states have no energy (+infinity: a barrier's closed gap,
  // an inverted neo-Hookean element). An implicit solver then keeps every
  // state it accepts, including a step's end when the forces are evaluated
  // elsewhere (the midpoint), where the energy is finite.
  virtual bool has_forbidden_states() const { return false; }
  // The largest alpha (+infinity when there is none) such that x + a dx is
  // allowed for every 0 <= a < alpha, where the forbidden states are known
  // in closed form (a barrier's gap d + a n.dx stays positive while
  // a < d / (-n.dx)): the step cap of IPC's line search (Li et al. 2020).
  virtual double admissible_fraction(const Vector& /*x*/, const Vector& /*dx*/) const {
    return std::numeric_limits<double>::infinity();
  }
  // A trust region (docs/physics.md "Implicit steps on a fluid"): true when
  // some forces are described by their value and Jacobians at x only over a
  // short distance, shorter than a large step can move a particle (a
  // fluid's: a particle feels its neighbours through a kernel of support
  // 2h, and a wall of particles through its pressure only once within that
  // support). An iterative solver then moves no particle further than that
  // in one update, and starts a step from its last accepted positions.
  virtual bool has_trust_region() const { return false; }
  // The largest alpha (+infinity: no bound) such that x + alpha dx moves no
  // particle further than the trust region's length (a fluid's water
  // particle: half its smoothing length).
  virtual double trusted_fraction(const Vector& /*x*/, const Vector& /*dx*/) const {
    return std::numeric_limits<double>::infinity();
  }

  // Lagged normal forces (docs/physics.md "Contact with planes"): with x_lag, Coulomb
  // friction takes its normal force f_n from x_lag instead of from the
  // evaluated state, which makes it the gradient of a dissipation potential
  // of v (IPC's lagging, Li et al. 2020); nullptr: from the evaluated state
  // again. An implicit method lags at the step's start (x_lag, v_lag) for
  // the duration of its solve of a step of length h (then
  // derives_from_potentials and jacobian_symmetric may change) and clears
  // it after; every other evaluation sees friction live. Contact between
  // bodies finds there the contacts it keeps for the step, as far as the
  // bodies can move in h at v_lag (docs/physics.md "Contact between
  // bodies"); v_lag may be null (then h is not read).
  virtual void lag_normal_forces(const Vector* /*x_lag*/, const Vector* /*v_lag*/,
                                 double /*h*/) const {}
  // While lagged: the contacts between bodies found again at x, an iterate
  // of the step's solve (Newton's accepted iterate's state), as far as the
  // bodies can move in h at v, in place of those found at the step's start
  // (IPC's constraint set, found at every iterate: Li et al. 2020, sec. 4).
  // True when they changed (the step's equations then did); x null: the
  // contacts of before the last such call again. Friction's normal forces
  // stay those of the step's start.
  virtual bool follow_lagged_contacts(const Vector* /*x*/, const Vector* /*v*/,
                                      double /*h*/) const {
    return false;
  }

  // Part 3: the fast solvers' views of the same forces
  // (models/core/fast_solver_views.h), or nullptr when the system has none (a
  // fast solver then refuses the scene and names implicit-euler).
  virtual const FastSolverViews* fast_solver_views() const { return nullptr; }
};

}  // namespace springlab
