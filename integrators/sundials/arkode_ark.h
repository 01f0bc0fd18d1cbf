// arkode-dirk and arkode-imex — SUNDIALS ARKODE's ARKStep, adaptive
// additive Runge-Kutta methods on y = (x, v).
//
// arkode-dirk: diagonally implicit RK (default order 4, SDIRK 5-3-4; L-stable),
//   y' = f(t, y) entirely implicit. Each stage solves a Newton system with
//   I - h a_ii J, J from the model's analytic Jacobian (dense / KLU / GMRES,
//   as cvode-bdf), or difference quotients with --dq-jacobian.
// arkode-imex: additive (IMEX) RK (default order 4, ARK4(3)6L): the stiff
//   part f_I = (v, M^-1 F_stiff) — springs, spring damping, drag — implicit,
//   the non-stiff part f_E = (0, M^-1 F_nonstiff) — gravity, wind — explicit,
//   so the Newton matrix involves only the stiff forces' Jacobian.
//
// --max-order picks ARKODE's default table of that order (arkode-dirk 2-5;
// arkode-imex 3-5: ARKODE has no order-2 IMEX table and would use order 3).
// Error control as CVODE (--rtol, --atol); --dt is the output interval.
#pragma once

#include "integrators/sundials/sundials_integrator.h"

namespace springlab {

class ArkodeArk : public SundialsIntegrator {
 protected:
  ArkodeArk(bool imex, IntegratorInfo info, SundialsMethod method);
  void create() override;
  void attach_jacobian(bool matrix_free) override;

 private:
  static const SundialsCalls& calls();
  static int explicit_rhs(double t, N_Vector y, N_Vector ydot, void* self);
  bool imex_;
};

class ArkodeDirk final : public ArkodeArk {
 public:
  ArkodeDirk();
};

class ArkodeImex final : public ArkodeArk {
 public:
  ArkodeImex();
};

}  // namespace springlab
