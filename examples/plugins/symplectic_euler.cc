// A symplectic Euler of your own, as a plug-in (docs/your-own-integrator.md):
//
//   v_{n+1} = v_n + h M^-1 F(t_n, x_n, v_n),   x_{n+1} = x_n + h v_{n+1}
//
//   springlab run cloth --plugin ./libmy_methods.so --integrator my-symplectic-euler
#include "integrators/core/your_integrator.h"

using namespace springlab;

class MySymplecticEuler final : public Integrator {
 public:
  // What `springlab check` holds the method to: order 1, symplectic,
  // stable for w h <= 2 on the undamped oscillator.
  MySymplecticEuler()
      : Integrator({.name = "my-symplectic-euler",
                    .scheme = "v' = v + h M^-1 F(t, x, v),  x' = x + h v'",
                    .order = 1,
                    .symplectic = true,
                    .stability = StabilityKind::kConditional,
                    .stability_limit = 2.0}) {}

 protected:
  StepResult do_step(double h) override {
    eval_acceleration(t_, x_, v_, a_);  // a = M^-1 F(t_n, x_n, v_n)
    v_ += h * a_;                       // kick with the old force
    x_ += h * v_;                       // drift with the new velocity
    return StepResult::success();
  }

 private:
  Vector a_;
};

SPRINGLAB_PLUGIN_INTEGRATOR(MySymplecticEuler)
