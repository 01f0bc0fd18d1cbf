// cvode-bdf and cvode-adams — SUNDIALS CVODE, variable order and step, on the
// first-order system y = (x, v), y' = (v, M^-1 F(t, x, v)).
//
// cvode-bdf: backward differentiation formulas, orders 1-5 (--max-order).
//   Each step solves y_n = sum a_j y_{n-j} + h b0 f(t_n, y_n) by Newton with
//   the matrix I - h b0 J, J = df/dy from the model's analytic dF/dx, dF/dv
//   (first_order_jacobian.h): dense, KLU sparse, or matrix-free GMRES with
//   J v products (--linear-solver); --dq-jacobian lets CVODE difference f
//   instead. Orders 1-2 are A-stable; orders 3-5 are not near the imaginary
//   axis, which is where undamped springs live: --stald turns on CVODE's
//   stability limit detection, which lowers the order when it sees that.
// cvode-adams: Adams-Moulton, orders 1-12, for non-stiff problems; its
//   implicit formula is solved by fixed-point iteration (no Jacobian), so on
//   stiff springs its steps shrink to the explicit stability limit.
//
// Both control the local error to --rtol, --atol per component; --dt is the
// output interval only. Reference: Hindmarsh et al., "SUNDIALS", ACM TOMS 2005.
#pragma once

#include "integrators/sundials/sundials_integrator.h"

namespace springlab {

class CvodeIntegrator : public SundialsIntegrator {
 protected:
  CvodeIntegrator(int multistep_method, IntegratorInfo info, SundialsMethod method);
  void create() override;
  void attach_jacobian(bool matrix_free) override;

 private:
  static const SundialsCalls& calls();
  int multistep_method_;
};

class CvodeBdf final : public CvodeIntegrator {
 public:
  CvodeBdf();
};

class CvodeAdams final : public CvodeIntegrator {
 public:
  CvodeAdams();
};

}  // namespace springlab
