// implicit-euler --solver quasi-newton (docs/integrators.md "Fast solvers"): the step's
// incremental potential Phi(v) (newton_velocity_solver.h) minimized by
// L-BFGS instead of Newton (Liu, Bouaziz and Kavan, "Quasi-Newton methods
// for real-time simulation of hyperelastic materials", ACM TOG 2017).
//
// L-BFGS keeps the last kHistory updates s_k = v_{k+1} - v_k and gradient
// changes y_k = r(v_{k+1}) - r(v_k) and applies an approximate inverse
// Hessian to the gradient r by the two-loop recursion (Nocedal and Wright,
// "Numerical Optimization", 2006, Algorithm 7.4). Its initial Hessian is
// projective dynamics' local/global matrix,
//   H0 = M + h^2 L (x) I,  L = sum_c k_c (e_a - e_b)(e_a - e_b)^T,
// Phi's Hessian with every spring's stiffness along and across it set to
// k_c (a spring of rest length 0): the same matrix for x, y and z, so one
// factor of an n_particles x n_particles matrix, made once per step size,
// serves the three coordinates (Liu et al. 2017, sec. 4). Each iteration
// costs one force evaluation, one potential and three triangular solve
// pairs; no Jacobian is assembled.
//
// The search is Newton's Armijo rule on Phi from the full step (halving;
// where states are forbidden, Phi is +infinity there and the search halves
// past them), with one extrapolation: H0 is as stiff across a spring as
// along it, so along the cloth's soft bending and folding modes it
// overestimates the curvature and the full step d falls short of the
// minimum on its line, Phi still descending at its end (r(v + d) . d < 0).
// Then the secant of the slope along the line, g(a) = r(v + a d) . d,
// through g(0) and g(1) puts the minimum at
//   a* = g(0) / (g(0) - g(1)) > 1
// (the extrapolation step of a line search, Nocedal and Wright sec. 3.5),
// and where a* >= 1.2 the step a = min(a*, 4) is tried and taken if it
// lowers Phi below the full step's. It costs one more evaluation where it
// is tried; on cloth 64 at 1/60 over 2 s at 1e-3 m/s it cut L-BFGS's
// iterations per step from 64 to 45 and ended the one fall-back to Newton
// (a step of 200 iterations), and the step's median distance from the
// tightly solved one fell from 0.71 to 0.42 mm.
//
// Converged by Newton's own rule on the update L-BFGS proposes: the
// distance to the minimum on the line, max(1, a*) ||d|| in the max norm,
// below --newton-tol, or, while L-BFGS converges linearly at an observed
// rate q > 1/2, what remains after it, q / (1 - q) times that. L-BFGS's
// update is a rougher error estimate than Newton's: at the same tolerance
// its step lies further from the exact one (the frame-rate experiment
// measures how far). Where the direction does not descend even
// from H0 alone, or the search fails, or --max-newton iterations pass,
// L-BFGS has stalled: the step is then solved by Newton from its start (the
// "fall-back to Newton where it stalls").
#include <cmath>
#include <limits>

#include "integrators/fast_solver.h"
#include "integrators/newton_velocity_solver.h"

