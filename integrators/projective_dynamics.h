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
// iteration is one solve with the three coordinates as three columns. The external forces (gravity, drag,
// wind, spring damping) act explicitly through y. Not iterated to
// convergence: N fixed, so it is implicit Euler only approximately (exactly,
// after one iteration, on springs of rest length 0). Iterations count as
// newton_iterations.
//
// Chebyshev acceleration (--chebyshev RHO; Wang, "A Chebyshev semi-iterative
// approach for accelerating projective and position-based dynamics", ACM
// TOG 2015): each global solve's result xh is extrapolated from the iterate
// before the last, x^(k+1) = w_(k+1) (xh - x^(k-1)) + x^(k-1), with
// w_1 = 1, w_2 = 2 / (2 - rho^2), w_(k+1) = 4 / (4 - rho^2 w_k); rho is the
// plain iteration's spectral radius (its error shrinks by rho per
// iteration), estimated by the user (docs/integrators.md "Fast solvers": watch the
// solver error fall with --iterations). Too large a rho makes the iterates
// overshoot; 0 (the default) turns it off.
//
// Contact planes (penalty only; the barrier is refused): the penalty
// k_c/2 min(d, 0)^2 is k_c/2 |x_i - P(x_i)|^2 with P the projection onto the
// half-space, a projective constraint (Bouaziz et al. 2014) whose local step
// is P and whose matrix term is k_c on particle i's diagonal -- the same for
// every coordinate, so one factor still serves x, y and z. It enters the
// matrix only for the pairs (particle, plane) in contact at the step's start
// or at y: the matrix is factored again whenever that set changes. Coulomb
// friction, with f_n = k_c (-d) at the new positions: static, the step's
// tangential displacement is undone where that takes at most mu f_n (force
// |dx_t| m / h^2); dynamic, v_t loses min(h mu f_n / m, |v_t|) (as in xpbd.h,
// Mueller et al. 2020): exact Coulomb friction, without the smoothing.
#pragma once

#include "integrators/fast_solver.h"
#include "integrators/sparse_direct_solver.h"

namespace springlab {

class ProjectiveDynamics final : public FastSolver {
 public:
  ProjectiveDynamics();
  std::vector<std::string> options_read() const override {
    return {"iterations", "chebyshev"};
  }
  static constexpr int kDefaultIterations = 10;

 protected:
  StepResult do_initialize() override;
  StepResult do_step(double h) override;

 private:
  bool factor(double h, std::string& error);
  // The (particle, plane) pairs in contact at x_n or at y; true when they
  // changed (the matrix must be factored again).
  bool update_contacts();
  // Friction of the planes on (x_, x_new_, v_) after the iterations.
  void apply_friction(double h);

  struct ContactPair {
    Eigen::Index particle;
    std::size_t plane;
    bool operator==(const ContactPair&) const = default;
  };
  std::vector<ContactPair> contacts_;

  SparseMatrix laplacian_;  // L, free particles x free particles
  SparseDirectSolver solver_{FactorUse::kSolvedOften};
  double factored_h_ = 0.0;
  Vector f_, y_, x_new_, rhs_;
  Eigen::MatrixXd columns_, solved_;  // n x dim: one coordinate per column
  Vector x_before_, x_last_;  // Chebyshev: the iterates k - 1 and k
};

}  // namespace springlab
