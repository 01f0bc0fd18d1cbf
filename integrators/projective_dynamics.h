// projective-dynamics — implicit Euler's step solved by local/global
// iterations (Liu, Bargteil, O'Brien and Kavan, "Fast simulation of
// mass-spring systems", SIGGRAPH Asia 2013; Bouaziz et al. 2014). Implicit
// Euler's positions minimize
//   g(x) = |x - y|_M^2 / (2 h^2) + sum_c k_c/2 |x_a - x_b - p_c|^2,
//   y = x_n + h v_n + h^2 M^-1 F_ext(t_n, x_n, v_n)
// over x and the springs' directions p_c (|p_c| = L_c). Starting from x = y,
// each of N iterations (--iterations, default 10)
//   local:   p_c = L_c (x_a - x_b) / |x_a - x_b|        (each spring alone)
//   global:  (M + h^2 L) x = M y + h^2 J p               (one linear solve
//            per coordinate; L = sum_c k_c (e_a - e_b)(e_a - e_b)^T)
// lowers g; then v = (x - x_n)/h. The matrix is the same for x, y and z and
// for every step of one h, so it is factored once (CHOLMOD, kept) and each
// iteration is three triangular solves. The external forces (gravity, drag,
// wind, spring damping) act explicitly through y. Not iterated to
// convergence: N fixed, so it is implicit Euler only approximately (exactly,
// after one iteration, on springs of rest length 0). Iterations count as
// newton_iterations.
#pragma once

#include "integrators/fast_solver.h"
#include "integrators/sparse_direct_solver.h"

namespace springlab {

class ProjectiveDynamics final : public FastSolver {
 public:
  ProjectiveDynamics();
  std::vector<std::string> options_read() const override { return {"iterations"}; }
  static constexpr int kDefaultIterations = 10;

 protected:
  StepResult do_initialize() override;
  StepResult do_step(double h) override;

 private:
  bool factor(double h, std::string& error);

  SparseMatrix laplacian_;  // L, free particles x free particles
  SparseDirectSolver solver_;
  double factored_h_ = 0.0;
  Vector f_, y_, x_new_, rhs_, coordinate_;
};

}  // namespace springlab