namespace springlab {
namespace {

constexpr int kHistory = 5;         // Liu et al. 2017 use 5
constexpr double kArmijo = 1e-4;    // as Newton's search
constexpr int kHalvings = 30;
constexpr double kExtrapolateFrom = 1.2;  // a* at which the longer step is tried
constexpr double kLongestStep = 4.0;      // its cap, as a multiple of d
constexpr double kRoundoff = 1e3 * std::numeric_limits<double>::epsilon();  // as Newton's

}  // namespace

bool ImplicitIntegrator::prepare_quasi_newton() {
  std::vector<DistanceConstraint> constraints;
  std::vector<ProjectiveElement> elements;
  const int dim = system().dimension_of_state();
  if (dim < 1 || !system().laplacian_form(constraints, elements)) return false;
  const Eigen::Index n = system().dofs() / dim;
  qn_.dim = dim;
  qn_.particle_mass.resize(n);
  for (Eigen::Index i = 0; i < n; ++i) qn_.particle_mass[i] = system().mass()[i * dim];
  qn_.laplacian = constraint_laplacian(constraints, elements, n);
  qn_.factor.reset();
  qn_.factored_h = 0.0;
  return true;
}

bool ImplicitIntegrator::quasi_newton(double h, const VelocityImplicitScheme& s, Vector& v) {
  QuasiNewtonState& q = qn_;
  const int dim = q.dim;
  const Eigen::Index n = q.particle_mass.size();
  // H0 = M + h^2 b L (x) I: Phi's v-Hessian is M + h^2 b K.
  if (!(std::abs(h - q.factored_h) <= 1e-12 * h)) {
    SparseMatrix a = (h * h * s.b) * q.laplacian;
    for (Eigen::Index i = 0; i < n; ++i) a.coeffRef(i, i) += q.particle_mass[i];
    ++mutable_stats().factorizations;
    if (!q.factor.factorize(a, MatrixKind::kPositiveDefinite)) return false;
    q.factored_h = h;
  }
  // z = H0^-1 q.q: the coordinates as the columns of an n x dim matrix,
  // solved together with the one factor.
  auto apply_h0_inverse = [&]() {
    q.columns = Eigen::Map<const Eigen::MatrixXd>(q.q.data(), dim, n).transpose();
    mutable_stats().linear_solves += dim;
    if (!q.factor.solve(q.columns, q.solved)) return false;
    q.z.resize(q.q.size());
    Eigen::Map<Eigen::MatrixXd>(q.z.data(), dim, n) = q.solved.transpose();
    return true;
  };

  q.s.clear();
  q.y.clear();
  q.rho.clear();
  const double tol = options().newton_tol;
  // Start from projective dynamics' inertial prediction: v_n plus what the
  // forces other than the distance constraints' (gravity, ...) add.
  system().external_force(t_, x_, v_, q.q);
  v = v_ + h * q.q.cwiseProduct(inv_mass());
  residual(h, s, v, r_);
  if (!r_.allFinite() && s.b > 0.0) {
    v = (-s.a / s.b) * v_;  // as Newton: a state the last step accepted
    residual(h, s, v, r_);
  }
  double magnitude = 0.0, magnitude_try = 0.0;
  double phi = potential(h, s, v, magnitude);
  if (!std::isfinite(phi) || !r_.allFinite()) return false;

  double previous_update = 0.0;
  for (int it = 0; it < options().max_newton; ++it) {
    ++mutable_stats().newton_iterations;
    // The two-loop recursion: d = -H r.
    q.q = r_;
    const std::size_t m = q.s.size();
    std::vector<double> alpha(m);
    for (std::size_t k = m; k-- > 0;) {
      alpha[k] = q.rho[k] * q.s[k].dot(q.q);
      q.q -= alpha[k] * q.y[k];
    }
    if (!apply_h0_inverse()) return false;
    for (std::size_t k = 0; k < m; ++k) {
      const double beta = q.rho[k] * q.y[k].dot(q.z);
      q.z += (alpha[k] - beta) * q.s[k];
    }
    q.d = -q.z;
    double slope = r_.dot(q.d);
    if (!(slope < 0.0) && m > 0) {  // the history misleads: H0 alone
      q.s.clear();
      q.y.clear();
      q.rho.clear();
      q.q = r_;
      if (!apply_h0_inverse()) return false;
      q.d = -q.z;
      slope = r_.dot(q.d);
    }
    if (!(slope < 0.0)) return r_.lpNorm<Eigen::Infinity>() == 0.0;
    // Armijo on Phi, halving from the full step.
    double step = 1.0, phi_try = 0.0;
    bool accepted = false;
    for (int k = 0; k <= kHalvings; ++k, step *= 0.5) {
      q.v_try = v + step * q.d;
      residual(h, s, q.v_try, q.r_try);
      if (!q.r_try.allFinite()) continue;
      phi_try = potential(h, s, q.v_try, magnitude_try);
      if (!std::isfinite(phi_try)) continue;
      const double noise = 1e3 * std::numeric_limits<double>::epsilon() *
                           std::max(magnitude, magnitude_try);
      if (phi_try - phi <= kArmijo * step * slope ||
          (step * -slope <= noise && q.r_try.norm() < r_.norm())) {
        accepted = true;
        break;
      }
    }
    if (!accepted) return false;
    // Where the full step still descends at its end, the minimum on the
    // line lies beyond it: a* from the secant of the slope.
    double a_star = 1.0;
    if (step == 1.0) {
      const double slope_end = q.r_try.dot(q.d);
      if (slope_end < 0.0) a_star = slope / (slope - slope_end);
      if (a_star >= kExtrapolateFrom) {
        const double longer = std::min(a_star, kLongestStep);
        q.v_long = v + longer * q.d;
        residual(h, s, q.v_long, q.r_long);
        double magnitude_long = 0.0;
        const double phi_long =
            q.r_long.allFinite() ? potential(h, s, q.v_long, magnitude_long) : phi_try;
        if (phi_long < phi_try) {
          step = longer;
          q.v_try.swap(q.v_long);
          q.r_try.swap(q.r_long);
          phi_try = phi_long;
          magnitude_try = magnitude_long;
        }
      }
    }
    // The update proposed (as Newton's full update, before its search: a
    // damped step is small without being near the solution), here the
    // estimated minimum on the line.
    const double update = a_star * q.d.lpNorm<Eigen::Infinity>();
    // The new pair, kept where it has positive curvature (y . s > 0).
    Vector s_new = step * q.d;
    Vector y_new = q.r_try - r_;
    const double ys = y_new.dot(s_new);
    if (ys > 1e-12 * y_new.norm() * s_new.norm()) {
      if (static_cast<int>(q.s.size()) == kHistory) {
        q.s.erase(q.s.begin());
        q.y.erase(q.y.begin());
        q.rho.erase(q.rho.begin());
      }
      q.s.push_back(std::move(s_new));
      q.y.push_back(std::move(y_new));
      q.rho.push_back(1.0 / ys);
    }
    v.swap(q.v_try);
    r_.swap(q.r_try);
    phi = phi_try;
    magnitude = magnitude_try;
    // Newton's rule: the update, or while converging linearly at an
    // observed rate q > 1/2, what remains after it, q / (1 - q) update.
    const double rate = previous_update > 0.0 ? update / previous_update : 0.0;
    const double remaining = rate > 0.5 && rate < 1.0 ? update * rate / (1.0 - rate) : update;
    // A tolerance below the round-off of v is met at that round-off.
    const double floor =
        kRoundoff * (v.lpNorm<Eigen::Infinity>() + v_.lpNorm<Eigen::Infinity>());
    if (remaining <= tol || update <= floor) return true;
    previous_update = update;
  }
  return false;
}

}  // namespace springlab
