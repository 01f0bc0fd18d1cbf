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
//            per coordinate; L = sum_c k_c (e_a - e_b)(e_a - e_b)^T;
//            with drag, h D and h D (x_n + h v_n) more: below)
// lowers g; then v = (x - x_n)/h. The matrix is the same for x, y and z and
// for every step of one h, so it is factored once (CHOLMOD, kept) and each
// iteration is one solve with the three coordinates as three columns. The
// other external forces (gravity, wind, spring damping) act explicitly
// through y, except their part -D v with D diagonal and the same for each
// coordinate of a particle (drag's gamma, wind's coefficient), which is
// implicit (below). Not iterated to convergence: N fixed, so it is implicit
// Euler only approximately (exactly, after one iteration, on springs of rest
// length 0). Iterations count as newton_iterations.
//
// The implicit -D v. Implicit Euler's step with x' = x_n + h v',
//   M (x' - x_n - h v_n) / h^2 = F_e(t_n, x_n, v_n) - D v' - grad E(x'),
// where F_e is the rest of the external forces. y above uses the external
// force, which holds -D v_n: y = x_n + h v_n + h^2 M^-1 (F_e - D v_n). Then
// M (x' - y) / h^2 = -D (v' - v_n) - grad E(x'), and with
// v' - v_n = (x' - x_n - h v_n) / h, times h^2:
//   (M + h D + h^2 L) x' = M y + h D (x_n + h v_n) + h^2 J p,
// the minimum over x' of g(x) + |x - x_n - h v_n|_D^2 / (2 h): the matrix
// gains h D (the same for every coordinate, and for every step of one h),
// the right-hand side h D (x_n + h v_n), computed once per step. Converged,
// the iterations give implicit Euler's step on a scene with drag too
// (tests/test_fast_solvers.cc). D is read once, at the start, from the
// system's dF/dv (MechanicalSystem::jacobians) where the system's velocity
// dependence is diagonal (MechanicalSystem::velocity_dependence): the
// coefficients of drag and wind are constants. (A time-varying wind's
// w(t) stays in F_e at t_n: there the converged step differs from implicit
// Euler's, which takes it at t_n+1, by h^2 M^-1 c (w(t_n+1) - w(t_n)).)
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

#include "integrators/fast/fast_solver.h"
#include "integrators/linear/sparse_direct_solver.h"

namespace springlab {

class ProjectiveDynamics final : public FastSolver {
 public:
  ProjectiveDynamics();
  std::vector<std::string> options_read() const override {
    return {"iterations", "chebyshev", "no-chebyshev"};
  }
  // --chebyshev without RHO: projective dynamics has no rho of its own.
  std::string check_options(const IntegratorOptions& options, Eigen::Index dofs) const override;
  // It reads dF/dv once where the damping is diagonal (read_linear_damping).
  bool assembles_jacobians(const MechanicalSystem& system) const override {
    return system.velocity_dependence() == VelocityDependence::kDiagonal;
  }
  static constexpr int kDefaultIterations = 10;

  // A distance constraint as the local step reads it, in 24 bytes: b < 0
  // stands for the anchor -1 - b.
  struct LocalSpring {
    int a = 0, b = 0;
    double stiffness = 0.0, length = 0.0;
  };

 protected:
  StepResult do_initialize() override;
  StepResult do_step(double h) override;

 private:
  // The pieces of a step (do_step): y and the contact set, the matrix's
  // factor, the right-hand side's part that stays over the iterations, the
  // local steps into the right-hand side, the global solve, the Chebyshev
  // extrapolation.
  void predict(double h);
  // damping_: D from dF/dv where the velocity dependence is diagonal.
  void read_linear_damping();
  bool factor(double h, std::string& error);
  void begin_right_hand_side(double h);
  void add_spring_projections(double h);
  void add_element_projections(double h);
  void add_contact_projections(double h);
  bool global_solve();
  void extrapolate(int iteration, double rho, double& omega);
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

  std::vector<LocalSpring> springs_;  // constraints_, in their order
  std::vector<Eigen::Vector3d> anchors_;
  SparseMatrix laplacian_;  // L, free particles x free particles
  SparseDirectSolver solver_{FactorUse::kSolvedOften};
  double factored_h_ = 0.0;
  Vector damping_;  // D per particle (read_linear_damping); empty: none
  // y; x'; the right-hand side, and its part M y + h D (x_n + h v_n)
  Vector f_, y_, x_new_, rhs_, rhs_start_;
  Eigen::MatrixXd columns_, solved_;  // n x dim: one coordinate per column
  Vector x_before_, x_last_;  // Chebyshev: the iterates k - 1 and k
};

}  // namespace springlab
