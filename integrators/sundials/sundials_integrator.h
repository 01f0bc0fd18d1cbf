// What every SUNDIALS-backed method shares: the context and state vector,
// RAII ownership, counted callbacks into the model (so force_evals includes
// the evaluations SUNDIALS spends on difference quotients), the choice of
// linear solver, the checks of the options against the method, and one
// piece of code that configures, runs and reads the counters of all four
// packages (CVODE, IDA, ARKODE's ARKStep and ERKStep), through a table of
// each package's own calls (SundialsCalls).
//
// These methods are adaptive: advance_to(t_out) takes as many internal steps
// as the error control (--rtol, --atol) needs, and --dt is only the output
// interval. Each output time is a stop time (SetStopTime), so the reported
// state is a step of the solver, not an interpolation between two: ARKODE's
// interpolant in particular can be far less accurate than the tolerance.
//
// Work per output interval is bounded: at most --max-steps internal steps,
// by default kStepBudget / (2 n) for 2 n first-order unknowns (between 500
// and 100000), so a hopeless run fails in seconds, whatever the scene's
// size. A failed call ends the run as a result, with a message naming the
// call, quoting SUNDIALS and saying what to try.
#pragma once

#include <memory>
#include <vector>

#include "integrators/sundials/first_order_jacobian.h"
#include "integrators/sundials/reduced_newton_solver.h"
#include "integrators/core/integrator.h"
#include "integrators/sundials/sundials_support.h"

namespace springlab {

// Internal steps x first-order unknowns allowed per output interval when
// --max-steps is not given (about 1-10 s of the slowest method).
inline constexpr double kStepBudget = 5e6;
inline constexpr long kMinStepLimit = 500, kMaxStepLimit = 100000;
// The largest Newton matrix --linear-solver dense builds (first-order
// unknowns): SUNDIALS' dense LU of 1000 x 1000 takes about 0.3 s, of
// 2000 x 2000 about 3 s, at every Jacobian update.
inline constexpr long kMaxDenseUnknowns = 1000;
// The smallest --rtol: double precision's unit roundoff, below which
// SUNDIALS stops with "too much accuracy requested".
inline constexpr double kMinRelativeTolerance = 2.220446049250313e-16;

// The steps one output interval may take (--max-steps, or scaled).
long sundials_step_limit(const IntegratorOptions& options, Eigen::Index first_order_unknowns);

// One package's calls, each a plain function of its solver memory (void*).
// A null entry: the package has no such call.
struct SundialsCalls {
  const char* prefix;       // "CVode", "IDA", "ARKStep", "ERKStep": calls are named prefix + suffix
  const char* evolve_call;  // for messages: "CVode", "IDASolve", "ARKStepEvolve", ...
  const char* order_call;   // "SetMaxOrd" or "SetOrder"
  int (*set_error_handler)(void*, void (*)(int, const char*, const char*, char*, void*), void*);
  int (*set_tolerances)(void*, double rtol, double atol);
  int (*set_user_data)(void*, void*);
  int (*set_max_steps)(void*, long);
  int (*set_order)(void*, int);
  int (*set_stop_time)(void*, double);
  // Integrates to t_out (normal mode); yp is IDA's y' (unused by the others).
  int (*evolve)(void* memory, double t_out, N_Vector y, N_Vector yp, double* t_reached);
  int (*set_linear_solver)(void*, SUNLinearSolver, SUNMatrix);
  int (*get_steps)(void*, long*);
  int (*get_error_test_fails)(void*, long*);
  int (*get_nonlinear_iterations)(void*, long*);
  int (*get_nonlinear_failures)(void*, long*);
  int (*get_linear_setups)(void*, long*);
  int (*get_jacobian_evals)(void*, long*);
};

// What a method built on a package takes.
struct SundialsMethod {
  std::vector<int> orders;  // the --max-order values it accepts
  const char* order_meaning;  // "its highest BDF order", "the order of its Runge-Kutta table"
  bool newton_matrix = false;  // solves with a Newton matrix (--linear-solver, --dq-jacobian)
  bool stald = false;          // takes --stald
};

class SundialsIntegrator : public Integrator {
 public:
  StepResult advance_to(double t_out) final;
  std::string check_options(const IntegratorOptions& options, Eigen::Index dofs) const override;
  std::vector<std::string> options_read() const override;
  // The reduced solver factors M - gamma D - gamma^2 K on the model's
  // pattern (auto's choice above 100 unknowns; below, the dense matrix is
  // small), so the memory rule for such a factor applies to it.
  bool factors_jacobian(const IntegratorOptions& options) const override {
    return method_.newton_matrix &&
           (options.linear_solver == "reduced" || options.linear_solver == "auto");
  }
  std::string factor_free_option(IntegratorOptions& options) const override {
    options.linear_solver = "gmres";
    return "--linear-solver gmres (it factors nothing)";
  }

