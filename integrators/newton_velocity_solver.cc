#include "integrators/newton_velocity_solver.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

namespace springlab {
namespace {

// ImplicitIntegrator::kCgSoftLimit, kCgHardLimit: a CG solve that needed
// more products than the first has the preconditioner refreshed before the
// next solve; one not converged after the second is redone at once with a
// fresh one. A factorization costs about 15-30 preconditioned CG iterations
// on cloth 64 and 128 (benchmarks/README.md): of the pairs (6, 20),
// (10, 30), (15, 40), (25, 60) measured on cloth 64 at 1/60 s, (10, 30)
// cost least. At a step's first solve the kept factor (made in an earlier
// step) gets kCgSoftLimit products, and after it failed there the next
// kFreshSteps steps start with a fresh factor: at 1/60 s a factor of the
// step before preconditions poorly (BM_LinearSolver/kept-factor-cg: 34
// products to 1e-2 on cloth 64, 444 on cloth 128), a new factorization
// costs less.
constexpr int kFreshSteps = 4;
// Forcing term of the inexact Newton method: CG stops once its estimated
// error is below eta ||dv||_inf, eta = min(kForcing, ||r|| / ||r_0||) (so
// tighter as Newton converges), or below kForcingTolerance x the Newton
// tolerance.
constexpr double kForcing = 0.1;
constexpr double kForcingTolerance = 0.1;
// The accurate solves where the update must be a true Newton update (the
// discrete gradient's second phase, a retry on the residual's path).
constexpr double kAccurateForcing = 1e-3;
// The discrete gradient's rank-one term is used while 1 + z.q stays above
// this (near 0 it makes the matrix nearly singular).
constexpr double kMinShermanMorrison = 0.5;
// Relative residual of the one linear solve of a linearized step.
constexpr double kLinearRtol = 1e-6;
// Armijo's sufficient-decrease fraction.
constexpr double kArmijo = 1e-4;
// Updates below this many units of round-off of ||v||_inf are noise.
constexpr double kRoundoff = 1e3 * std::numeric_limits<double>::epsilon();
// The longest update tried along a direction of negative curvature, m/s.
constexpr double kMaxEscape = 10.0;
// The line search starts at this fraction of the step that would close a
// barrier's first gap (IPC's step cap: short of contact, never at it).
constexpr double kGapCap = 0.9;

// A factor that does not fit in memory (issue 38.1): the solver's line and
// what to try; no other method, no second attempt (each needs as much).
std::string out_of_memory_text(const SparseDirectSolver& solver) {
  return solver.error() +
         ": use a coarser mesh, --solver quasi-newton (it factors a matrix of a third of the "
         "unknowns), or a method that factors none (rk4, xpbd, projective-dynamics)";
}

}  // namespace

StepResult ImplicitIntegrator::do_initialize() {
  direct_.reset();
  preconditioner_.reset();
  preconditioner_valid_ = false;
  direct_current_ = false;
  fresh_steps_ = 0;
  cg_slow_ = 0;
  jacobian_ = SparseMatrix();
  preconditioner_matrix_ = SparseMatrix();
  dfdv_ = SparseMatrix();  // the next system may not need it
  jacobian_version_ = preconditioner_matrix_version_ = -1;
  direct_version_ = preconditioner_version_ = -1;
  return StepResult::success();
}

bool ImplicitIntegrator::factorize_on(SparseDirectSolver& solver, long& analysed, long version,
                                      const SparseMatrix& a, MatrixKind kind) {
  if (analysed != version) {
    solver.reset();  // a new pattern: a new symbolic analysis
    analysed = version;
  }
  return solver.factorize(a, kind);
}

void ImplicitIntegrator::stage(double h, const VelocityImplicitScheme& s, const Vector& v) {
  xs_ = x_ + h * (s.a * v_ + s.b * v);
  if (s.x_offset != nullptr) xs_ += *s.x_offset;
  vs_ = (1.0 - s.c) * v_ + s.c * v;
}

void ImplicitIntegrator::residual(double h, const VelocityImplicitScheme& s, const Vector& v,
                                  Vector& r) {
  stage(h, s, v);
  const double t = t_ + s.t_eval_offset * h;
  eval_force(t, xs_, vs_, f_);
  const Vector& v_c = s.inertia != nullptr ? *s.inertia : v_;
  r = system().mass().cwiseProduct(v - v_c) - (h * s.weight) * f_;
  if (!s.discrete_gradient) return;
  // Gonzalez (1996): grad V(x*) becomes
  //   grad V(x*) + (V(y) - V(x_n) - grad V(x*).Delta) / |Delta|^2 Delta,
  // Delta = y - x_n = h v*, x* the midpoint. grad V(x*).Delta is -F.Delta
  // plus the work of the forces that do not derive from V.
  delta_ = h * vs_;
  y_ = x_ + delta_;
  const double v_end = system().position_potential(t, y_);
  const double slope =
      -f_.dot(delta_) + h * system().nonconservative_power(t, xs_, vs_);
  const double numerator = v_end - v_start_potential_ - slope;
  const double noise = 1e3 * std::numeric_limits<double>::epsilon() *
                       (std::abs(v_end) + std::abs(v_start_potential_) + std::abs(slope));
  const double length2 = delta_.squaredNorm();
  correction_ = std::abs(numerator) > noise && length2 > 0.0 ? numerator / length2 : 0.0;
  const double c = frozen_ ? frozen_c_ : correction_;
  if (c != 0.0) r += (h * c) * delta_;
}

double ImplicitIntegrator::potential(double h, const VelocityImplicitScheme& s, const Vector& v,
                                     double& magnitude) const {
  // xs_ and vs_ are those of the last residual(), at this v.
  const double t = t_ + s.t_eval_offset * h;
  const Vector& v_c = s.inertia != nullptr ? *s.inertia : v_;
  const double inertia = 0.5 * (v - v_c).cwiseAbs2().dot(system().mass());
  const double stored = s.weight * system().position_potential(t, xs_) / s.b;
  const double dissipated = (h * s.weight) / s.c * system().velocity_potential(t, vs_);
  // The discrete gradient's correction with its coefficient frozen,
  // h c D = d/dv (c |D|^2).
  const double corrected = s.discrete_gradient ? frozen_c_ * delta_.squaredNorm() : 0.0;
  magnitude = inertia + std::abs(stored) + std::abs(dissipated) + std::abs(corrected);
  return inertia + stored + dissipated + corrected;
}

void ImplicitIntegrator::assemble(double t, const Vector& x, const Vector& v, double h,
                                  double b, double c, bool definite, SparseMatrix& out) {
  // No force depends on v: dF/dv = 0 is neither assembled nor stored (on
  // cloth n = 128, 23 MB of values and indices).
  SparseMatrix* dfdv =
      system().velocity_dependence() == VelocityDependence::kNone ? nullptr : &dfdv_;
  if (definite) {
    eval_definite_jacobians(t, x, v, &dfdx_, dfdv);
  } else {
    eval_jacobians(t, x, v, &dfdx_, dfdv);
  }
  // All three share the model's pattern: combine value by value.
  if (&out == &jacobian_) direct_current_ = false;
  const long version = system().pattern_version();
  long& out_version = &out == &jacobian_ ? jacobian_version_ : preconditioner_matrix_version_;
  if (out_version != version || out.nonZeros() != dfdx_.nonZeros()) out = dfdx_;
  out_version = version;
  const Eigen::Index nnz = dfdx_.nonZeros();
  const double* px = dfdx_.valuePtr();
  double* pj = out.valuePtr();
  const double cx = -h * h * b, cv = -h * c;
  if (dfdv != nullptr) {
    const double* pv = dfdv_.valuePtr();
    for (Eigen::Index k = 0; k < nnz; ++k) pj[k] = cx * px[k] + cv * pv[k];
  } else {
    for (Eigen::Index k = 0; k < nnz; ++k) pj[k] = cx * px[k];
  }
  out.diagonal() += system().mass();
}

bool ImplicitIntegrator::refresh_preconditioner(double t, const Vector& x, const Vector& v,
                                                double h, double b, double c,
                                                bool jacobian_is_definite, std::string& error) {
  const SparseMatrix* a = &jacobian_;
  preconditioner_valid_ = false;
  if (!jacobian_is_definite) {
    assemble(t, x, v, h, b, c, /*definite=*/true, preconditioner_matrix_);
    a = &preconditioner_matrix_;
  }
  ++mutable_stats().factorizations;
  preconditioner_valid_ =
      factorize_on(preconditioner_, preconditioner_version_,
                   a == &jacobian_ ? jacobian_version_ : preconditioner_matrix_version_, *a,
                   MatrixKind::kPositiveDefinite) &&
      preconditioner_.positive_definite();
  cg_slow_ = 0;
  if (!preconditioner_valid_ && preconditioner_.out_of_memory()) {
    error = out_of_memory_text(preconditioner_);
  } else if (!preconditioner_valid_) {
    error = "the definite Newton matrix is not positive definite";
    if (!preconditioner_.error().empty()) error += " (" + preconditioner_.error() + ")";
  }
  return preconditioner_valid_;
}

ImplicitIntegrator::LinearSolve ImplicitIntegrator::solve_linear(
    double t, const Vector& x, const Vector& v, double h, double b, double c, bool definite,
    const Vector& rhs, double rtol, double atol, bool truncate, Vector& d, std::string& error,
    int max_iterations) {
  LinearSolve out;
  ++mutable_stats().linear_solves;
  auto direct = [&](MatrixKind kind) {
    // The same matrix as the last direct solve's (a second right-hand side).
    if (direct_current_ && direct_.has_factor()) {
      out.ok = direct_.solve(rhs, d);
      out.converged = true;
      if (!out.ok) error = "the linear solve gave a non-finite update";
      return out;
    }
    ++mutable_stats().factorizations;
    direct_current_ = true;
    if (!factorize_on(direct_, direct_version_, jacobian_version_, jacobian_, kind)) {
      direct_current_ = false;
      error = direct_.out_of_memory() ? out_of_memory_text(direct_)
                                      : "the Newton matrix is singular (" + direct_.error() + ")";
      out.ok = false;
      return out;
    }
    out.ok = direct_.solve(rhs, d);
    out.converged = true;
    if (!out.ok) error = "the linear solve gave a non-finite update";
    return out;
  };
  // Spring damping makes the Jacobian non-symmetric: no CG, LU.
  if (!system().jacobian_symmetric()) return direct(MatrixKind::kGeneral);

  if ((!preconditioner_valid_ || cg_slow_ > 0) &&
      !refresh_preconditioner(t, x, v, h, b, c, definite, error)) {
    if (preconditioner_.out_of_memory()) {
      out.ok = false;
      return out;
    }
    // No positive definite matrix to precondition with (a negative mass,
    // say, cannot happen; round-off in a nearly singular one can).
    return direct(MatrixKind::kSymmetric);
  }
  // CG where the matrix is positive definite or truncation is wanted (Newton
  // on a potential); MINRES where a true solve of an indefinite one is.
  const bool minres = !definite && !truncate;
  auto krylov = [&](int limit) {
    CgResult k = minres ? preconditioned_minres(jacobian_, preconditioner_, rhs, rtol, limit, d,
                                                minres_)
                        : preconditioned_cg(jacobian_, preconditioner_, rhs, rtol, atol, limit,
                                            d, cg_);
    mutable_stats().linear_iterations += k.iterations;
    return k;
  };
  CgResult cg = krylov(max_iterations);
  if (cg.finite && !cg.converged && !cg.negative_curvature) {
    // The kept factor is too far from this matrix: a fresh one, at once.
    if (!refresh_preconditioner(t, x, v, h, b, c, definite, error)) {
      if (preconditioner_.out_of_memory()) {
        out.ok = false;
        return out;
      }
      return direct(MatrixKind::kSymmetric);
    }
    cg = krylov(std::max(max_iterations, kCgHardLimit));
  }
  cg_slow_ = cg.iterations > kCgSoftLimit ? 1 : 0;
  if (!cg.finite) {
    error = "the linear solve gave a non-finite update";
    out.ok = false;
    return out;
  }
  if (cg.converged || (truncate && cg.negative_curvature)) {
    out.converged = cg.converged;
    out.negative_curvature = cg.negative_curvature && cg.iterations == 1;
    return out;
  }
  // Indefinite (or still not converged) and a true solve is wanted.
  return direct(definite ? MatrixKind::kPositiveDefinite : MatrixKind::kSymmetric);
}

ImplicitIntegrator::StepStart ImplicitIntegrator::begin_step() {
  StepStart start;
  start.probe = fresh_steps_ == 0 && cg_slow_ == 0 && preconditioner_valid_;
  if (fresh_steps_ > 0) {
    --fresh_steps_;
    cg_slow_ = 1;  // refresh before the first solve
  }
  start.factorizations = stats().factorizations;
  return start;
}

void ImplicitIntegrator::end_first_solve(const StepStart& start) {
  // The kept factor failed at a step's start: fresh ones for the next steps.
  if (start.probe && stats().factorizations > start.factorizations) fresh_steps_ = kFreshSteps;
}

bool ImplicitIntegrator::solve_linearized(double t, const Vector& x, const Vector& v,
                                          const Vector& f, double h, double b, double c,
                                          bool definite, Vector& dv, std::string& error) {
  assemble(t, x, v, h, b, c, definite, jacobian_);
  jd_.noalias() = dfdx_ * v;
  jd_ = h * (f + h * jd_);  // the right-hand side, before dfdx_ is reused
  if (!definite) {
    // The exact stiffness: the matrix may be indefinite (compressed springs),
    // so LDL^T (LU without symmetry), as a direct solve of it always was;
    // MINRES with the definite factor needs tens of products on cloth 64.
    ++mutable_stats().linear_solves;
    ++mutable_stats().factorizations;
    direct_current_ = false;
    if (!factorize_on(direct_, direct_version_, jacobian_version_, jacobian_,
                      system().jacobian_symmetric() ? MatrixKind::kSymmetric
                                                    : MatrixKind::kGeneral)) {
      error = direct_.out_of_memory() ? out_of_memory_text(direct_)
                                      : "the step's matrix is singular (" + direct_.error() + ")";
      return false;
    }
    if (!direct_.solve(jd_, dv)) {
      error = "the linear solve gave a non-finite update";
      return false;
    }
    return true;
  }
  const StepStart start = begin_step();
  const bool ok = solve_linear(t, x, v, h, b, c, definite, jd_, kLinearRtol, 0.0,
                               /*truncate=*/false, dv, error, kCgSoftLimit)
                      .ok;
  end_first_solve(start);
  return ok;
}

StepResult ImplicitIntegrator::solve_velocity(double h, const VelocityImplicitScheme& s,
                                              Vector& v, bool quasi) {
  // Friction's normal forces from the step's start while the step is
  // solved (MechanicalSystem::lag_normal_forces): friction then derives
  // from a dissipation potential, and Newton minimizes.
  struct Lag {
    const MechanicalSystem& system;
    Lag(const MechanicalSystem& m, const Vector& x) : system(m) { system.lag_normal_forces(&x); }
    ~Lag() { system.lag_normal_forces(nullptr); }
  } lag(system(), x_);
  // Where the step minimizes the incremental potential Phi, a solution lies
  // no higher than the start guesses the solvers descend from: v_n, and the
  // v that keeps the stage at x_n (Newton's start where v_n leaves the
  // states with an energy; for implicit Euler, v = 0 and Phi = E_n, the
  // step's starting energy). An answer above the lower of the two by more
  // than Phi's round-off is an iterate that looked converged but is no
  // minimizer (near-incompressible elements: block n=3 at poisson
  // 0.49999999999 with L-BFGS, whose stiff initial Hessian makes its updates
  // small while the residual is not, went from 47 J to 493 J in 1 s of
  // "completed" steps, each answer up to 26 J above E_n). L-BFGS's answer is
  // then not taken: Newton solves the step from its start.
  // (Only L-BFGS's answers are checked: Newton's and every other method's
  // steps pay nothing for it.)
  const bool minimizes = quasi && system().derives_from_potentials() && s.b > 0.0 &&
                         s.c > 0.0 && !s.discrete_gradient;
  double phi_start = std::numeric_limits<double>::infinity(), magnitude_start = 0.0;
  if (minimizes) {
    Vector v_kept = (-s.a / s.b) * v_;
    if (s.x_offset != nullptr) v_kept -= (1.0 / (h * s.b)) * *s.x_offset;
    // Phi's round-off scale is that of both guesses' terms (at v_n the
    // inertia term is 0 and the stored energy may be nearly 0 too -- a
    // strain-free spin --, while the answer's terms carry the round-off of
    // the kinetic energy the guess at x_n holds).
    for (const Vector* guess : {&v_, &v_kept}) {
      double magnitude = 0.0;
      stage(h, s, *guess);
      const double phi = potential(h, s, *guess, magnitude);
      if (std::isfinite(magnitude)) magnitude_start = std::max(magnitude_start, magnitude);
      if (phi < phi_start) phi_start = phi;
    }
  }
  double phi_end = 0.0;
  auto raises_potential = [&](const Vector& v_end) {
    if (!minimizes || !std::isfinite(phi_start)) return false;
    double magnitude_end = 0.0;
    stage(h, s, v_end);
    phi_end = potential(h, s, v_end, magnitude_end);
    // (At least the smallest normal double: a state decayed into denormals,
    // 0 J to 4.9e-324 J, has nothing left to compare.)
    const double noise = std::max(kRoundoff * std::max(magnitude_start, magnitude_end),
                                  std::numeric_limits<double>::min());
    if (phi_end <= phi_start + noise) return false;
    // Above the start by more than round-off: still a solution if within
    // what the Newton tolerance leaves. Near the minimizer v*,
    // Phi(v) - Phi(v*) ~ r(v).(v - v*) / 2 <= ||r(v)||_1 tol / 2 (a body
    // at rest, turned: both about 1.5e-29 J, 3 % apart).
    residual(h, s, v_end, r_try_);
    const double allowance = 0.5 * options().newton_tol * r_try_.lpNorm<1>();
    return !(phi_end <= phi_start + noise + allowance);
  };
  auto raised_text = [&](const char* solver) {
    std::ostringstream message;
    message << name() << ": " << solver << "'s step at t = " << t_ << " (h = " << h
            << ") raised the incremental potential from " << phi_start << " J to " << phi_end
            << " J (this method's step minimizes it: not a solution)";
    return message.str();
  };
  std::string quasi_rejected;  // why L-BFGS's answer was not taken
  // L-BFGS needs the potential; where it stalls, Newton solves the step.
  if (quasi && system().derives_from_potentials() && quasi_newton(h, s, v)) {
    if (!raises_potential(v)) return StepResult::success();
    quasi_rejected = raised_text("L-BFGS");
    ++mutable_stats().nonlinear_failures;  // Newton from the step's start
  }
  // Newton's own answers are not checked so: its line search already asks
  // Phi to fall, and near a state at rest the stored energy's round-off
  // (a turned neo-Hookean block: 2.3e-14 J against terms of mu W ~ 300 J)
  // is not Phi's parts' magnitude, so a check at that scale refuses good
  // steps.
  StepResult result = newton(h, s, v);
  const bool out_of_memory = direct_.out_of_memory() || preconditioner_.out_of_memory();
  if (!result.ok && system().jacobian_symmetric() && !out_of_memory) {
    // Projected Newton from the step's start: every update from the definite
    // matrix, a descent direction of the incremental potential with a
    // search that cannot fail but to round-off. It converges linearly where
    // Newton with the exact matrix alternates with it and stalls near a
    // buckling state (cloth 96 at 1/60, t = 0.167: 200 iterations of long
    // exact updates cut to 1/64 between definite ones), at more iterations
    // per step than the exact matrix takes where it works, so it is the
    // second attempt, not the first.
    ++mutable_stats().nonlinear_failures;
    definite_only_ = true;
    StepResult second = newton(h, s, v);
    definite_only_ = false;
    if (second.ok) return second;
    result = second;
  }
  if (!result.ok) ++mutable_stats().nonlinear_failures;
  if (!result.ok && !quasi_rejected.empty()) {
    const std::string own = name() + ": ";  // Newton's message names the method too
    const std::string newton_text = result.message.rfind(own, 0) == 0
                                        ? result.message.substr(own.size())
                                        : result.message;
    result = StepResult::failure(quasi_rejected + ", and " + newton_text);
  }
  return result;
}

StepResult ImplicitIntegrator::newton(double h, const VelocityImplicitScheme& s, Vector& v) {
  std::string error;
  auto fail = [&](const std::string& why) {
    std::ostringstream message;
    message << name() << ": Newton failed at t = " << t_ << " (h = " << h << "): " << why;
    return StepResult::failure(message.str());
  };
  const double t = t_ + s.t_eval_offset * h;
  // The Newton matrix's coefficients of dF/dx (h^2 w b) and dF/dv (h w c).
  const double wb = s.weight * s.b, wc = s.weight * s.c;
  const double tol = options().newton_tol;
  const bool symmetric = system().jacobian_symmetric();
  const bool forbidden_states = system().has_forbidden_states();
  // Newton minimizes the incremental potential when r is its gradient.
  const bool has_potential = system().derives_from_potentials() && s.b > 0.0 && s.c > 0.0;
  bool minimize = has_potential;
  // The discrete gradient on the potential path: phase 1 minimizes the
  // potential with the coefficient frozen (robust far from the solution);
  // once a full exact update is taken, phase 2 is Newton with the exact
  // Jacobian (rank-one term included) and a search on ||r||, quadratic near
  // the solution; back to phase 1 when that search fails.
  bool dg_newton = false;
  frozen_ = s.discrete_gradient && minimize;
  frozen_c_ = 0.0;
  if (s.discrete_gradient) v_start_potential_ = system().position_potential(t, x_);

  v = v_;
  residual(h, s, v, r_);
  if (!r_.allFinite() && s.b > 0.0) {
    // The guess v = v_n leaves the states where the forces are defined (a
    // barrier's gap closed, an element inverted): start where the stage
    // stays at x_n, a v_n + b v = 0, a state the last step accepted.
    v = (-s.a / s.b) * v_;
    residual(h, s, v, r_);
  }
  double magnitude = 0.0, magnitude_try = 0.0;
  double phi = minimize ? potential(h, s, v, magnitude) : 0.0;
  const double r_start = r_.norm();
  bool definite = definite_only_ && symmetric;
  double previous_update = 0.0;  // ||dv||_inf of the last full update
  double rate = 0.0;             // its ratio to the one before (0: not known)
  double last_update = 0.0;
  // What the convergence test made of the last update: the error it
  // estimates to remain, the rate that estimate used, and why an update
  // below the tolerance was not taken.
  double last_remaining = 0.0, last_rate = 0.0;
  std::string last_why;
  bool careful = false;
  bool started = false;  // the step's first linear solve is behind
  // Updates computed: iterations, plus the retries from the same iterate
  // (another matrix, a true Newton update); bounded so no cycle of retries
  // runs on.
  int attempts = 0;
  for (int iteration = 0;;) {
    if (!r_.allFinite()) return fail("the residual is not finite");
    if (iteration == options().max_newton || ++attempts > 3 * options().max_newton) {
      // Say why the last update, even one below the tolerance, did not end
      // the iteration.
      std::ostringstream why;
      why << "no convergence in " << options().max_newton << " iterations (last update "
          << last_update << " m/s, tolerance " << tol << " m/s";
      if (last_remaining > tol && last_remaining > last_update) {
        why << "; converging linearly at the rate " << last_rate << ", it leaves an error of about "
            << last_remaining << " m/s";
      } else if (last_update <= tol && !last_why.empty()) {
        why << "; not taken: " << last_why;
      }
      why << "); try a larger --max-newton or a smaller --dt";
      return fail(why.str());
    }
    if (s.discrete_gradient && has_potential) {
      minimize = !dg_newton;
      frozen_ = minimize;
      careful = careful || dg_newton;
    }
    if (frozen_ && correction_ != frozen_c_) {
      // The discrete gradient's coefficient at this v: the potential and r
      // of the next iterations use it.
      r_ += (h * (correction_ - frozen_c_)) * delta_;
      phi += (correction_ - frozen_c_) * delta_.squaredNorm();
      frozen_c_ = correction_;
    }
    stage(h, s, v);
    assemble(t, xs_, vs_, h, wb, wc, definite, jacobian_);
    const double r_norm = r_.norm();
    const double eta =
        careful ? kAccurateForcing
                : std::min(kForcing, r_start > 0.0 ? r_norm / r_start : kForcing);
    const double atol = careful ? 0.0 : kForcingTolerance * tol;
    // The discrete gradient's correction c D (c = correction_) has the
    // derivative (h^2/2) (c I + D (w - 2 c D)^T / |D|^2) with respect to v,
    // w = grad V(y) - grad V(x*) - H(x*) D / 2 (H = -dF/dx): a shift of the
    // diagonal and a rank-one term, solved by Sherman and Morrison.
    const bool rank_one = s.discrete_gradient && correction_ != 0.0;
    if (rank_one) {
      eval_force(t, y_, vs_, f_end_);
      z_.noalias() = dfdx_ * delta_;
      z_ = 0.5 * z_ - (f_end_ - f_) - 2.0 * correction_ * delta_;
      z_ *= 0.5 * h * h / delta_.squaredNorm();
      // (The definite matrix keeps only a positive shift.)
      jacobian_.diagonal().array() +=
          0.5 * h * h * (definite ? std::max(0.0, correction_) : correction_);
      direct_current_ = false;
    }
    r_try_ = -r_;
    const bool first = iteration == 0 && !started;
    StepStart start;
    if (first) start = begin_step();
    started = true;
    const LinearSolve ls =
        solve_linear(t, xs_, vs_, h, wb, wc, definite, r_try_, eta, atol, minimize, dv_, error,
                     first ? kCgSoftLimit : kCgHardLimit);
    if (first) end_first_solve(start);
    if (!ls.ok) return fail(error);
    if (rank_one) {
      const LinearSolve lq = solve_linear(t, xs_, vs_, h, wb, wc, definite, delta_, eta, 0.0,
                                          /*truncate=*/false, q_, error);
      if (!lq.ok) return fail(error);
      // Near zero the rank-one term makes the matrix nearly singular: there
      // the midpoint matrix alone gives the better direction.
      const double denominator = 1.0 + z_.dot(q_);
      if (denominator > kMinShermanMorrison || (careful && denominator != 0.0)) {
        // Where the coefficient is frozen, only if the update still descends.
        const double step = z_.dot(dv_) / denominator;
        if (!frozen_ || r_.dot(dv_ - step * q_) < 0.0) dv_ -= step * q_;
      }
    }
    const double update = dv_.lpNorm<Eigen::Infinity>();
    last_update = update;
    last_rate = rate;
    last_remaining = rate > 0.5 && rate < 1.0 ? update * rate / (1.0 - rate) : update;
    last_why = ls.converged || ls.negative_curvature
                   ? ""
                   : "its linear solve stopped short of its own tolerance";

    // The slope of the potential along dv (negative: CG's iterates descend
    // but for round-off).
    const double slope = minimize ? r_.dot(dv_) : 0.0;

    // Line search: on the potential, Armijo (below the potential's
    // round-off, ||r|| must decrease); on the residual, ||r|| must decrease.
    double phi_try = 0.0;
    auto noise = [&] {
      return 1e3 * std::numeric_limits<double>::epsilon() * std::max(magnitude, magnitude_try);
    };
    // Where some states have no energy, a trial whose step would end in one
    // is refused even when the forces' state (the midpoint) is allowed.
    auto end_allowed = [&] {
      if (s.end == 1.0 || !forbidden_states) return true;
      x_end_ = x_ + s.end * (xs_ - x_);
      return std::isfinite(system().position_potential(t_ + h, x_end_));
    };
    // The fraction of dv at which the first gap of the stage -- or, for the
    // midpoint methods, of the step's end -- would close (+infinity: none
    // closes; MechanicalSystem::admissible_fraction).
    auto gap_fraction = [&] {
      x_cap_ = x_ + h * (s.a * v_ + s.b * v);
      if (s.x_offset != nullptr) x_cap_ += *s.x_offset;
      dx_cap_ = (h * s.b) * dv_;
      double fraction = system().admissible_fraction(x_cap_, dx_cap_);
      if (s.end != 1.0) {
        x_cap_ = x_ + s.end * (x_cap_ - x_);
        dx_cap_ *= s.end;
        fraction = std::min(fraction, system().admissible_fraction(x_cap_, dx_cap_));
      }
      return fraction;
    };
    auto accept = [&](double alpha) {
      const double r_try_norm = r_try_.norm();
      if (!std::isfinite(r_try_norm) || !end_allowed()) return false;
      const bool residual_decreases = r_try_norm <= (1.0 - kArmijo * alpha) * r_norm;
      if (!minimize) return residual_decreases;
      phi_try = potential(h, s, v_try_, magnitude_try);
      if (!std::isfinite(phi_try)) return false;
      if (phi_try - phi <= kArmijo * alpha * slope) return true;
      return alpha * -slope <= noise() && residual_decreases;
    };
    // dv is a direction of negative curvature (CG stopped at its first
    // product): the potential falls faster than linearly along it, so try
    // longer steps, doubling from `alpha` while the potential keeps falling
    // (and not visibly rising: tiny steps change it below its round-off).
    // True, with v_try_, r_try_, phi_try at the best step, when the
    // potential fell beyond its round-off.
    auto expand = [&](double& alpha) {
      double best_phi = phi, best_magnitude = magnitude, best_alpha = 0.0;
      for (int k = 0; k < 40; ++k, alpha *= 2.0) {
        if (alpha * update > kMaxEscape) break;
        v_try_ = v + alpha * dv_;
        residual(h, s, v_try_, r_try_);
        phi_try = potential(h, s, v_try_, magnitude_try);
        if (!std::isfinite(phi_try) || phi_try > best_phi + noise() || !end_allowed()) break;
        if (phi_try < best_phi) {
          best_phi = phi_try;
          best_magnitude = magnitude_try;
          best_alpha = alpha;
        }
      }
      if (!(best_phi < phi - noise())) return false;
      alpha = best_alpha;
      v_try_ = v + alpha * dv_;
      residual(h, s, v_try_, r_try_);
      phi_try = best_phi;
      magnitude_try = best_magnitude;
      return true;
    };

    // Converged: the update (an estimate of the error before it) is below the
    // tolerance, or, converging linearly at `rate`, what remains after it is.
    // Where the potential curves down (a saddle of it, not a minimum: a
    // buckling cloth), the step's equations have lower solutions nearby:
    // leave along that direction if the potential visibly falls.
    double alpha = 1.0;
    bool accepted = false;
    if (ls.converged || ls.negative_curvature) {
      const double remaining = rate > 0.5 && rate < 1.0 ? update * rate / (1.0 - rate) : update;
      // A tolerance below the round-off of v is met at that round-off.
      const double floor =
          kRoundoff * (v.lpNorm<Eigen::Infinity>() + v_.lpNorm<Eigen::Infinity>());
      // Where states are forbidden, the last update must not end in one
      // (a barrier's gap closed by it): then it is searched like any other,
      // from the step cap.
      const bool small = remaining <= tol || update <= floor;
      const bool keeps_gaps = !small || !forbidden_states || gap_fraction() > 1.0;
      if (small && !keeps_gaps) last_why = "it would close a barrier's gap";
      if (small && keeps_gaps) {
        alpha = update > 0.0 ? tol / update : 1.0;
        if (!ls.negative_curvature || !expand(alpha)) {
          ++mutable_stats().newton_iterations;
          v += dv_;
          return StepResult::success();
        }
        last_why = "the incremental potential kept falling beyond it (negative curvature)";
        accepted = true;
      }
    }

    if (!accepted && minimize && !(slope < 0.0)) {
      if (!definite) {
        definite = true;
        continue;
      }
      if (frozen_) {  // the frozen potential is only a guide: Newton on r
        dg_newton = true;
        continue;
      }
      return fail("the Newton update does not descend the incremental potential");
    }

    // IPC's step cap (Li et al. 2020): where a barrier forbids states, the
    // search starts at kGapCap of the fraction of dv at which the first gap
    // of the stage -- or, for the midpoint methods, of the step's end --
    // would close, instead of finding the closed gap by halving.
    if (!accepted && forbidden_states) {
      const double cap = gap_fraction();
      // A cap below the search's own floor means the iterate is pinned at a
      // gap: search from the full step as without a cap, which ends in the
      // line search's failure (the step's equations have no solution that
      // keeps the gaps open).
      if (kGapCap * cap >= 1.0 / 1024.0) alpha = std::min(alpha, kGapCap * cap);
    }
    // With a descent direction of the potential the search cannot fail but
    // to round-off; otherwise give up at 1/1024 and try the definite matrix.
    const double alpha_min = minimize && definite ? 1e-12 : 1.0 / 1024.0;
    while (!accepted) {
      v_try_ = v + alpha * dv_;
      residual(h, s, v_try_, r_try_);
      if (accept(alpha)) {
        accepted = true;
        if (alpha == 1.0 && minimize && ls.negative_curvature) {
          double beta = 2.0;
          const Vector v_one = v_try_, r_one = r_try_;
          const double phi_one = phi_try, magnitude_one = magnitude_try;
          if (expand(beta) && phi_try < phi_one) {
            alpha = beta;
          } else {
            v_try_ = v_one;
            r_try_ = r_one;
            phi_try = phi_one;
            magnitude_try = magnitude_one;
          }
        }
        break;
      }
      alpha *= 0.5;
      if (alpha < alpha_min) break;
    }
    if (!accepted && dg_newton) {
      // Back to the frozen potential, from v.
      dg_newton = false;
      careful = false;
      frozen_ = false;
      residual(h, s, v, r_);  // sets correction_ at v, and r_ with it
      frozen_ = true;
      frozen_c_ = correction_;
      phi = potential(h, s, v, magnitude);
      continue;
    }
    if (!accepted) {
      if (!minimize && !careful && symmetric) {
        careful = true;  // an accurate Newton update descends ||r||: retry with one
        residual(h, s, v, r_);
        continue;
      }
      if (!definite && symmetric) {
        definite = true;  // its update descends: retry from the same v
        residual(h, s, v, r_);  // the state of the residual at v again
        continue;
      }
      return fail(minimize ? "the line search could not decrease the incremental potential; try "
                             "a smaller --dt"
                           : "the line search could not reduce the residual; try a smaller --dt");
    }
    rate = alpha == 1.0 && previous_update > 0.0 ? update / previous_update : 0.0;
    previous_update = alpha == 1.0 ? update : 0.0;
    if (s.discrete_gradient && has_potential && !dg_newton && alpha == 1.0 && !definite) {
      dg_newton = true;
    }
    // The definite matrix after a line search, the exact one after a full
    // update (quadratic convergence near the solution).
    if (symmetric) definite = alpha < 1.0 || definite_only_;
    ++mutable_stats().newton_iterations;
    ++iteration;
    v.swap(v_try_);
    r_.swap(r_try_);
    phi = phi_try;
    magnitude = magnitude_try;
  }
}

}  // namespace springlab
