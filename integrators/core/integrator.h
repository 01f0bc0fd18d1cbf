// The integrator interface. A base class owns what every method shares
// (state, time, statistics, the counted calls into the model); a method
// overrides one narrow hook:
//   - fixed-step methods implement do_step(h): advance (x, v) from t to t+h;
//   - adaptive methods (SUNDIALS) override advance_to(t_out) and take as many
//     internal steps as their error control needs.
// Failures (Newton not converging, a solver error) are returned as a
// StepResult, never thrown, never abort()/exit().
#pragma once

#include <complex>
#include <functional>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "integrators/core/integrator_options.h"
#include "models/core/mechanical_system.h"
#include "models/core/refusal.h"

namespace springlab {

// One vocabulary for every method (docs/integrators.md "The integrators"), exported with these
// names.
struct IntegratorStats {
  long steps = 0;               // accepted steps
  long rejected_steps = 0;      // error-test failures (adaptive) or failed attempts
  long force_evals = 0;         // evaluations of F(t, x, v)
  long jacobian_evals = 0;      // evaluations of dF/dx and/or dF/dv
  long linear_solves = 0;       // solves with a factorized (or iterative) matrix
  long linear_iterations = 0;   // iterations of the iterative ones (conjugate gradients)
  long newton_iterations = 0;   // nonlinear iterations
  long factorizations = 0;      // numeric factorizations / linear solver setups
  long nonlinear_failures = 0;  // nonlinear solves that did not converge
};

// A weaker variant of a method that some of a run's steps fell back to
// (docs/command-line.md "Warnings": the run reports it, with the number of
// steps). Data, not prose: the driver's warnings print it.
enum class Fallback {
  // discrete-gradient: Gonzalez's generic discrete gradient for every force
  // instead of a force's own (the rigid bodies' rigidity): energy still
  // exact, but the step's angular momentum is not kept.
  kGenericDiscreteGradient,
  // implicit-midpoint, discrete-gradient, the Newmark-alpha methods, bdf2:
  // a step whose Newton failed, solved again as 2, 4 or 8 substeps
  // (VelocityImplicitMethod::retry_in_substeps).
  kSubsteps,
};
struct FallbackCount {
  Fallback fallback = Fallback::kGenericDiscreteGradient;
  long steps = 0;
};

struct StepResult {
  bool ok = true;
  std::string message;  // why it failed, naming the call / condition
  // A refusal before the first step, as data (models/core/refusal.h): the
  // sentence without the method's name (message is "name: " + it) and the
  // scene setting that would make the pairing work, or empty.
  Refusal refused;
  static StepResult success() { return {}; }
  static StepResult failure(std::string why) { return {false, std::move(why), {}}; }
  static StepResult refusal(const std::string& method, Refusal why) {
    std::string message = method + ": " + why.text;
    return {false, std::move(message), std::move(why)};
  }
};

// What a method's stability region {z : |R(z)| <= 1} covers, R being one
// step's map on the test equation y' = lambda y and z = h lambda (lambda an
// eigenvalue of the linearized first-order system: +-i w for an undamped
// mode, in the left half-plane with damping). `springlab list` states it and
// tests/test_stability_property.cc measures it for every registered method.
enum class StabilityKind {
  kUnknown,      // not declared: no claim is made
  kConditional,  // stable only for steps small enough: see stability_limit
  kAAlpha,       // A(alpha): the wedge |arg(-z)| <= alpha (stability_alpha,
                 // degrees) - stiff decay, but not every oscillation
  kA,            // the whole left half-plane: no step is too large
  kL,            // A-stable and R(z) -> 0 as |z| -> infinity: a large step
                 // damps a stiff mode almost completely
};
const char* to_string(StabilityKind kind);
// The stability_limit of A- and L-stable methods: every w h is stable.
inline constexpr double kInfinity = std::numeric_limits<double>::infinity();  // "unknown", "conditional", "A(alpha)", "A", "L"

// What a student (and the shared test suites) can read off a method.
struct IntegratorInfo {
  std::string name;
  std::string scheme;        // one line: the update formula
  int order = 1;             // global order of accuracy
  // Where the positions alone converge faster when F depends on x only: the
  // order of x then (fox-goodwin's positions are Numerov's method: 4). 0:
  // the same as `order`.
  int position_order = 0;
  bool adaptive = false;
  bool implicit = false;
  bool iterates_to_tolerance = false;  // solves its nonlinear system to --newton-tol
  // Approximates implicit Euler's step with a fixed number of iterations
  // and no Jacobian (projective dynamics, XPBD: docs/integrators.md "Fast solvers").
  bool jacobian_free = false;
  bool symplectic = false;   // for forces that depend on x only
  StabilityKind stability = StabilityKind::kUnknown;
  // Largest stable omega*h on the undamped linear oscillator (eigenvalues
  // +-i w): finite for a conditionally stable fixed-step method, 0 for one
  // unstable at every step without damping (explicit Euler); infinity for A-
  // and L-stable methods; NaN when it is not one number (unknown, A(alpha),
  // or an adaptive method, whose step control keeps h inside its region).
  double stability_limit = std::numeric_limits<double>::quiet_NaN();
  double stability_alpha = std::numeric_limits<double>::quiet_NaN();  // kAAlpha, degrees
  // What the property holds for when that is not the method as a whole,
  // e.g. "at the default --max-order 5; orders 1-2 are L-stable".
  std::string stability_note = {};
  // R(z) of the method on y' = lambda y, when one step is that scalar map
  // (so the oscillator's energy changes by |R(i w h)|^2 each step). Empty for
  // partitioned methods (symplectic Euler, Verlet) and adaptive ones.
  std::function<std::complex<double>(std::complex<double>)> stability_function = {};
  // The spectral radius of the step's amplification matrix as w h -> infinity
  // on the undamped oscillator, where the method declares it (the Newmark
  // family, BDF2, TR-BDF2): 1 keeps a stiff mode's amplitude, 0 removes it
  // in one step. NaN: not stated.
  double spectral_radius_infinity = std::numeric_limits<double>::quiet_NaN();
  // The most the energy E = (v^2 + w^2 x^2)/2 of an undamped linear mode can
  // rise along one stable orbit, max E / E_0 over the worst starting phase,
  // as a function of w h below the stability limit. Empty: 1, a stable step
  // never raises it (a scalar map with |R(i w h)| <= 1). A symplectic method
  // conserves a nearby quadratic instead, so its energy swings: symplectic
  // Euler (1 + w h/2) / (1 - w h/2), the Newmark methods with gamma = 1/2
  // (Verlet, central difference, Fox-Goodwin, linear acceleration)
  // 1 / (1 - (w h / limit)^2) (Hairer, Lubich and Wanner, Geometric Numerical
  // Integration, I.5 and XIII.2: the conserved modified energy). The
  // stability search scales its blow-up threshold by it, so a bounded swing
  // near the limit is not taken for divergence.
  std::function<double(double)> energy_excursion = {};
};

// The property in words, e.g. "L-stable", "A(51.8 deg)-stable",
// "conditionally stable: w h <= 2.828 undamped", with the note appended.
std::string stability_text(const IntegratorInfo& info);

// info.energy_excursion at w h: 1 where it is not declared, and at or past
// the stability limit (where no orbit is bounded).
double energy_excursion(const IntegratorInfo& info, double wh);

// Whether every undamped mode is stable at every step (A- and L-stable).
inline bool stable_on_imaginary_axis(const IntegratorInfo& info) {
  return info.stability == StabilityKind::kA || info.stability == StabilityKind::kL;
}

class Integrator {
 public:
  virtual ~Integrator() = default;
  Integrator(const Integrator&) = delete;
  Integrator& operator=(const Integrator&) = delete;

