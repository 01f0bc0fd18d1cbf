// Four methods with a mistake each, as a student might make them, for the
// test that `springlab check` names the claim each one breaks
// (tests/check_test.cmake, docs/your-own-integrator.md "Checking it").
// Each declares the claims of the method it means to be.
#include "integrators/core/your_integrator.h"

using namespace springlab;

// Velocity Verlet whose closing half-kick reuses the old acceleration:
// v' = v + h a(x_n) instead of v + h/2 (a(x_n) + a(x_{n+1})). First order,
// and it gains energy: breaks --order 2.
class WrongHalfKickVerlet final : public Integrator {
 public:
  WrongHalfKickVerlet()
      : Integrator({.name = "wrong-half-kick-verlet", .scheme = "Verlet, closing kick at x_n",
                    .order = 2, .symplectic = true, .stability = StabilityKind::kConditional,
                    .stability_limit = 2.0}) {}

 protected:
  StepResult do_step(double h) override {
    eval_acceleration(t_, x_, v_, a_);
    v_ += 0.5 * h * a_;
    x_ += h * v_;
    v_ += 0.5 * h * a_;  // the mistake: a(x_n), not a(x_{n+1})
    return StepResult::success();
  }

 private:
  Vector a_;
};

// "Implicit" Euler that evaluates the force at the start of the step:
// v' = v + h M^-1 F(x_n, v_n), x' = x + h v' (symplectic Euler in
// disguise). Stable only for w h <= 2: breaks --a-stable.
class ExplicitForceImplicitEuler final : public Integrator {
 public:
  ExplicitForceImplicitEuler()
      : Integrator({.name = "explicit-force-implicit-euler", .scheme = "backward Euler, F at t_n",
                    .order = 1, .implicit = true, .stability = StabilityKind::kL,
                    .stability_limit = kInfinity}) {}

 protected:
  StepResult do_step(double h) override {
    eval_acceleration(t_, x_, v_, a_);  // the mistake: F(t_n, x_n, v_n)
    v_ += h * a_;
    x_ += h * v_;
    return StepResult::success();
  }

 private:
  Vector a_;
};

// Classic RK4 on y' = f(y), y = (x, v), with the weights 1, 2, 1, 2 (of 6)
// instead of 1, 2, 2, 1: no longer fourth order: breaks --order 4.
class WrongWeightRk4 final : public Integrator {
 public:
  WrongWeightRk4()
      : Integrator({.name = "wrong-weight-rk4", .scheme = "RK4, weights 1 2 1 2", .order = 4,
                    .stability = StabilityKind::kConditional, .stability_limit = 2.8284271247461903}) {}

 protected:
  StepResult do_step(double h) override {
    const double t = t_;
    eval_acceleration(t, x_, v_, a1_);
    const Vector x1 = x_, v1 = v_;
    const Vector x2 = x_ + 0.5 * h * v1, v2 = v_ + 0.5 * h * a1_;
    eval_acceleration(t + 0.5 * h, x2, v2, a2_);
    const Vector x3 = x_ + 0.5 * h * v2, v3 = v_ + 0.5 * h * a2_;
    eval_acceleration(t + 0.5 * h, x3, v3, a3_);
    const Vector x4 = x_ + h * v3, v4 = v_ + h * a3_;
    eval_acceleration(t + h, x4, v4, a4_);
    // The mistake: (k1 + 2 k2 + k3 + 2 k4) / 6.
    x_ += h / 6.0 * (v1 + 2.0 * v2 + v3 + 2.0 * v4);
    v_ += h / 6.0 * (a1_ + 2.0 * a2_ + a3_ + 2.0 * a4_);
    return StepResult::success();
  }

 private:
  Vector a1_, a2_, a3_, a4_;
};

// Heun's method (explicit trapezoid, second order) declared symplectic: it
// is not (|R(i y)|^2 = 1 + y^4/4 > 1, the energy creeps up): breaks
// --symplectic while its --order 2 holds.
class NotSymplecticHeun final : public Integrator {
 public:
  NotSymplecticHeun()
      : Integrator({.name = "not-symplectic-heun", .scheme = "Heun's method", .order = 2,
                    .symplectic = true}) {}

 protected:
  StepResult do_step(double h) override {
    eval_acceleration(t_, x_, v_, a1_);
    const Vector xp = x_ + h * v_, vp = v_ + h * a1_;
    eval_acceleration(t_ + h, xp, vp, a2_);
    x_ += 0.5 * h * (v_ + vp);
    v_ += 0.5 * h * (a1_ + a2_);
    return StepResult::success();
  }

 private:
  Vector a1_, a2_;
};

SPRINGLAB_PLUGIN_INTEGRATOR(WrongHalfKickVerlet)
SPRINGLAB_PLUGIN_INTEGRATOR(ExplicitForceImplicitEuler)
SPRINGLAB_PLUGIN_INTEGRATOR(WrongWeightRk4)
SPRINGLAB_PLUGIN_INTEGRATOR(NotSymplecticHeun)
