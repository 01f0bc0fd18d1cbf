#include "integrators/fast/projective_dynamics.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <string>
#include <utility>
#include <vector>

#include "integrators/core/integrator_entry.h"

namespace springlab {

ProjectiveDynamics::ProjectiveDynamics()
    : FastSolver({.name = "projective-dynamics",
                  .scheme = "y = x + h v + h^2 M^-1 F_ext; N x (p_c = L_c d_c/|d_c|, "
                            "elements' R(F), (M + h D + h^2 L) x' = M y + h D (x + h v) + "
                            "h^2 J p); v' = (x' - x)/h",
                  .order = 1,
                  .implicit = true,
                  .jacobian_free = true,
                  // One global solve is implicit Euler on springs of rest
                  // length 0 with drag; spring damping acts explicitly, so
                  // a stiff damper between particles limits the step
                  // (tests/test_stability_property.cc).
                  .stability = StabilityKind::kL,
                  .stability_limit = kInfinity,
                  .stability_note = "for linear springs, drag and wind (one iteration is "
                                    "implicit Euler); spring damping is explicit"}) {}

std::string ProjectiveDynamics::check_options(const IntegratorOptions& options,
                                              Eigen::Index) const {
  if (options.chebyshev == kChebyshevOn && !options.no_chebyshev) {
    return name() + ": --chebyshev needs RHO, the plain iteration's spectral radius in (0, 1) "
                    "(docs/integrators.md \"Fast solvers\": watch the solver error fall with "
                    "--iterations), e.g. --chebyshev 0.99";
  }
  return {};
}

StepResult ProjectiveDynamics::do_initialize() {
  StepResult base = FastSolver::do_initialize();
  if (!base.ok) return base;
  contacts_.clear();
  laplacian_ = constraint_laplacian(constraints_, elements_, inv_particle_mass_.size());
  springs_.clear();
  anchors_.clear();
  for (const DistanceConstraint& c : constraints_) {
    int b = c.b;
    if (b < 0) {
      anchors_.push_back(c.anchor);
      b = -static_cast<int>(anchors_.size());  // -1 - its index
    }
    springs_.push_back({c.a, b, c.stiffness, c.length});
  }
  read_linear_damping();
  factored_h_ = 0.0;
  return StepResult::success();
}

void ProjectiveDynamics::read_linear_damping() {
  damping_.resize(0);
  // Only where F is affine in v with a diagonal dF/dv (MechanicalSystem::
  // velocity_dependence); coupled (spring damping) or nonlinear (friction)
  // velocity dependence stays explicit.
  if (system().velocity_dependence() != VelocityDependence::kDiagonal) return;
  SparseMatrix dfdv;
  eval_jacobians(t_, x_, v_, nullptr, &dfdv);
  const Eigen::Index n = inv_particle_mass_.size();
  Vector d(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    d[i] = -dfdv.coeff(i * dim_, i * dim_);
    // One factor serves every coordinate: D must be the same for each.
    for (int r = 1; r < dim_; ++r) {
      if (-dfdv.coeff(i * dim_ + r, i * dim_ + r) != d[i]) return;
    }
  }
  if (n == 0 || !(d.minCoeff() >= 0.0) || !(d.maxCoeff() > 0.0)) return;
  damping_ = std::move(d);
}

bool ProjectiveDynamics::factor(double h, std::string& error) {
  // The grid's steps t_{k+1} - t_k differ in their last bits: one factor
  // serves steps equal to 1e-12 (the matrix then differs by less).
  if (std::abs(h - factored_h_) <= 1e-12 * h) return true;
  SparseMatrix a = (h * h) * laplacian_;
  for (Eigen::Index i = 0; i < a.rows(); ++i) a.coeffRef(i, i) += 1.0 / inv_particle_mass_[i];
  for (Eigen::Index i = 0; i < damping_.size(); ++i) a.coeffRef(i, i) += h * damping_[i];
  for (const ContactPair& c : contacts_) {
    a.coeffRef(c.particle, c.particle) += h * h * planes_[c.plane].stiffness;
  }
  ++mutable_stats().factorizations;
  if (!solver_.factorize(a, MatrixKind::kPositiveDefinite)) {
    error = solver_.error();
    return false;
  }
  factored_h_ = h;
  return true;
}

bool ProjectiveDynamics::update_contacts() {
  std::vector<ContactPair> now;
  const Eigen::Index n = inv_particle_mass_.size();
  for (std::size_t p = 0; p < planes_.size(); ++p) {
    for (Eigen::Index i = 0; i < n; ++i) {
      if (gap(planes_[p], x_, i) < 0.0 || gap(planes_[p], y_, i) < 0.0) now.push_back({i, p});
    }
  }
  if (now == contacts_) return false;
  contacts_.swap(now);
  return true;
}

void ProjectiveDynamics::apply_friction(double h) {
  for (const ContactPair& c : contacts_) {
    const PlaneConstraint& plane = planes_[c.plane];
    const double depth = -gap(plane, x_new_, c.particle);
    if (!(plane.friction > 0.0) || !(depth > 0.0)) continue;
    const Eigen::Index i = c.particle;
    const double w = inv_particle_mass_[i];
    const double limit = plane.friction * plane.stiffness * depth;  // mu f_n
    Eigen::Vector3d dx = Eigen::Vector3d::Zero();
    for (int r = 0; r < dim_; ++r) dx[r] = x_new_[i * dim_ + r] - x_[i * dim_ + r];
    Eigen::Vector3d dx_t = dx - dx.dot(plane.normal) * plane.normal;
    // Static: undo the tangential displacement if mu f_n can.
    if (dx_t.norm() <= limit * w * h * h) {
      for (int r = 0; r < dim_; ++r) {
        x_new_[i * dim_ + r] -= dx_t[r];
        v_[i * dim_ + r] = (x_new_[i * dim_ + r] - x_[i * dim_ + r]) / h;
      }
      continue;
    }
    // Dynamic: slow the tangential velocity by h mu f_n / m.
    slow_tangential_velocity(plane, i, h * limit * w);
  }
}

void ProjectiveDynamics::predict(double h) {
  eval_external_force(t_, x_, v_, f_);
  y_ = x_ + h * v_ + (h * h) * f_.cwiseProduct(inv_mass());
  if (!planes_.empty() && update_contacts()) factored_h_ = 0.0;  // a new matrix
}

void ProjectiveDynamics::begin_right_hand_side(double h) {
  // M y, and the drag's h D (x_n + h v_n) (projective_dynamics.h).
  const Eigen::Index n = inv_particle_mass_.size();
  rhs_start_.resize(y_.size());
  for (Eigen::Index i = 0; i < n; ++i) {
    for (int r = 0; r < dim_; ++r) rhs_start_[i * dim_ + r] = y_[i * dim_ + r] / inv_particle_mass_[i];
  }
  if (damping_.size() == 0) return;
  for (Eigen::Index i = 0; i < n; ++i) {
    for (int r = 0; r < dim_; ++r) {
      const Eigen::Index k = i * dim_ + r;
      rhs_start_[k] += h * damping_[i] * (x_[k] + h * v_[k]);
    }
  }
}

namespace {

// rhs += h^2 J p, p_c = L_c d_c / |d_c| at x (the springs' local steps),
// for D coordinates per particle: the loop of every iteration, so its
// dimension is a constant, it reads 24 bytes per spring, and |d_c| is summed
// in scalars, (d_0^2 + d_1^2) + d_2^2, the order of Eigen's norm() of a
// Vector3d, without its 16-byte load of two values just stored, which
// stalled the loop (perf, cloth 64: 37 % of the run's time for 17 % of its
// instructions). Before, with the dimension read at run time, the
// difference out of line and 56-byte constraints: 177 instructions per
// spring (callgrind, cloth 32), now 71.
template <int D>
void add_spring_projections_d(const std::vector<ProjectiveDynamics::LocalSpring>& springs,
                              const std::vector<Eigen::Vector3d>& anchors, const Vector& x,
                              double h, Vector& rhs) {
  const double* xs = x.data();
  double* b = rhs.data();
  for (const ProjectiveDynamics::LocalSpring& c : springs) {
    const double* xa = xs + static_cast<std::ptrdiff_t>(c.a) * D;
    const double* anchor =
        c.b < 0 ? anchors[static_cast<std::size_t>(-1 - c.b)].data() : nullptr;
    const double* xb = anchor != nullptr ? anchor : xs + static_cast<std::ptrdiff_t>(c.b) * D;
    double d[D];  // d_c = x_a - x_b (or the anchor)
    for (int r = 0; r < D; ++r) d[r] = xa[r] - xb[r];
    double l2 = d[0] * d[0];
    for (int r = 1; r < D; ++r) l2 += d[r] * d[r];
    const double l = std::sqrt(l2);
    double p[D];
    const double scale = l > 0.0 ? c.length / l : 0.0;
    for (int r = 0; r < D; ++r) p[r] = l > 0.0 ? scale * d[r] : 0.0;
    const double w = h * h * c.stiffness;
    double* ba = b + static_cast<std::ptrdiff_t>(c.a) * D;
    if (anchor == nullptr) {
      double* bb = b + static_cast<std::ptrdiff_t>(c.b) * D;
      for (int r = 0; r < D; ++r) {
        ba[r] += w * p[r];
        bb[r] -= w * p[r];
      }
    } else {
      for (int r = 0; r < D; ++r) ba[r] += w * (anchor[r] + p[r]);
    }
  }
}

}  // namespace

void ProjectiveDynamics::add_spring_projections(double h) {
  switch (dim_) {
    case 1: add_spring_projections_d<1>(springs_, anchors_, x_new_, h, rhs_); break;
    case 2: add_spring_projections_d<2>(springs_, anchors_, x_new_, h, rhs_); break;
    default: add_spring_projections_d<3>(springs_, anchors_, x_new_, h, rhs_); break;
  }
}

// Elements (Bouaziz et al. 2014): E = w/2 |F - T|^2 with T = project(F) at
// the current x adds w (T g_i - sum over fixed nodes j of (g_i . g_j) x_j)
// to free node i.
void ProjectiveDynamics::add_element_projections(double h) {
  for (const ProjectiveElement& e : elements_) {
    const Eigen::Index k = e.G.cols();
    ProjectiveElement::Deformation F = ProjectiveElement::Deformation::Zero(dim_, k);
    for (std::size_t j = 0; j < e.nodes.size(); ++j) {
      for (int r = 0; r < dim_; ++r) {
        const double xr = e.nodes[j] >= 0 ? x_new_[e.nodes[j] * dim_ + r] : e.fixed[j][r];
        F.row(r) += xr * e.G.row(static_cast<Eigen::Index>(j));
      }
    }
    // Column i: T g_i.
    const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, 3, 4> TGt =
        e.project(F) * e.G.transpose();
    const double w = h * h * e.weight;
    for (std::size_t i = 0; i < e.nodes.size(); ++i) {
      if (e.nodes[i] < 0) continue;
      const auto gi = e.G.row(static_cast<Eigen::Index>(i));
      for (int r = 0; r < dim_; ++r) {
        double sum = TGt(r, static_cast<Eigen::Index>(i));
        for (std::size_t j = 0; j < e.nodes.size(); ++j) {
          if (e.nodes[j] >= 0) continue;
          sum -= gi.dot(e.G.row(static_cast<Eigen::Index>(j))) * e.fixed[j][r];
        }
        rhs_[e.nodes[i] * dim_ + r] += w * sum;
      }
    }
  }
}

// Contacts: the projection P(x_i) onto the plane's half-space.
void ProjectiveDynamics::add_contact_projections(double h) {
  for (const ContactPair& c : contacts_) {
    const PlaneConstraint& plane = planes_[c.plane];
    const double d = std::min(gap(plane, x_new_, c.particle), 0.0);
    const double w = h * h * plane.stiffness;
    for (int r = 0; r < dim_; ++r) {
      rhs_[c.particle * dim_ + r] += w * (x_new_[c.particle * dim_ + r] - d * plane.normal[r]);
    }
  }
}

// The global step: the coordinates as the columns of an n x dim matrix,
// solved together with the one factor.
bool ProjectiveDynamics::global_solve() {
  const Eigen::Index n = inv_particle_mass_.size();
  columns_ = Eigen::Map<const Eigen::MatrixXd>(rhs_.data(), dim_, n).transpose();
  mutable_stats().linear_solves += dim_;
  if (!solver_.solve(columns_, solved_)) return false;
  Eigen::Map<Eigen::MatrixXd>(x_new_.data(), dim_, n) = solved_.transpose();
  return true;
}

// Wang 2015: x^(k+1) = omega (xh - x^(k-1)) + x^(k-1), w_2 = 2 / (2 - rho^2),
// then w_(k+1) = 4 / (4 - rho^2 w_k); the first iteration is not extrapolated.
void ProjectiveDynamics::extrapolate(int iteration, double rho, double& omega) {
  if (iteration == 0) return;
  omega = iteration == 1 ? 2.0 / (2.0 - rho * rho) : 4.0 / (4.0 - rho * rho * omega);
  x_new_ = omega * (x_new_ - x_before_) + x_before_;
}

StepResult ProjectiveDynamics::do_step(double h) {
  std::string error;
  const int iterations = options().iterations > 0 ? options().iterations : kDefaultIterations;
  predict(h);
  if (!factor(h, error)) {
    return StepResult::failure(name() + ": the matrix M + h D + h^2 L is singular (" + error + ")");
  }
  begin_right_hand_side(h);
  x_new_ = y_;
  // 0 is off, as is --no-chebyshev.
  const double rho = options().no_chebyshev ? 0.0 : options().chebyshev;
  double omega = 1.0;
  for (int it = 0; it < iterations; ++it) {
    if (rho > 0.0) {  // keep x^(k-1) and x^(k) for the extrapolation
      x_before_.swap(x_last_);
      x_last_ = x_new_;
    }
    rhs_ = rhs_start_;
    add_spring_projections(h);
    add_element_projections(h);
    add_contact_projections(h);
    if (!global_solve()) {
      return StepResult::failure(name() + ": the global solve gave a non-finite position");
    }
    if (rho > 0.0) extrapolate(it, rho, omega);
    ++mutable_stats().newton_iterations;
  }
  v_ = (x_new_ - x_) / h;
  if (!planes_.empty()) apply_friction(h);
  x_.swap(x_new_);
  return StepResult::success();
}

SPRINGLAB_INTEGRATOR(ProjectiveDynamics, projective_dynamics_integrator)

}  // namespace springlab
