#include "integrators/core/integrator.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace springlab {

const char* to_string(StabilityKind kind) {
  switch (kind) {
    case StabilityKind::kConditional: return "conditional";
    case StabilityKind::kAAlpha: return "A(alpha)";
    case StabilityKind::kA: return "A";
    case StabilityKind::kL: return "L";
    case StabilityKind::kUnknown: break;
  }
  return "unknown";
}

double energy_excursion(const IntegratorInfo& info, double wh) {
  if (!info.energy_excursion || !(wh >= 0.0) || !(wh < info.stability_limit)) return 1.0;
  return std::max(1.0, info.energy_excursion(wh));
}

std::string stability_text(const IntegratorInfo& info) {
  char number[32];
  std::string text;
  switch (info.stability) {
    case StabilityKind::kUnknown:
      text = "stability unknown";
      break;
    case StabilityKind::kConditional:
      text = "conditionally stable";
      if (info.stability_limit == 0.0) {
        text += ": no stable step without damping";
      } else if (std::isfinite(info.stability_limit)) {
        std::snprintf(number, sizeof number, "%.4g", info.stability_limit);
        text += std::string(": w h <= ") + number + " undamped";
      }
      break;
    case StabilityKind::kAAlpha:
      std::snprintf(number, sizeof number, "%.1f", info.stability_alpha);
      text = std::string("A(") + number + " deg)-stable";
      break;
    case StabilityKind::kA:
      text = "A-stable";
      break;
    case StabilityKind::kL:
      text = "L-stable";
      break;
  }
  if (std::isfinite(info.spectral_radius_infinity)) {
    std::snprintf(number, sizeof number, "%.3g", info.spectral_radius_infinity);
    text += std::string(", rho_inf = ") + number;
  }
  if (!info.stability_note.empty()) text += " (" + info.stability_note + ")";
  return text;
}

std::string Integrator::check_options(const IntegratorOptions&, Eigen::Index) const { return {}; }

bool Integrator::assembles_jacobians(const MechanicalSystem&) const {
  return info_.implicit && !info_.jacobian_free;
}

std::vector<std::string> Integrator::options_read() const {
  if (info_.iterates_to_tolerance) return {"newton-tol", "max-newton"};
  return {};
}


StepResult Integrator::initialize(const MechanicalSystem& system, double t0, const Vector& x0,
                                  const Vector& v0, const IntegratorOptions& options) {
  if (system_ != nullptr) {
    return StepResult::failure(name() +
                               ": already initialized: an integrator runs one system once (its "
                               "caches belong to that system); make a new one for the next run");
  }
  system_ = &system;
  options_ = options;
  stats_ = {};
  t_ = t0;
  x_ = x0;
  v_ = v0;
  inv_mass_ = system.mass().cwiseInverse();
  return do_initialize();
}

IntegratorInfo Integrator::info_for(const IntegratorOptions&) const { return info_; }

StepResult Integrator::advance_to(double t_out) {
  const double h = t_out - t_;
  if (!(h > 0.0)) return StepResult::failure(name() + ": step size must be positive");
  StepResult result = do_step(h);
  if (!result.ok) return result;
  t_ = t_out;  // exactly, so fixed-step times do not drift
  ++stats_.steps;
  return result;
}

void Integrator::eval_force(double t, const Vector& x, const Vector& v, Vector& f) {
  ++stats_.force_evals;
  system_->force(t, x, v, f);
}

void Integrator::eval_acceleration(double t, const Vector& x, const Vector& v, Vector& a) {
  eval_force(t, x, v, a);
  a.array() *= inv_mass_.array();
}

void Integrator::eval_jacobians(double t, const Vector& x, const Vector& v, SparseMatrix* dfdx,
                                SparseMatrix* dfdv) {
  ++stats_.jacobian_evals;
  system_->jacobians(t, x, v, dfdx, dfdv);
}

void Integrator::eval_definite_jacobians(double t, const Vector& x, const Vector& v,
                                         SparseMatrix* dfdx, SparseMatrix* dfdv) {
  ++stats_.jacobian_evals;
  system_->definite_jacobians(t, x, v, dfdx, dfdv);
}

}  // namespace springlab