  const IntegratorInfo& info() const { return info_; }
  const std::string& name() const { return info_.name; }
  // What the method claims when run with `options`, where they change it
  // (newmark's --beta and --gamma: --beta 0 is the central difference,
  // stable for w h <= 2); by default info().
  virtual IntegratorInfo info_for(const IntegratorOptions& options) const;

  // Option values this method cannot take on a system of `dofs` position
  // unknowns, checked before any run: empty when they are fine, otherwise
  // one line naming the option and what to use instead.
  virtual std::string check_options(const IntegratorOptions& options, Eigen::Index dofs) const;
  // The command-line options (without "--") this method reads, so a caller
  // can say which of the given ones it ignores.
  virtual std::vector<std::string> options_read() const;
  // Whether a run on `system` assembles its Jacobians, and so makes the
  // model build its pattern (Model builds it only when asked): the
  // memory estimate counts the pattern only then (issue 46.5). By default
  // the implicit methods that are not Jacobian-free.
  virtual bool assembles_jacobians(const MechanicalSystem& system) const;
  // Whether a step with these options factors the whole Newton matrix of
  // the system's Jacobian pattern, so that a caller can refuse a factor that
  // will not fit in memory before the run (factor_fit_error). By default
  // no; the velocity-implicit methods unless --solver quasi-newton (which
  // factors a matrix of a third of the unknowns).
  virtual bool factors_jacobian(const IntegratorOptions&) const { return false; }
  // The option that makes such a method factor no Jacobian of the model's
  // pattern, set in `options`, and how the refusal of a factor too large
  // names it ("--solver quasi-newton (...)"); "" when it has none.
  virtual std::string factor_free_option(IntegratorOptions& /*options*/) const { return {}; }
  // The substeps one step takes with these options, for a method that reads
  // --substeps (`run --json` reports it); 1 for the others.
  virtual int substeps(const IntegratorOptions&) const { return 1; }

