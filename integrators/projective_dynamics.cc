#include "integrators/projective_dynamics.h"

#include <cmath>
#include <vector>

namespace springlab {

ProjectiveDynamics::ProjectiveDynamics()
    : FastSolver({.name = "projective-dynamics",
                  .scheme = "y = x + h v + h^2 M^-1 F_ext; N x (p_c = L_c d_c/|d_c|, "
                            "(M + h^2 L) x' = M y + h^2 J p); v' = (x' - x)/h",
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
  if (!planes_.empty()) {
    // A plane's projection enters the global matrix only where it is
    // active, which would need a new factorization whenever contacts change.
    return StepResult::failure(
        "projective-dynamics: this scene has contact planes, which projective-dynamics does not "
        "solve yet; use xpbd or implicit-euler, or an explicit method at a small --dt");
  }
  const Eigen::Index n = inv_particle_mass_.size();
  std::vector<Eigen::Triplet<double>> entries;
  for (const DistanceConstraint& c : constraints_) {
    entries.emplace_back(c.a, c.a, c.stiffness);
    if (c.b >= 0) {
      entries.emplace_back(c.b, c.b, c.stiffness);
      entries.emplace_back(c.a, c.b, -c.stiffness);
      entries.emplace_back(c.b, c.a, -c.stiffness);
    }
  }
  for (Eigen::Index i = 0; i < n; ++i) entries.emplace_back(i, i, 0.0);  // the full diagonal
  laplacian_.resize(n, n);
  laplacian_.setFromTriplets(entries.begin(), entries.end());
  laplacian_.makeCompressed();
  factored_h_ = 0.0;
  return StepResult::success();
}

bool ProjectiveDynamics::factor(double h, std::string& error) {
  // The grid's steps t_{k+1} - t_k differ in their last bits: one factor
  // serves steps equal to 1e-12 (the matrix then differs by less).
  if (std::abs(h - factored_h_) <= 1e-12 * h) return true;
  SparseMatrix a = (h * h) * laplacian_;
  for (Eigen::Index i = 0; i < a.rows(); ++i) a.coeffRef(i, i) += 1.0 / inv_particle_mass_[i];
  ++mutable_stats().factorizations;
  if (!solver_.factorize(a, MatrixKind::kPositiveDefinite)) {
    error = solver_.error();
    return false;
  }
  factored_h_ = h;
  return true;
}

StepResult ProjectiveDynamics::do_step(double h) {
  std::string error;
  if (!factor(h, error)) {
    return StepResult::failure(name() + ": the matrix M + h^2 L is singular (" + error + ")");
  }
  const int iterations = options().iterations > 0 ? options().iterations : kDefaultIterations;
  eval_external_force(t_, x_, v_, f_);
  y_ = x_ + h * v_ + (h * h) * f_.cwiseProduct(inv_mass());
  x_new_ = y_;
  const Eigen::Index n = inv_particle_mass_.size();
  for (int it = 0; it < iterations; ++it) {
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
    // The global step, coordinate by coordinate with the one factor.
    coordinate_.resize(n);
    Vector solution;
    for (int r = 0; r < dim_; ++r) {
      for (Eigen::Index i = 0; i < n; ++i) coordinate_[i] = rhs_[i * dim_ + r];
      ++mutable_stats().linear_solves;
      if (!solver_.solve(coordinate_, solution)) {
        return StepResult::failure(name() + ": the global solve gave a non-finite position");
      }
      for (Eigen::Index i = 0; i < n; ++i) x_new_[i * dim_ + r] = solution[i];
    }
    ++mutable_stats().newton_iterations;
  }
  v_ = (x_new_ - x_) / h;
  x_.swap(x_new_);
  return StepResult::success();
}

}  // namespace springlab
