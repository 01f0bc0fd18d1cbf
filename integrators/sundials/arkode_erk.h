// arkode-erk — SUNDIALS ARKODE's ERKStep: an adaptive explicit Runge-Kutta
// method (default: the order-4 Zonneveld pair with an embedded order-3 error
// estimate; --max-order 2..8 picks ARKODE's default table of that order) on
// y = (x, v), y' = (v, M^-1 F(t, x, v)).
//
// Error control as CVODE (--rtol, --atol). Being explicit, its steps cannot
// exceed its stability region: on stiff springs the controller keeps the
// step near the stability limit (~2.8/w_max for order 4) whatever the
// tolerance, which is what makes stiffness visible as cost.
#pragma once

#include "integrators/sundials/sundials_integrator.h"

namespace springlab {

class ArkodeErk final : public SundialsIntegrator {
 public:
  ArkodeErk();

 protected:
  void create() override;
  void attach_jacobian(bool) override {}  // explicit: no Newton matrix

 private:
  static const SundialsCalls& calls();
};

}  // namespace springlab
