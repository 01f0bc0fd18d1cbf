#include "integrators/fast/xpbd.h"

#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

#include "integrators/core/integrator_entry.h"

namespace springlab {

Xpbd::Xpbd()
    : FastSolver({.name = "xpbd",
                  .scheme = "S substeps: v += h_s M^-1 F_ext, x += h_s v, N Gauss-Seidel "
                            "projections of C = |x_a - x_b| - L with compliance 1/k (elements: "
                            "C = |F - R(F)|, compliance 1/w), v = (x - x_prev)/h_s",
                  .order = 1,
                  .implicit = true,
                  .jacobian_free = true,
                  // On springs of rest length 0, one iteration per substep is
                  // S implicit Euler steps of h/S; spring damping, drag and
                  // wind act explicitly, so a stiff damper limits the step
                  // (tests/test_stability_property.cc shows both).
                  .stability = StabilityKind::kL,
                  .stability_limit = kInfinity,
                  .stability_note = "for linear springs, one iteration per substep (S implicit "
                                    "Euler steps of h/S); unconverged projections of stiff "
                                    "nonlinear springs can gain energy; damping, drag and wind "
                                    "are explicit"}) {
  takes_projections_ = true;
}

StepResult Xpbd::do_initialize() {
  StepResult result = FastSolver::do_initialize();
  if (!result.ok) return result;
  // The constraints come in the model's order (the scene's, for springs):
  // the Gauss-Seidel pass projects them so.
  projections_.clear();
  stiffness_.clear();
  for (const DistanceConstraint& c : constraints_) {
    if (!(c.stiffness > 0.0)) continue;
    Projection p{.a = c.a * dim_,
                 .b = c.b >= 0 ? c.b * dim_ : -1,
                 .wa = inv_particle_mass_[c.a],
                 .wb = c.b >= 0 ? inv_particle_mass_[c.b] : 0.0,
                 .length = c.length,
                 .compliance = 0.0,
                 .anchor = {c.anchor[0], c.anchor[1], c.anchor[2]}};
    projections_.push_back(p);
    stiffness_.push_back(c.stiffness);
  }
  compliance_hs_ = 0.0;
  return StepResult::success();
}

template <int D>
void Xpbd::project_constraints() {
  double* x = x_.data();
  double* lambda = lambda_.data();
  const std::size_t count = projections_.size();
  for (std::size_t k = 0; k < count; ++k) {
    const Projection& c = projections_[k];
    double* xa = x + c.a;
    double* xb = c.b >= 0 ? x + c.b : nullptr;
    const double* end_b = xb != nullptr ? xb : c.anchor;
    double d[D];
    double l2 = 0.0;
    for (int r = 0; r < D; ++r) {
      d[r] = xa[r] - end_b[r];
      l2 += d[r] * d[r];
    }
    if (!(l2 > 0.0)) continue;  // no direction (a rest-length-0 spring: C = 0 there)
    const double l = std::sqrt(l2);
    // dlambda = (-C - a~ lambda) / (w_a + w_b + a~), and the correction
    // w dlambda n = w (dlambda / l) d.
    const double dlambda = (-(l - c.length) - c.compliance * lambda[k]) /
                           (c.wa + c.wb + c.compliance);
    const double step = dlambda / l;
    for (int r = 0; r < D; ++r) xa[r] += c.wa * step * d[r];
    if (xb != nullptr) {
      for (int r = 0; r < D; ++r) xb[r] -= c.wb * step * d[r];
    }
    lambda[k] += dlambda;
  }
}

void Xpbd::predict(double hs) {
  const Eigen::Index n = x_.size();
  double* x = x_.data();
  double* v = v_.data();
  double* x_prev = x_prev_.data();
  const double* f = f_.data();
  const double* w = inv_mass().data();
  for (Eigen::Index i = 0; i < n; ++i) {
    v[i] += hs * (f[i] * w[i]);
    x_prev[i] = x[i];
    x[i] += hs * v[i];
  }
}

StepResult Xpbd::do_step(double h) {
  const int substeps = this->substeps(options());
  const int iterations = options().iterations > 0 ? options().iterations : kDefaultIterations;
  const double hs = h / substeps;
  if (hs != compliance_hs_) {
    for (std::size_t k = 0; k < projections_.size(); ++k) {
      projections_[k].compliance = 1.0 / (stiffness_[k] * hs * hs);
    }
    compliance_hs_ = hs;
  }
  lambda_.resize(static_cast<Eigen::Index>(projections_.size()));
  lambda_elements_.resize(static_cast<Eigen::Index>(elements_.size()));
  lambda_planes_.resize(static_cast<Eigen::Index>(planes_.size()) * inv_particle_mass_.size());
  x_prev_.resize(x_.size());
  for (int s = 0; s < substeps; ++s) {
    const double t = t_ + s * hs;
    eval_external_force(t, x_, v_, f_);
    predict(hs);
    for (const auto& projection : position_projections_) projection->begin(x_);
    lambda_.setZero();
    if (!elements_.empty()) lambda_elements_.setZero();
    if (!planes_.empty()) lambda_planes_.setZero();
    for (int it = 0; it < iterations; ++it) {
      switch (dim_) {
        case 1: project_constraints<1>(); break;
        case 2: project_constraints<2>(); break;
        default: project_constraints<3>(); break;
      }
      if (!elements_.empty()) project_elements(hs);
      for (const auto& projection : position_projections_) projection->project(x_, hs);
      if (!planes_.empty()) project_planes(hs);
      ++mutable_stats().newton_iterations;
    }
    v_ = (x_ - x_prev_) / hs;
    for (const auto& projection : position_projections_) projection->correct_velocity(x_, v_, hs);
    if (!planes_.empty()) apply_friction(hs);
  }
  return StepResult::success();
}

void Xpbd::project_elements(double hs) {
  for (std::size_t k = 0; k < elements_.size(); ++k) {
    const ProjectiveElement& e = elements_[k];
    const Eigen::Index nodes = static_cast<Eigen::Index>(e.nodes.size());
    ProjectiveElement::Deformation F = ProjectiveElement::Deformation::Zero(dim_, e.G.cols());
    for (Eigen::Index j = 0; j < nodes; ++j) {
      const int p = e.nodes[static_cast<std::size_t>(j)];
      for (int r = 0; r < dim_; ++r) {
        F.row(r) += (p >= 0 ? x_[p * dim_ + r] : e.fixed[static_cast<std::size_t>(j)][r]) *
                    e.G.row(j);
      }
    }
    const ProjectiveElement::Deformation D = F - e.project(F);
    const double C = D.norm();
    if (!(C > 0.0)) continue;  // on the set: no direction
    // Column i: grad_i C.
    const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, 3, 4> grad =
        D * e.G.transpose() / C;
    double denominator = 1.0 / (e.weight * hs * hs);       // a~
    const double compliance = denominator;
    for (Eigen::Index i = 0; i < nodes; ++i) {
      const int p = e.nodes[static_cast<std::size_t>(i)];
      if (p >= 0) denominator += inv_particle_mass_[p] * grad.col(i).squaredNorm();
    }
    double& lambda = lambda_elements_[static_cast<Eigen::Index>(k)];
    const double dlambda = (-C - compliance * lambda) / denominator;
    for (Eigen::Index i = 0; i < nodes; ++i) {
      const int p = e.nodes[static_cast<std::size_t>(i)];
      if (p < 0) continue;
      for (int r = 0; r < dim_; ++r) {
        x_[p * dim_ + r] += inv_particle_mass_[p] * dlambda * grad(r, i);
      }
    }
    lambda += dlambda;
  }
}

void Xpbd::project_planes(double hs) {
  const Eigen::Index n = inv_particle_mass_.size();
  for (std::size_t p = 0; p < planes_.size(); ++p) {
    const PlaneConstraint& plane = planes_[p];
    const double compliance = plane.stiffness > 0.0 ? 1.0 / (plane.stiffness * hs * hs) : 0.0;
    for (Eigen::Index i = 0; i < n; ++i) {
      double& lambda = lambda_planes_[static_cast<Eigen::Index>(p) * n + i];
      const double d = gap(plane, x_, i);
      if (d >= 0.0 && lambda == 0.0) continue;  // apart, and never pushed this substep
      const double w = inv_particle_mass_[i];
      // The inequality: lambda + dlambda >= 0.
      const double dlambda =
          std::max((-d - compliance * lambda) / (w + compliance), -lambda);
      for (int r = 0; r < dim_; ++r) x_[i * dim_ + r] += w * dlambda * plane.normal[r];
      lambda += dlambda;
      // Static friction: the tangential displacement of the substep is
      // undone when the force that takes, |dx_t| / (w h_s^2), is within
      // mu f_n = mu lambda / h_s^2.
      if (!(plane.friction > 0.0) || !(lambda > 0.0)) continue;
      Eigen::Vector3d dx = Eigen::Vector3d::Zero();
      double dn = 0.0;
      for (int r = 0; r < dim_; ++r) {
        dx[r] = x_[i * dim_ + r] - x_prev_[i * dim_ + r];
        dn += plane.normal[r] * dx[r];
      }
      const Eigen::Vector3d dx_t = dx - dn * plane.normal;
      if (dx_t.norm() <= plane.friction * w * lambda) {
        for (int r = 0; r < dim_; ++r) x_[i * dim_ + r] -= dx_t[r];
      }
    }
  }
}

void Xpbd::apply_friction(double hs) {
  const Eigen::Index n = inv_particle_mass_.size();
  for (std::size_t p = 0; p < planes_.size(); ++p) {
    const PlaneConstraint& plane = planes_[p];
    if (!(plane.friction > 0.0)) continue;
    for (Eigen::Index i = 0; i < n; ++i) {
      const double lambda = lambda_planes_[static_cast<Eigen::Index>(p) * n + i];
      if (!(lambda > 0.0)) continue;
      // |dv| = h_s mu f_n / m with f_n = lambda / h_s^2, at most the speed.
      slow_tangential_velocity(plane, i, plane.friction * lambda * inv_particle_mass_[i] / hs);
    }
  }
}

SPRINGLAB_INTEGRATOR(Xpbd, xpbd_integrator)

}  // namespace springlab
