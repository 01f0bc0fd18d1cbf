#include "integrators/xpbd.h"

#include <cmath>

namespace springlab {

Xpbd::Xpbd()
    : FastSolver({.name = "xpbd",
                  .scheme = "S substeps: v += h_s M^-1 F_ext, x += h_s v, N Gauss-Seidel "
                            "projections of C = |x_a - x_b| - L with compliance 1/k, "
                            "v = (x - x_prev)/h_s",
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
                                    "are explicit"}) {}

StepResult Xpbd::do_step(double h) {
  const int substeps = options().substeps > 0 ? options().substeps : kDefaultSubsteps;
  const int iterations = options().iterations > 0 ? options().iterations : kDefaultIterations;
  const double hs = h / substeps;
  lambda_.resize(static_cast<Eigen::Index>(constraints_.size()));
  for (int s = 0; s < substeps; ++s) {
    const double t = t_ + s * hs;
    eval_external_force(t, x_, v_, f_);
    v_ += hs * f_.cwiseProduct(inv_mass());
    x_prev_ = x_;
    x_ += hs * v_;
    lambda_.setZero();
    for (int it = 0; it < iterations; ++it) {
      for (std::size_t k = 0; k < constraints_.size(); ++k) {
        const DistanceConstraint& c = constraints_[k];
        if (!(c.stiffness > 0.0)) continue;
        const Eigen::Vector3d d = difference(c, x_);
        const double l = d.norm();
        if (!(l > 0.0)) continue;  // no direction (a rest-length-0 spring: C = 0 there)
        const Eigen::Vector3d n = d / l;
        const double wa = inv_particle_mass_[c.a];
        const double wb = c.b >= 0 ? inv_particle_mass_[c.b] : 0.0;
        const double compliance = 1.0 / (c.stiffness * hs * hs);
        const double dlambda =
            (-(l - c.length) - compliance * lambda_[static_cast<Eigen::Index>(k)]) /
            (wa + wb + compliance);
        for (int r = 0; r < dim_; ++r) {
          x_[c.a * dim_ + r] += wa * dlambda * n[r];
          if (c.b >= 0) x_[c.b * dim_ + r] -= wb * dlambda * n[r];
        }
        lambda_[static_cast<Eigen::Index>(k)] += dlambda;
      }
      ++mutable_stats().newton_iterations;
    }
    v_ = (x_ - x_prev_) / hs;
  }
  return StepResult::success();
}

}  // namespace springlab
