#include "integrators/projective_dynamics.h"

#include <algorithm>
#include <cmath>
#include <vector>

namespace springlab {

ProjectiveDynamics::ProjectiveDynamics()
    : FastSolver({.name = "projective-dynamics",
                  .scheme = "y = x + h v + h^2 M^-1 F_ext; N x (p_c = L_c d_c/|d_c|, "
                            "elements' R(F), (M + h^2 L) x' = M y + h^2 J p); v' = (x' - x)/h",
                  .order = 1,
                  .implicit = true,
                  .jacobian_free = true,
                  // One global solve is implicit Euler on springs of rest
                  // length 0; damping, drag and wind act explicitly, so a
                  // stiff damper limits the step (tests/test_stability_property.cc).
                  .stability = StabilityKind::kL,
                  .stability_limit = kInfinity,
                  .stability_note = "for linear springs (one iteration is implicit Euler); "
                                    "damping, drag and wind are explicit"}) {}

StepResult ProjectiveDynamics::do_initialize() {
  StepResult base = FastSolver::do_initialize();
  if (!base.ok) return base;
  contacts_.clear();
  laplacian_ = constraint_laplacian(constraints_, elements_, inv_particle_mass_.size());
  factored_h_ = 0.0;
  return StepResult::success();
}

bool ProjectiveDynamics::factor(double h, std::string& error) {
  // The grid's steps t_{k+1} - t_k differ in their last bits: one factor
  // serves steps equal to 1e-12 (the matrix then differs by less).
  if (std::abs(h - factored_h_) <= 1e-12 * h) return true;
  SparseMatrix a = (h * h) * laplacian_;
  for (Eigen::Index i = 0; i < a.rows(); ++i) a.coeffRef(i, i) += 1.0 / inv_particle_mass_[i];
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

StepResult ProjectiveDynamics::do_step(double h) {
  std::string error;
  const int iterations = options().iterations > 0 ? options().iterations : kDefaultIterations;
  eval_external_force(t_, x_, v_, f_);
  y_ = x_ + h * v_ + (h * h) * f_.cwiseProduct(inv_mass());
  if (!planes_.empty() && update_contacts()) factored_h_ = 0.0;  // a new matrix
  if (!factor(h, error)) {
    return StepResult::failure(name() + ": the matrix M + h^2 L is singular (" + error + ")");
  }
  x_new_ = y_;
  const Eigen::Index n = inv_particle_mass_.size();
  const double rho = options().chebyshev;
  double omega = 1.0;
  for (int it = 0; it < iterations; ++it) {
    if (rho > 0.0) {  // keep x^(k-1) and x^(k) for the extrapolation below
      x_before_.swap(x_last_);
      x_last_ = x_new_;
    }
    // rhs = M y + h^2 J p, p from the current x (the local step).
    rhs_.resize(y_.size());
    for (Eigen::Index i = 0; i < n; ++i) {
      for (int r = 0; r < dim_; ++r) rhs_[i * dim_ + r] = y_[i * dim_ + r] / inv_particle_mass_[i];
    }
    for (const DistanceConstraint& c : constraints_) {
      const Eigen::Vector3d d = difference(c, x_new_);
      const double l = d.norm();
      const Eigen::Vector3d p = l > 0.0 ? Eigen::Vector3d(c.length / l * d) : Eigen::Vector3d::Zero();
      const double w = h * h * c.stiffness;
      for (int r = 0; r < dim_; ++r) {
        if (c.b >= 0) {
          rhs_[c.a * dim_ + r] += w * p[r];
          rhs_[c.b * dim_ + r] -= w * p[r];
        } else {
          rhs_[c.a * dim_ + r] += w * (c.anchor[r] + p[r]);
        }
      }
    }
    // Elements (Bouaziz et al. 2014): E = w/2 |F - T|^2 with T = project(F)
    // at the current x adds w (T g_i - sum over fixed nodes j of
    // (g_i . g_j) x_j) to free node i.
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
    // Contacts: the projection P(x_i) onto the plane's half-space.
    for (const ContactPair& c : contacts_) {
      const PlaneConstraint& plane = planes_[c.plane];
      const double d = std::min(gap(plane, x_new_, c.particle), 0.0);
      const double w = h * h * plane.stiffness;
      for (int r = 0; r < dim_; ++r) {
        rhs_[c.particle * dim_ + r] += w * (x_new_[c.particle * dim_ + r] - d * plane.normal[r]);
      }
    }
    // The global step: the coordinates as the columns of an n x dim matrix,
    // solved together with the one factor.
    columns_ = Eigen::Map<const Eigen::MatrixXd>(rhs_.data(), dim_, n).transpose();
    mutable_stats().linear_solves += dim_;
    if (!solver_.solve(columns_, solved_)) {
      return StepResult::failure(name() + ": the global solve gave a non-finite position");
    }
    Eigen::Map<Eigen::MatrixXd>(x_new_.data(), dim_, n) = solved_.transpose();
    if (rho > 0.0 && it > 0) {
      // Wang 2015: w_2 = 2 / (2 - rho^2), then w_(k+1) = 4 / (4 - rho^2 w_k).
      omega = it == 1 ? 2.0 / (2.0 - rho * rho) : 4.0 / (4.0 - rho * rho * omega);
      x_new_ = omega * (x_new_ - x_before_) + x_before_;
    }
    ++mutable_stats().newton_iterations;
  }
  v_ = (x_new_ - x_) / h;
  if (!planes_.empty()) apply_friction(h);
  x_.swap(x_new_);
  return StepResult::success();
}

}  // namespace springlab
