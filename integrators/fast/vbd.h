// vbd — vertex block descent (Chen, Macklin, Yang, Thaler, Guan, Xu and
// Xu, "Vertex Block Descent", ACM TOG 43(4), SIGGRAPH 2024): implicit
// Euler's step found by minimizing its incremental potential one particle
// at a time. Implicit Euler's positions minimize
//
//   G(x) = sum_i m_i / (2 h^2) |x_i - y_i|^2 + E(x) + h W((x - x_n) / h),
//   y_i = x_n,i + h v_n,i,
//
// E the stored energies (springs, elements, gravity, contact), W the
// dissipation potential of drag, wind and (lagged) friction. Holding every
// other particle, G restricted to particle i, G_i(x_i), has the gradient
// and Hessian (VertexBlockView, models/core/vertex_blocks.h)
//
//   g_i = m_i / h^2 (x_i - y_i) - F_i(t + h, x, v),   v = (x - x_n) / h,
//   H_i = m_i / h^2 I - dF_i/dx_i - dF_i/dv_i / h,
//
// and one iteration takes, for every particle in turn, the 3 x 3 Newton step
//
//   x_i <- x_i - H_i^-1 g_i                              (the paper's eq. 4-6)
//
// from the positions the particles before it left (Gauss-Seidel). The
// particles are coloured so that no two of one colour share an element
// (vertex_colouring.h, once per Jacobian pattern): a colour's particles
// are independent and are updated from the same positions, colour after
// colour (what the paper runs in parallel on a GPU; here in one thread).
// Each step of h is S substeps of h/S (--substeps, default 1), each N
// iterations (--iterations, default 10), then v = (x - x_n) / h.
//
// The local step stays a descent step no longer than the inertia allows:
// H_i is used where its symmetric part is positive definite (a Cholesky
// factor exists) and its step is no longer than |g_i| h^2 / m_i, the
// longest a definite H_i >= m_i / h^2 I can take; where it is not (a
// compressed spring's negative transverse stiffness outweighs the inertia,
// or nearly cancels it), the particle's blocks are evaluated again with
// each element's share made semidefinite (VertexBlockView's `definite`:
// projection on demand, per particle), which leaves H_i >= m_i / h^2 I. With a barrier
// (contact planes, IPC) or a material without energy at J <= 0
// (neo-Hookean), the step is capped at kStepCap = 0.9 of the fraction at
// which particle i alone would close a gap or invert an element (IPC's
// step cap, Li et al. 2020, applied per particle).
//
// Initial guess (the paper's sec. 3.7, "adaptive"): x = x_n + h v_n +
// h^2 a~ with a~_i = a_ext,i clamp(a_n,i . a_ext,i / |a_ext,i|^2, 0, 1),
// a_ext the constant forces' acceleration (gravity) and a_n = (v_n -
// v_n-1) / h the last step's; a_ext itself at the first step.
//
// Chebyshev acceleration (the paper's sec. 3.8, Wang 2015) across
// iterations, as in projective dynamics: after iteration k's sweep gives
// x^, x^(k+1) = w_(k+1) (x^ - x^(k-1)) + x^(k-1), w_1 = 1,
// w_2 = 2 / (2 - rho^2), w_(k+1) = 4 / (4 - rho^2 w_k). Off by default
// (--chebyshev turns it on at rho = kDefaultRho, --chebyshev RHO at RHO,
// --no-chebyshev off again): on the cloth at 1/60 s it speeds up one step's
// convergence from rest, but whole runs with it diverge (docs/integrators.md
// "Vertex block descent" has the measurements). Where states are
// forbidden, an extrapolation that would leave them is not taken (that
// iteration keeps x^).
//
// Converged (N large), the step is implicit Euler's (tests/test_vbd.cc:
// within 1e-8 m of Newton's on a cloth and a tetrahedral block); the
// fixed point holds g_i = 0 for every particle, whatever H_i was used.
// Unconverged, it is not: the springs stay stretched by what the sweeps
// did not remove (the energy then comes out above implicit Euler's), and
// Chebyshev's extrapolation can overshoot. Friction's normal forces are
// lagged from the substep's start, as in Newton's step. Iterations count
// as newton_iterations and each sweep as one force evaluation (it
// evaluates every particle's force and blocks once); there is no global
// Jacobian or linear solve.
#pragma once

#include <vector>

#include "integrators/core/integrator.h"
#include "integrators/fast/vertex_colouring.h"
#include "models/core/vertex_blocks.h"

namespace springlab {

class Vbd final : public Integrator {
 public:
  Vbd();
  std::vector<std::string> options_read() const override {
    return {"iterations", "substeps", "chebyshev", "no-chebyshev"};
  }
  static constexpr int kDefaultIterations = 10;
  static constexpr int kDefaultSubsteps = 1;
  int substeps(const IntegratorOptions& o) const override {
    return o.substeps > 0 ? o.substeps : kDefaultSubsteps;
  }
  // It colours the vertices from the Jacobian's pattern, so the model builds
  // the pattern (the memory estimate counts it).
  bool assembles_jacobians(const MechanicalSystem&) const override { return true; }
  static constexpr double kDefaultRho = 0.9;
  // The fraction of the distance to a forbidden state one local step may
  // cover.
  static constexpr double kStepCap = 0.9;
  // Chebyshev's rho the options ask for (0: off).
  static double chebyshev_rho(const IntegratorOptions& options);

  // Local steps solved with the definite blocks (the particle's exact
  // block was indefinite, or its step longer than the inertia's), since
  // the start of the run.
  long definite_steps() const { return definite_steps_; }

 protected:
  StepResult do_initialize() override;
  StepResult do_step(double h) override;

 private:
  void substep(double t, double h);
  void initial_guess(double h);
  // One Gauss-Seidel sweep over the colours at time t (the step's end).
  void sweep(double t, double h);
  template <int D>
  void solve_chunk(double t, double h, const int* particles, int count);
  // Whether x_all_ (the free part) is a state with a finite energy.
  bool admissible(double t) const;
  void extrapolate(double t, double h, int iteration, double rho, double& omega);
  void set_velocities(double h);

  const VertexBlockView* view_ = nullptr;
  int dim_ = 3;
  Eigen::Index free_ = 0;  // free particles
  bool forbidden_ = false;  // the system has forbidden states
  VertexColouring colouring_;
  Vector mass_;  // per free particle
  // All particles (free, then fixed): positions and velocities as the view
  // reads them; the free head of x_all_ is the iterate.
  Vector x_all_, v_all_;
  Vector x_n_, v_n_, y_;          // the substep's start and inertial target (free)
  Vector a_ext_;                  // the constant forces' acceleration (free)
  Vector v_previous_;             // v_n of the substep before (the initial guess)
  bool has_previous_ = false;
  Vector x_before_, x_last_, x_hat_;  // Chebyshev: x^(k-1), x^(k), the sweep's result
  std::vector<double> f_, dfdx_, dfdv_;  // one chunk's blocks
  long definite_steps_ = 0;
};

}  // namespace springlab
