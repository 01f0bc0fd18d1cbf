// ida — SUNDIALS IDA, variable-order (1-5) variable-step BDF on the
// residual (implicit DAE) form of the equations of motion:
//
//   R(t, y, y') = ( x' - v ,  M v' - F(t, x, v) ) = 0,    y = (x, v)
//
// with consistent initial y'(0) = (v0, M^-1 F(0, x0, v0)) computed from the
// forces. Each step's Newton iteration uses G = dR/dy + cj dR/dy'
// = [[cj I, -I], [-dF/dx, cj M - dF/dv]] from the model's analytic
// Jacobians (dense, KLU, or GMRES with G v products; --dq-jacobian lets IDA
// difference R). The mass matrix stays on the left, never inverted: the form
// a constrained or singular-mass model would need. Error control as CVODE
// (--rtol, --atol); stability as BDF: orders 1-2 A-stable.
#pragma once

#include "integrators/sundials/sundials_integrator.h"

namespace springlab {

class IdaIntegrator final : public SundialsIntegrator {
 public:
  IdaIntegrator();

 protected:
  void create() override;
  void attach_jacobian(bool matrix_free) override;

 private:
  static const SundialsCalls& calls();
  static int residual(double t, N_Vector y, N_Vector yp, N_Vector r, void* self);
  static int jacobian(double t, double cj, N_Vector y, N_Vector yp, N_Vector r, SUNMatrix G,
                      void* self, N_Vector, N_Vector, N_Vector);
  static int jtimes_setup(double t, N_Vector y, N_Vector yp, N_Vector r, double cj, void* self);
  static int jtimes(double t, N_Vector y, N_Vector yp, N_Vector r, N_Vector v, N_Vector Gv,
                    double cj, void* self, N_Vector, N_Vector);

  Vector force_;
};

}  // namespace springlab
