#include "integrators/newton/incremental_potential_check.h"
#include "integrators/newton/newton_tolerances.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

namespace springlab {
namespace {

// Units of round-off of Phi's terms (as Newton's line search).
using newton::kRoundoff;

}  // namespace

void IncrementalPotentialCheck::begin(VelocityStep& step, double tol, bool solved_as_is) {
  const VelocityImplicitScheme& s = step.scheme();
  active_ = step.has_potential() && solved_as_is;
  if (!active_) return;
  // v_kept: x*(v) = x_n + x_o + h (a v_n + b v) = x_n.
  const Vector& v_n = step.v_n();
  v_kept_ = (-s.a / s.b) * v_n;
  if (s.x_offset != nullptr) v_kept_ -= (1.0 / (step.h() * s.b)) * *s.x_offset;
  if (!start_potentials(step)) {
    active_ = false;  // nothing to compare with
    return;
  }
  // The energy of a velocity error of tol (the header).
  resolution_ = 0.5 * tol * tol * step.system().mass().sum();
  // Backward Euler on a conservative system: Phi(v_kept) = Phi(0) = H_n.
  judges_energy_ = s.a == 0.0 && s.b == 1.0 && s.c == 1.0 &&
                   s.weight == 1.0 && s.inertia == nullptr && s.x_offset == nullptr &&
                   step.system().velocity_dependence() == VelocityDependence::kNone;
}

bool IncrementalPotentialCheck::start_potentials(VelocityStep& step) {
  follows_ = step.follows();
  const Vector& v_n = step.start();
  double magnitude_kept = 0.0, magnitude_n = 0.0;
  step.stage(v_kept_);
  phi_kept_ = step.potential(v_kept_, magnitude_kept);
  step.stage(v_n);
  const double phi_n = step.potential(v_n, magnitude_n);
  if (!std::isfinite(phi_kept_)) return false;
  // (A non-finite Phi(v_n): a state with no energy.)
  const bool kept_lower = !(phi_n < phi_kept_);
  phi_start_ = kept_lower ? phi_kept_ : phi_n;
  noise_scale_ = kept_lower ? magnitude_kept : std::max(magnitude_kept, magnitude_n);
  return true;
}

std::string IncrementalPotentialCheck::judge(VelocityStep& step, const Vector& v, double tol,
                                             Vector& r, NewtonLinearSolver& linear) {
  if (!active_) return {};
  // Where the solve set the step up again (the contacts between bodies found
  // again at an iterate: VelocityStep::follow), Phi is another function:
  // the start's values are those of the step as it now is.
  if (step.follows() != follows_ && !start_potentials(step)) return {};
  double magnitude_end = 0.0;
  step.stage(v);
  const double phi_end = step.potential(v, magnitude_end);
  // (At least the smallest normal double: a state decayed into denormals,
  // 0 J to 4.9e-324 J, has nothing left to compare.)
  double noise = std::max(kRoundoff * std::max(noise_scale_, magnitude_end),
                          std::numeric_limits<double>::min());
  // Backward Euler's energy H(v) = Phi(v) - |v - v_n|^2_M / 2 + |v|^2_M / 2.
  const Vector& v_n = step.v_n();
  const Vector& mass = step.system().mass();
  const bool energy_judged = judges_energy_;
  double inertia = 0.0, kinetic = 0.0;
  if (energy_judged) {
    inertia = 0.5 * (v - v_n).cwiseAbs2().dot(mass);
    kinetic = 0.5 * v.cwiseAbs2().dot(mass);
  }
  const double energy_end = phi_end - inertia + kinetic;
  double energy_noise = noise + kRoundoff * (inertia + kinetic);  // the two terms' round-off
  auto within_noise = [&] {
    return phi_end <= phi_start_ + noise &&
           (!energy_judged || energy_end <= phi_kept_ + energy_noise);
  };
  if (within_noise()) return {};
  // The stored energy's own round-off, which its sum hides where its terms
  // cancel (VelocityStep::stored_magnitude), at the answer and at v_kept:
  // a cantilever's static step rose from -0.246281 J by 1.4e-13 J, 600
  // units of round-off of the sum but 2.5 of its terms (+-25 J), as the
  // BLAS kernel rounds the factorization.
  const double stored = step.stored_magnitude();
  step.stage(v_kept_);
  const double stored_kept = step.stored_magnitude();
  step.stage(v);
  noise += kRoundoff * std::max(stored, stored_kept);
  energy_noise += kRoundoff * std::max(stored, stored_kept);
  if (within_noise()) return {};
  // Above the start by more than round-off: still a solution if within the
  // tolerance of a minimizer v* no higher than the start. Newton's next
  // update d = H^-1 r (H the definite Newton matrix at v) estimates
  // v - v*, and Phi(v) - Phi(v*) ~ r.d / 2 (the header; twice that
  // allowed) where ||d||_inf is within the tolerance (at least v's
  // round-off); otherwise v is no answer to the tolerance.
  step.residual(v, r);
  const double resolved_tol = std::max(
      tol, kRoundoff * (v.lpNorm<Eigen::Infinity>() + v_n.lpNorm<Eigen::Infinity>()));
  std::string error;
  step.matrix(v, true, linear);
  const bool within =
      linear.solve(r, {.rtol = 1e-3, .atol = 0.0, .truncate = false}, d_, error).ok &&
      d_.lpNorm<Eigen::Infinity>() <= resolved_tol;
  step.stage(v);
  const double allowance = (within ? std::abs(r.dot(d_)) : 0.0) + resolution_;
  std::ostringstream text;
  if (phi_end > phi_start_ + noise + allowance) {
    text << "raised the incremental potential from " << phi_start_ << " J to " << phi_end
         << " J (more than the " << allowance << " J its tolerance leaves)";
    return text.str();
  }
  if (!energy_judged) return {};
  // H's error for the error d of v: grad H = M v_n + r.
  const double energy_allowance =
      (within ? std::abs((mass.cwiseProduct(v_n) + r).dot(d_)) : 0.0) + resolution_;
  if (energy_end <= phi_kept_ + energy_noise + energy_allowance) return {};
  text << "raised the energy from " << phi_kept_ << " J to " << energy_end
       << " J (more than the " << energy_allowance << " J its tolerance leaves)";
  return text.str();
}

}  // namespace springlab
