// What every SUNDIALS-backed method shares: the context and state vector,
// RAII ownership, counted callbacks into the model (so force_evals includes
// the evaluations SUNDIALS spends on difference quotients), the choice of
// linear solver, and the mapping of SUNDIALS' counters onto SPEC's names.
//
// These methods are adaptive: advance_to(t_out) takes as many internal steps
// as the error control (--rtol, --atol) needs, and --dt is only the output
// interval. Each output time is a stop time, so the reported state is a
// solver step, not an interpolation. A failed call ends the run with a
// message naming it, as a result.
#pragma once

#include <memory>

#include "integrators/first_order_jacobian.h"
#include "integrators/integrator.h"
#include "integrators/sundials_support.h"

namespace springlab {

class SundialsIntegrator : public Integrator {
 public:
  StepResult advance_to(double t_out) final;

 protected:
  explicit SundialsIntegrator(IntegratorInfo info);
  ~SundialsIntegrator() override;

  enum class LinearSolverKind { kNone, kDense, kKlu, kGmres };

  // Hooks for each solver family. create() builds the solver memory for the
  // current state (throwing sundials::Failure); solve() integrates to t_out
  // and returns the solver's flag; read_counters() fills the statistics.
  virtual void create() = 0;
  virtual int solve(double t_out, double& t_reached) = 0;
  virtual void read_counters(IntegratorStats& stats) const = 0;
  virtual const char* solve_call() const = 0;

  // --linear-solver, resolved ("auto": dense up to 100 unknowns, KLU above).
  LinearSolverKind linear_solver_kind() const;
  // Creates matrix_ and linear_solver_ of that kind for 2n unknowns.
  void create_linear_solver(LinearSolverKind kind);
  const char* linear_solver_name(LinearSolverKind kind) const;

  // y = (x, v) <-> the base's x_, v_.
  void state_to_vector(N_Vector y) const;
  void vector_to_state(N_Vector y);

  // f(t, y) = (v, M^-1 F_part) or, for an IMEX non-stiff part, (0, M^-1 F_part).
  int evaluate_rhs(ForcePart part, bool with_velocity, double t, N_Vector y, N_Vector ydot);
  // dF/dx, dF/dv of `part` at y, into dfdx_, dfdv_.
  void evaluate_jacobians(ForcePart part, double t, N_Vector y);

  // Callbacks with user_data = this, for the ODE form (CVODE, ARKODE).
  static int ode_rhs(double t, N_Vector y, N_Vector ydot, void* self);
  static int ode_jacobian(double t, N_Vector y, N_Vector fy, SUNMatrix J, void* self, N_Vector,
                          N_Vector, N_Vector);
  static int ode_jtimes_setup(double t, N_Vector y, N_Vector fy, void* self);
  static int ode_jtimes(N_Vector v, N_Vector Jv, double t, N_Vector y, N_Vector fy, void* self,
                        N_Vector);

  Eigen::Index n() const { return system().dofs(); }

  sundials::ContextPtr context_;
  sundials::VectorPtr y_;
  sundials::MatrixPtr matrix_;
  sundials::LinearSolverPtr linear_solver_;
  sundials::NonlinearSolverPtr nonlinear_solver_;
  sundials::SolverMemory memory_;
  sundials::ErrorLog log_;
  std::unique_ptr<sundials::FirstOrderJacobian> jacobian_;
  SparseMatrix dfdx_, dfdv_;
  ForcePart implicit_part_ = ForcePart::kAll;  // what the Newton matrix differentiates
  long analytic_jacobians_ = 0;                // through our callbacks
  long difference_quotient_jacobians_ = 0;     // SUNDIALS' own, with --dq-jacobian

 private:
  StepResult do_initialize() final;
  StepResult do_step(double) final;

  Vector x_scratch_, v_scratch_, f_scratch_;
};

}  // namespace springlab
