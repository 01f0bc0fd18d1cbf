// Your own integrator: the one header to read first
// (docs/your-own-integrator.md is the tutorial).
//
// A method written outside springlab's tree is a class like every built-in
// one: it derives from Integrator (integrator.h), says what it is in an
// IntegratorInfo, and overrides one hook,
//
//   StepResult do_step(double h);   // advance (x_, v_) from t_ to t_ + h
//
// A plug-in (a shared library built with find_package(springlab) and
// springlab_add_plugin(), docs/cmake-package.md) registers it with one line,
//
//   SPRINGLAB_PLUGIN_INTEGRATOR(MyEuler)
//
// and the ordinary command line runs it: `springlab run cloth --plugin
// ./libmy_method.so --integrator my-euler` (also `stability`, `check` and
// an experiment definition's "plugins": [...]).
//
// What a step may use: the model as every method sees it,
//
//     M x'' = F(t, x, v),   v = x',
//
// over the free unknowns (fixed particles are not unknowns; an affine
// body's 12 numbers are unknowns like a particle's 3).
//
//   the state        t_, x_, v_ (Vector = Eigen::VectorXd, length n); the
//                    driver reads them after each step
//   the mass         system().mass(): the lumped mass per unknown (length
//                    n, all > 0); inv_mass() is its inverse
//   the force        eval_force(t, x, v, f): f = F(t, x, v)
//                    eval_acceleration(t, x, v, a): a = M^-1 F(t, x, v)
//   the Jacobians    eval_jacobians(t, x, v, &K, &D): K = dF/dx and
//                    D = dF/dv, sparse (SparseMatrix, column-major), both on
//                    the pattern system().jacobian_pattern(), so
//                    A = M - h D - h^2 K is combined value by value
//                    eval_definite_jacobians(...): the same with each
//                    force's indefinite part dropped (a compressed spring),
//                    so that M - h D - h^2 K is positive definite: the
//                    Newton matrix of an implicit step
//   the energies     system().position_potential(t, x) (V: springs,
//                    gravity, elements) and system().velocity_potential(t, v)
//                    (W: drag, wind), when system().derives_from_potentials():
//                    the pieces of implicit Euler's incremental potential
//                      E(v) = |v - v_n|^2_M / 2 + V(x_n + h v) + h W(v),
//                    whose gradient is the step's residual
//                      r(v) = M (v - v_n) - h F(t + h, x_n + h v, v)
//                    and whose Hessian is M - h D - h^2 K; the energies by
//                    column (kinetic, spring, gravity, ...) are written by
//                    the driver, not by a method
//   the options      options(): --newton-tol, --max-newton, ... as typed
//   the statistics   mutable_stats(): the eval_* calls count themselves;
//                    count your own Newton iterations and linear solves
//                    there, so `run --json` reports them like a built-in's
//   failing          return StepResult::failure("why, and what to try"): the
//                    run ends as a result (never throw, never exit)
//
// Tools the built-ins use, callable from a plug-in:
//   SparseDirectSolver (integrators/linear/sparse_direct_solver.h):
//     factorize(A, MatrixKind::kPositiveDefinite) then solve(b, x);
//   NewtonLoop (integrators/newton/newton_loop.h) and the velocity-implicit
//     step (integrators/newton/velocity_implicit_method.h): the library's
//     Newton with its line search and fallbacks.
//
// What the class declares is what `springlab check` tests it against (no
// claim given on the command line: these): IntegratorInfo's `order`,
// `symplectic`, `stability` with `stability_limit` (the largest stable w h
// on the undamped oscillator) or kA / kL; see integrator.h. Other claims
// (--dissipative, --momentum, --deterministic) are given on the command line.
//
// examples/plugins/ holds two: a symplectic Euler of about 30 lines and an
// implicit Euler with its own Newton loop of about 80.
#pragma once

#include <vector>

#include "integrators/core/integrator.h"
#include "integrators/core/integrator_entry.h"

namespace springlab {

// Called by SPRINGLAB_PLUGIN_INTEGRATOR while a plug-in is loaded (its
// static initialisers run): the loader (integrators/registry/plugins.h)
// takes the offered entries and registers them, refusing a name that is
// taken with a message naming the plug-in. `entry` is a static of the
// plug-in.
void offer_plugin_integrator(const IntegratorEntry& entry) noexcept;
// The entries offered since the last call (the loader's side).
std::vector<const IntegratorEntry*> take_offered_integrators();

}  // namespace springlab

#define SPRINGLAB_PLUGIN_CONCAT_(a, b) a##b
#define SPRINGLAB_PLUGIN_CONCAT(a, b) SPRINGLAB_PLUGIN_CONCAT_(a, b)

// Registers the method class CLASS (default-constructible, its name in its
// IntegratorInfo) when the plug-in is loaded. At namespace scope, once per
// class.
#define SPRINGLAB_PLUGIN_INTEGRATOR(CLASS)                                                 \
  namespace {                                                                              \
  const bool SPRINGLAB_PLUGIN_CONCAT(springlab_offered_, __LINE__) = [] {                  \
    static const ::springlab::IntegratorEntry entry = ::springlab::integrator_entry<CLASS>(); \
    ::springlab::offer_plugin_integrator(entry);                                           \
    return true;                                                                           \
  }();                                                                                     \
  }
