// An implicit (backward) Euler of your own, with its own Newton loop, as a
// plug-in (docs/your-own-integrator.md):
//
//   v_{n+1} = v_n + h M^-1 F(t_{n+1}, x_n + h v_{n+1}, v_{n+1}),
//   x_{n+1} = x_n + h v_{n+1}.
//
// Newton on the velocity: the residual and its matrix
//
//   r(v) = M (v - v_n) - h F(t_{n+1}, x_n + h v, v),
//   A(v) = dr/dv = M - h D - h^2 K,   K = dF/dx, D = dF/dv,
//
// and the update A dv = -r until |dv|_inf <= --newton-tol. With the
// definite Jacobians A is positive definite, and dv descends the step's
// incremental potential |v - v_n|^2_M / 2 + V(x_n + h v) + h W(v).
//
//   springlab run cloth --plugin ./libmy_methods.so --integrator my-implicit-euler
#include "integrators/core/your_integrator.h"
#include "integrators/linear/sparse_direct_solver.h"

using namespace springlab;

class MyImplicitEuler final : public Integrator {
 public:
  MyImplicitEuler()
      : Integrator({.name = "my-implicit-euler",
                    .scheme = "v' = v + h M^-1 F(t + h, x + h v', v'), x' = x + h v' (Newton)",
                    .order = 1,
                    .implicit = true,
                    .iterates_to_tolerance = true,
                    .stability = StabilityKind::kL,
                    .stability_limit = kInfinity}) {}

 protected:
  StepResult do_step(double h) override {
    const double t1 = t_ + h;
    const Vector& m = system().mass();
    v1_ = v_;  // Newton starts from v_n
    for (int k = 0; k < options().max_newton; ++k) {
      ++mutable_stats().newton_iterations;
      // 1. The residual at v1.
      x1_ = x_ + h * v1_;
      eval_force(t1, x1_, v1_, f_);
      r_ = m.cwiseProduct(v1_ - v_) - h * f_;
      // 2. Its matrix M - h D - h^2 K.
      eval_definite_jacobians(t1, x1_, v1_, &K_, &D_);
      A_ = (-h * h) * K_ + (-h) * D_;
      A_.diagonal() += m;
      // 3. The update: A dv = -r.
      ++mutable_stats().factorizations;
      if (!solver_.factorize(A_, MatrixKind::kPositiveDefinite)) {
        return StepResult::failure(name() + ": " + solver_.error());
      }
      ++mutable_stats().linear_solves;
      if (!solver_.solve(-r_, dv_)) {
        return StepResult::failure(name() + ": the Newton update is not finite: try a smaller --dt");
      }
      v1_ += dv_;
      // 4. Converged when the update is below the tolerance (m/s).
      if (dv_.lpNorm<Eigen::Infinity>() <= options().newton_tol) {
        v_ = v1_;
        x_ += h * v_;
        return StepResult::success();
      }
    }
    ++mutable_stats().nonlinear_failures;
    return StepResult::failure(name() + ": Newton did not converge in --max-newton " +
                               std::to_string(options().max_newton) +
                               " iterations: try a smaller --dt");
  }

 private:
  Vector v1_, x1_, f_, r_, dv_;
  SparseMatrix K_, D_, A_;
  SparseDirectSolver solver_;
};

SPRINGLAB_PLUGIN_INTEGRATOR(MyImplicitEuler)