  // Binds the integrator to `system` and sets the initial state. An
  // integrator serves one system for one run: its caches (a symbolic
  // factorization of the system's Jacobian pattern, a kept Newton matrix, the
  // last acceleration) belong to that system, so a second call fails (with a
  // StepResult, nothing changed); make a new integrator for the next run.
  StepResult initialize(const MechanicalSystem& system, double t0, const Vector& x0,
                        const Vector& v0, const IntegratorOptions& options);

  // Advances to t_out. A fixed-step method takes exactly one step of
  // h = t_out - t(); an adaptive one as many as it needs.
  virtual StepResult advance_to(double t_out);

  // The steps that fell back to a weaker variant of the method so far, one
  // entry per variant used (empty: none).
  virtual std::vector<FallbackCount> fallbacks() const { return {}; }
  // The method's overshoot (docs/command-line.md "Divergence"; the
  // Newmark-alpha family, Hilber and Hughes 1978): the most steps an
  // undamped stiff mode's energy can keep rising, at large w h, before the
  // method damps it, with the options it was initialized with; 0: its steps
  // do not overshoot.
  virtual int overshoot_steps() const { return 0; }

  double t() const { return t_; }
  const Vector& x() const { return x_; }
  const Vector& v() const { return v_; }
  const IntegratorStats& stats() const { return stats_; }

 protected:
  explicit Integrator(IntegratorInfo info) : info_(std::move(info)) {}

  // Hooks.
  virtual StepResult do_initialize() { return StepResult::success(); }
  virtual StepResult do_step(double h) = 0;  // fixed-step methods

  // Counted calls into the model.
  void eval_force(double t, const Vector& x, const Vector& v, Vector& f);
  // a = M^-1 F(t, x, v)
  void eval_acceleration(double t, const Vector& x, const Vector& v, Vector& a);
  void eval_jacobians(double t, const Vector& x, const Vector& v, SparseMatrix* dfdx,
                      SparseMatrix* dfdv);
  // The same, counted alike, of MechanicalSystem::definite_jacobians.
  void eval_definite_jacobians(double t, const Vector& x, const Vector& v, SparseMatrix* dfdx,
                               SparseMatrix* dfdv);

  // M^-1 as a vector, computed once in initialize(): methods that fuse the
  // acceleration into their own loop over the state multiply by it there.
  const Vector& inv_mass() const { return inv_mass_; }

  const MechanicalSystem& system() const { return *system_; }
  const IntegratorOptions& options() const { return options_; }
  IntegratorStats& mutable_stats() { return stats_; }

  // State, owned here so the driver and observers read it uniformly.
  double t_ = 0.0;
  Vector x_, v_;

 private:
  IntegratorInfo info_;
  const MechanicalSystem* system_ = nullptr;
  IntegratorOptions options_;
  IntegratorStats stats_;
  Vector inv_mass_;
};

}  // namespace springlab