 protected:
  SundialsIntegrator(IntegratorInfo info, const SundialsCalls& calls, SundialsMethod method);
  ~SundialsIntegrator() override;

  enum class LinearSolverKind { kNone, kDense, kKlu, kGmres, kReduced };

  // Hooks for each package. create() makes the solver memory for the
  // current state (first adopt(), then the package's Init), throwing
  // sundials::Failure; configure() then sets what every package shares.
  // attach_jacobian() gives the Newton matrix's callbacks to the package
  // (matrix-free: the J v products for GMRES).
  virtual void create() = 0;
  virtual void attach_jacobian(bool matrix_free) = 0;
  // Takes ownership of the package's memory and routes its errors to log_.
  void adopt(void* memory, sundials::SolverMemory::FreeFn free_fn);

  // --linear-solver, resolved ("auto": dense up to 100 unknowns, the reduced
  // solver above: reduced_newton_solver.h).
  LinearSolverKind linear_solver_kind() const;
  static LinearSolverKind linear_solver_kind(const std::string& choice, Eigen::Index unknowns);

  // y = (x, v) <-> the base's x_, v_.
  void state_to_vector(N_Vector y) const;
  void vector_to_state(N_Vector y);

  // f(t, y) = (v, M^-1 F_part) or, for an IMEX non-stiff part, (0, M^-1 F_part).
  int evaluate_rhs(ForcePart part, bool with_velocity, double t, N_Vector y, N_Vector ydot);
  // dF/dx, dF/dv of `part` at y, into dfdx_, dfdv_.
  void evaluate_jacobians(ForcePart part, double t, N_Vector y);
  // True when a stop was requested (options().stop): a callback returns an
  // unrecoverable failure, and the run ends at once.
  bool stop_requested() const;

  // Callbacks with user_data = this, for the ODE form (CVODE, ARKODE).
  static int ode_rhs(double t, N_Vector y, N_Vector ydot, void* self);
  static int ode_jacobian(double t, N_Vector y, N_Vector fy, SUNMatrix J, void* self, N_Vector,
                          N_Vector, N_Vector);
  static int ode_jtimes_setup(double t, N_Vector y, N_Vector fy, void* self);
  static int ode_jtimes(N_Vector v, N_Vector Jv, double t, N_Vector y, N_Vector fy, void* self,
                        N_Vector);

  Eigen::Index n() const { return system().dofs(); }
  void* memory() const { return memory_.get(); }

  sundials::ContextPtr context_;
  sundials::VectorPtr y_;
  sundials::VectorPtr yp_;  // IDA's y'
  sundials::NonlinearSolverPtr nonlinear_solver_;  // cvode-adams' fixed-point iteration
  sundials::ErrorLog log_;
  std::unique_ptr<sundials::FirstOrderJacobian> jacobian_;
  SparseMatrix dfdx_, dfdv_;
  sundials::ReducedSystem reduced_;  // what --linear-solver reduced reads
  ForcePart implicit_part_ = ForcePart::kAll;  // what the Newton matrix differentiates

 private:
  StepResult do_initialize() final;
  StepResult do_step(double) final;
  void configure();
  void create_linear_solver(LinearSolverKind kind);
  void read_counters(IntegratorStats& stats);
  std::string call(const char* suffix) const { return std::string(calls_.prefix) + suffix; }

  const SundialsCalls& calls_;
  SundialsMethod method_;
  sundials::MatrixPtr matrix_;
  sundials::LinearSolverPtr linear_solver_;
  sundials::SolverMemory memory_;  // declared last of the SUNDIALS objects: freed first
  long analytic_jacobians_ = 0;  // through our callbacks
  long step_limit_ = 0;          // internal steps per output interval
  Vector x_scratch_, v_scratch_, f_scratch_;
};

}  // namespace springlab
