#include "integrators/fast/vbd.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <optional>
#include <string>

#include "integrators/core/integrator_entry.h"
#include "integrators/core/lagged_normal_forces.h"
#include "models/core/fast_solver_views.h"

namespace springlab {
namespace {

// Particles whose blocks are evaluated together (one colour's, a chunk at a
// time: their blocks stay in the first-level cache until solved).
constexpr int kChunk = 64;

}  // namespace

Vbd::Vbd()
    : Integrator({.name = "vbd",
                  .scheme = "S substeps; N sweeps over the particles by colour: x_i -= H_i^-1 "
                            "g_i, g_i = m_i/h^2 (x_i - x_n,i - h v_n,i) - F_i, H_i = m_i/h^2 I - "
                            "dF_i/dx_i - dF_i/dv_i / h; Chebyshev across sweeps; v = (x - x_n)/h",
                  .order = 1,
                  .implicit = true,
                  .jacobian_free = true,
                  // Converged, the step is implicit Euler's (drag and wind
                  // included: their dF/dv is in H_i). On one particle a
                  // sweep is exact Newton on its quadratic potential.
                  .stability = StabilityKind::kL,
                  .stability_limit = kInfinity,
                  .stability_note = "at convergence: implicit Euler's step, drag and wind "
                                    "(and spring damping) included; an unconverged step leaves "
                                    "springs stretched and can gain energy (cloth 32 at 1/60 s: "
                                    "over 5 E_s with 10 iterations, under 0.01 E_s with 100), and "
                                    "Chebyshev's extrapolation can overshoot"}) {}

double Vbd::chebyshev_rho(const IntegratorOptions& options) {
  if (options.no_chebyshev) return 0.0;
  return options.chebyshev == kChebyshevOn ? kDefaultRho : options.chebyshev;
}

StepResult Vbd::do_initialize() {
  const FastSolverViews* views = system().fast_solver_views();
  view_ = views != nullptr ? views->vertex_block_view() : nullptr;
  Refusal why{"this system has no per-particle form; use implicit-euler", {}};
  if (view_ == nullptr || !view_->vertex_form(why)) {
    return StepResult::refusal(name(), std::move(why));
  }
  dim_ = view_->dimension_of_state();
  free_ = system().dofs() / dim_;
  forbidden_ = system().has_forbidden_states();
  colouring_ = colour_vertices(system().jacobian_pattern(), dim_, static_cast<int>(free_));
  mass_.resize(free_);
  for (Eigen::Index i = 0; i < free_; ++i) mass_[i] = system().mass()[i * dim_];
  x_all_.resize(view_->all_particles() * dim_);
  view_->fill_fixed(x_all_);
  v_all_.setZero(x_all_.size());
  a_ext_.resize(system().dofs());
  view_->constant_force(a_ext_.data());
  a_ext_.array() *= inv_mass().array();
  has_previous_ = false;
  const std::size_t block = static_cast<std::size_t>(kChunk * dim_ * dim_);
  f_.assign(static_cast<std::size_t>(kChunk * dim_), 0.0);
  dfdx_.assign(block, 0.0);
  dfdv_.assign(view_->reads_velocity() ? block : 0, 0.0);
  definite_steps_ = 0;
  return StepResult::success();
}

StepResult Vbd::do_step(double h) {
  const int substeps = this->substeps(options());
  const double hs = h / substeps;
  for (int s = 0; s < substeps; ++s) substep(t_ + s * hs, hs);
  return StepResult::success();
}

void Vbd::substep(double t, double h) {
  const Eigen::Index n = system().dofs();
  x_n_ = x_;
  v_n_ = v_;
  // (Only friction lags; lagging copies the state.)
  std::optional<LaggedNormalForces> lag;
  if (system().velocity_dependence() == VelocityDependence::kNonlinear) lag.emplace(system(), x_n_);
  y_ = x_n_ + h * v_n_;
  initial_guess(h);
  set_velocities(h);
  const int iterations = options().iterations > 0 ? options().iterations : kDefaultIterations;
  const double rho = chebyshev_rho(options());
  double omega = 1.0;
  for (int k = 0; k < iterations; ++k) {
    if (rho > 0.0) {  // keep x^(k-1) and x^(k) for the extrapolation
      x_before_.swap(x_last_);
      x_last_ = x_all_.head(n);
    }
    sweep(t + h, h);
    if (rho > 0.0) extrapolate(t + h, h, k, rho, omega);
    ++mutable_stats().newton_iterations;
  }
  x_ = x_all_.head(n);
  v_ = (x_ - x_n_) / h;
  v_previous_ = v_n_;
  has_previous_ = true;
}

void Vbd::initial_guess(double h) {
  const Eigen::Index n = system().dofs();
  // x = y + h^2 a~, a~ = a_ext clamp(a_n . a_ext / |a_ext|^2, 0, 1), per particle.
  double* guess = x_all_.data();
  const double* acc = a_ext_.data();
  const double* v_n = v_n_.data();
  const double* v_previous = v_previous_.data();
  for (Eigen::Index k = 0; k < n; ++k) guess[k] = y_[k];
  for (Eigen::Index i = 0; i < free_; ++i) {
    double aa = 0.0, an = 0.0;
    for (int r = 0; r < dim_; ++r) {
      const Eigen::Index k = i * dim_ + r;
      aa += acc[k] * acc[k];
      if (has_previous_) an += (v_n[k] - v_previous[k]) / h * acc[k];
    }
    if (!(aa > 0.0)) continue;
    const double scale = has_previous_ ? std::clamp(an / aa, 0.0, 1.0) : 1.0;
    for (int r = 0; r < dim_; ++r) guess[i * dim_ + r] += h * h * scale * acc[i * dim_ + r];
  }
  if (!forbidden_) return;
  // Where states are forbidden: no further than kStepCap of the way to the
  // first closed gap, and back toward x_n while some energy is infinite.
  const Vector step = x_all_.head(n) - x_n_;
  const double cap = system().admissible_fraction(x_n_, step);
  double a = std::min(1.0, kStepCap * cap);
  for (int halvings = 0;; ++halvings) {
    x_all_.head(n) = x_n_ + a * step;
    if (halvings == 60 || admissible(t_)) break;
    a *= 0.5;
  }
}

bool Vbd::admissible(double t) const {
  return std::isfinite(system().position_potential(t, x_all_.head(system().dofs())));
}

void Vbd::set_velocities(double h) {
  if (!view_->reads_velocity()) return;  // no force reads v
  const Eigen::Index n = system().dofs();
  v_all_.head(n) = (x_all_.head(n) - x_n_) / h;
}

void Vbd::sweep(double t, double h) {
  ++mutable_stats().force_evals;
  for (const std::vector<int>& members : colouring_.members) {
    const int count = static_cast<int>(members.size());
    for (int first = 0; first < count; first += kChunk) {
      const int m = std::min(kChunk, count - first);
      switch (dim_) {
        case 1: solve_chunk<1>(t, h, members.data() + first, m); break;
        case 2: solve_chunk<2>(t, h, members.data() + first, m); break;
        default: solve_chunk<3>(t, h, members.data() + first, m); break;
      }
    }
  }
}

namespace {

// Solves H dx = -g for a symmetric H by Cholesky, H = L L^T,
//   l_jj = sqrt(h_jj - sum_k<j l_jk^2),  l_ij = (h_ij - sum_k<j l_ik l_jk) / l_jj,
// then L z = -g and L^T dx = z; false where a pivot is not positive (H is
// not positive definite).
template <int D>
bool cholesky_solve(const double (&H)[D][D], const double (&g)[D], double (&dx)[D]) {
  double L[D][D], inv[D];  // inv: 1 / l_jj
  for (int j = 0; j < D; ++j) {
    double pivot = H[j][j];
    for (int k = 0; k < j; ++k) pivot -= L[j][k] * L[j][k];
    if (!(pivot > 0.0)) return false;
    L[j][j] = std::sqrt(pivot);
    inv[j] = 1.0 / L[j][j];
    for (int i = j + 1; i < D; ++i) {
      double sum = H[i][j];
      for (int k = 0; k < j; ++k) sum -= L[i][k] * L[j][k];
      L[i][j] = sum * inv[j];
    }
  }
  double z[D];
  for (int i = 0; i < D; ++i) {
    double sum = -g[i];
    for (int k = 0; k < i; ++k) sum -= L[i][k] * z[k];
    z[i] = sum * inv[i];
  }
  for (int i = D - 1; i >= 0; --i) {
    double sum = z[i];
    for (int k = i + 1; k < D; ++k) sum -= L[k][i] * dx[k];
    dx[i] = sum * inv[i];
  }
  return true;
}

// Whether the step dx = -H^-1 g is no longer than the inertia's alone,
// |dx| <= |g| / w, w = m_i / h^2: the longest step any H >= w I can take.
// A definite but nearly singular H_i (a compressed spring's negative
// transverse stiffness cancelling almost all of the inertia) passes
// Cholesky and throws the particle far (cloth at 1/60 s, 10 iterations: 3.6
// m in one sweep at t = 1.53 s, then 470 E_s of energy); such a step is
// taken again with the definite blocks (vbd.h).
template <int D>
bool within_inertia_step(const double (&g)[D], const double (&dx)[D], double w) {
  double dx2 = 0.0, g2 = 0.0;
  for (int r = 0; r < D; ++r) {
    dx2 += dx[r] * dx[r];
    g2 += g[r] * g[r];
  }
  return dx2 * w * w <= g2;
}

// Particle i's gradient and the symmetric part of its Hessian (vbd.h),
// from its blocks at `at` in b: g = w (x_i - y_i) - F_i,
// H = w I - sym(dF_i/dx_i) - sym(dF_i/dv_i) / h, w = m_i / h^2.
template <int D>
void local_system(const VertexBlocks& b, int at, const double* x, const double* y, double w,
                  double h, double (&g)[D], double (&H)[D][D]) {
  const double* f = b.f + at * D;
  const double* K = b.dfdx + at * D * D;
  for (int r = 0; r < D; ++r) g[r] = w * (x[r] - y[r]) - f[r];
  for (int r = 0; r < D; ++r) {
    for (int q = 0; q < D; ++q) H[r][q] = -0.5 * (K[r * D + q] + K[q * D + r]);
    H[r][r] += w;
  }
  if (b.dfdv == nullptr) return;
  const double* V = b.dfdv + at * D * D;
  for (int r = 0; r < D; ++r) {
    for (int q = 0; q < D; ++q) H[r][q] -= 0.5 * (V[r * D + q] + V[q * D + r]) / h;
  }
}

}  // namespace

template <int D>
void Vbd::solve_chunk(double t, double h, const int* particles, int count) {
  const bool damped = !dfdv_.empty();
  const bool reads_velocity = view_->reads_velocity();
  const VertexBlocks blocks{f_.data(), dfdx_.data(), damped ? dfdv_.data() : nullptr};
  view_->vertex_blocks(t, x_all_.data(), v_all_.data(), particles, count, false, blocks);
  double* x = x_all_.data();
  const double* y = y_.data();
  for (int k = 0; k < count; ++k) {
    const int i = particles[k];
    const double w = mass_[i] / (h * h);  // the inertia's curvature m_i / h^2
    double g[D], H[D][D], dx[D];
    local_system<D>(blocks, k, x + i * D, y + i * D, w, h, g, H);
    if (!cholesky_solve<D>(H, g, dx) || !within_inertia_step<D>(g, dx, w)) {
      // Indefinite, or definite but so nearly singular that the step is
      // longer than any definite H_i >= m_i / h^2 I allows: this particle's
      // blocks again, each element's share semidefinite (then H_i >= m_i /
      // h^2 I, but for a damper's symmetric part; failing that, H_i's
      // eigenvalues raised to m_i / h^2).
      ++definite_steps_;
      double f1[D], k1[D * D], v1[D * D];
      const VertexBlocks one{f1, k1, damped ? v1 : nullptr};
      view_->vertex_blocks(t, x, v_all_.data(), &i, 1, true, one);
      local_system<D>(one, 0, x + i * D, y + i * D, w, h, g, H);
      if (!cholesky_solve<D>(H, g, dx)) {
        Eigen::Matrix<double, D, D> M;
        for (int r = 0; r < D; ++r)
          for (int q = 0; q < D; ++q) M(r, q) = H[r][q];
        Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, D, D>> eig(M);
        M = eig.eigenvectors() * eig.eigenvalues().cwiseMax(w).asDiagonal() *
            eig.eigenvectors().transpose();
        for (int r = 0; r < D; ++r)
          for (int q = 0; q < D; ++q) H[r][q] = M(r, q);
        cholesky_solve<D>(H, g, dx);
      }
    }
    if (forbidden_) {
      const double cap = view_->vertex_admissible_fraction(x, i, dx);
      if (kStepCap * cap < 1.0) {
        for (int r = 0; r < D; ++r) dx[r] *= kStepCap * cap;
      }
    }
    for (int r = 0; r < D; ++r) x[i * D + r] += dx[r];
    if (reads_velocity) {
      for (int r = 0; r < D; ++r) v_all_[i * D + r] = (x[i * D + r] - x_n_[i * D + r]) / h;
    }
  }
}

void Vbd::extrapolate(double t, double h, int iteration, double rho, double& omega) {
  if (iteration == 0) return;
  const Eigen::Index n = system().dofs();
  omega = iteration == 1 ? 2.0 / (2.0 - rho * rho) : 4.0 / (4.0 - rho * rho * omega);
  if (forbidden_) x_hat_ = x_all_.head(n);
  x_all_.head(n) = omega * (x_all_.head(n) - x_before_) + x_before_;
  if (forbidden_) {
    const Vector step = x_all_.head(n) - x_hat_;
    if (!(system().admissible_fraction(x_hat_, step) > 1.0) || !admissible(t)) {
      x_all_.head(n) = x_hat_;  // the extrapolation would leave the allowed states
    }
  }
  set_velocities(h);
}

SPRINGLAB_INTEGRATOR(Vbd, vbd_integrator)

}  // namespace springlab
