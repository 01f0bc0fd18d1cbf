// The contact potential phi(d) of a particle at gap d = n.(x - point) from
// a plane (docs/physics.md "Contact with planes"), with its first two derivatives:
//   penalty:  phi(d) = k_c/2 min(d, 0)^2                      (any d)
//   barrier:  phi(d) = kappa b(d), b(d) = -(d - dhat)^2 ln(d / dhat)
//             for 0 < d < dhat, 0 beyond, +infinity for d <= 0
//             (IPC, Li et al. 2020, eq. 6)
// The plane's force on the particle is -phi'(d) n (planes.cc); its normal
// magnitude f_n = -phi'(d) >= 0 is what Coulomb friction scales with
// (friction_force.cc).
#pragma once

#include <cmath>
#include <limits>

#include "models/contact/contact.h"

namespace springlab {

struct ContactPhi {
  double value, slope, curvature;  // phi, phi', phi''
};

inline ContactPhi penalty_phi(double k, double d) {
  if (d >= 0.0) return {0.0, 0.0, 0.0};
  return {0.5 * k * d * d, k * d, k};
}

// b = -(d - h)^2 ln(d/h); b' = -2 (d - h) ln(d/h) - (d - h)^2 / d;
// b'' = -2 ln(d/h) - 4 (d - h)/d + (d - h)^2 / d^2.
inline ContactPhi barrier_phi(double kappa, double h, double d) {
  if (d >= h) return {0.0, 0.0, 0.0};
  if (!(d > 0.0)) {
    const double nan = std::numeric_limits<double>::quiet_NaN();
    return {std::numeric_limits<double>::infinity(), nan, nan};
  }
  const double e = d - h, l = std::log(d / h);
  return {-kappa * e * e * l, kappa * (-2.0 * e * l - e * e / d),
          kappa * (-2.0 * l - 4.0 * e / d + e * e / (d * d))};
}

// Between bodies the penalty acts on a skin (docs/physics.md "Contact
// between bodies"): the gap d there is a distance between surfaces, never
// negative while they are apart, so the penalty spring k_c engages at the
// contact distance delta and the surfaces themselves must not cross:
//   phi(d) = k_c/2 (delta - d)^2 for 0 <= d < delta, 0 beyond, +infinity for d < 0.
inline ContactPhi skin_penalty_phi(double k, double delta, double d) {
  if (d >= delta) return {0.0, 0.0, 0.0};
  if (!(d >= 0.0)) {
    const double nan = std::numeric_limits<double>::quiet_NaN();
    return {std::numeric_limits<double>::infinity(), nan, nan};
  }
  const double e = delta - d;
  return {0.5 * k * e * e, -k * e, k};
}

// Smoothed Coulomb friction's weight (IPC, Li et al. 2020, sec. 5.2;
// friction_force.cc): F = -mu f_n g(y) v_t with y = |v_t| and
//   g(y) = f1(y) / y = 2/eps - y/eps^2 (y < eps), 1/y beyond,
// and g'(y) / y = -1/(eps^2 y) or -1/y^3 (0 at y = 0, where v_t v_t^T = 0),
// the two numbers the force and its dF/dv need. Particles (friction_force.cc)
// and bodies' surface vertices (body_forces.cc) share it.
struct FrictionWeight {
  double y, g, g_over_y;
};

// From y2 = |v_t|^2.
inline FrictionWeight friction_weight(double y2, double eps) {
  const double y = std::sqrt(y2);
  if (y < eps) return {y, 2.0 / eps - y / (eps * eps), y > 0.0 ? -1.0 / (eps * eps * y) : 0.0};
  return {y, 1.0 / y, -1.0 / (y2 * y)};
}

// The dissipation potential whose v-derivative is that force, f0(|v_t|)
// with f0' = f1 (IPC's D(v), Li et al. 2020, eq. 15; lagged friction is
// F = -dW/dv, W = sum mu f_n0 f0(|v_t|)):
//   f0(y) = y^2/eps - y^3/(3 eps^2) (y < eps),  y - eps/3 beyond.
inline double friction_potential(double y, double eps) {
  return y < eps ? y * y / eps - y * y * y / (3.0 * eps * eps) : y - eps / 3.0;
}

// Damping along the normal at a contact, after Hunt and Crossley (1975,
// "Coefficient of restitution interpreted as damping in vibroimpact",
// J. Appl. Mech. 42:440): a force proportional to the normal force and, at
// low speed, to the approach speed v_n = n . v,
//   f = -f_n g_n v_n n,   g_n = f1(|v_n|) / |v_n|  (friction's f1 at eps = 2 / alpha),
// i.e. -alpha f_n v_n n while |v_n| << 2 / alpha, and never more than f_n
// (reached at |v_n| = 2 / alpha). It is zero where the contact starts
// (f_n = 0: no jump as it engages) and dissipates. Evaluated live, a
// separating contact's total normal force f_n (1 - f1) is never a pull;
// within an implicit step f_n is lagged from the step's start while the
// contact force is the stage's, so there it can pull by up to the lagged
// f_n. Bounded, a lagged f_n that is large at a step's start (the barrier's
// force as a gap nearly closes) cannot throw the step: unbounded,
// alpha f_n v_n at such a contact glued boxes together and Newton failed
// (box-drop). With f_n lagged it is -dW/dv of
//   W(v) = f_n f0(|v_n|),   dF/dv = -f_n f1'(|v_n|) n n^T  (f1' >= 0).
struct NormalDamping {
  double g = 0.0;          // g_n: f = -f_n g_n v_n n
  double slope = 0.0;      // f1'(|v_n|) = d(g_n v_n)/dv_n: df/dv_n = -f_n slope n
  double potential = 0.0;  // f0(|v_n|) = W / f_n
};
inline NormalDamping normal_damping(double alpha, double v_n) {
  if (!(alpha > 0.0)) return {};
  const double eps = 2.0 / alpha;
  const FrictionWeight w = friction_weight(v_n * v_n, eps);
  return {w.g, w.g + w.g_over_y * v_n * v_n, friction_potential(w.y, eps)};
}

// phi of the scene's contact model (its stiffness and distance resolved).
struct ContactLaw {
  ContactModel model = ContactModel::kPenalty;
  double stiffness = 0.0, distance = 0.0;
  explicit ContactLaw(const Contact& c)
      : model(c.model), stiffness(c.stiffness_or_default()), distance(c.distance_or_default()) {}
  ContactPhi operator()(double d) const {
    return model == ContactModel::kPenalty ? penalty_phi(stiffness, d)
                                           : barrier_phi(stiffness, distance, d);
  }
  // Between two bodies' surfaces: the barrier, or the penalty on its skin.
  ContactPhi between_bodies(double d) const {
    return model == ContactModel::kPenalty ? skin_penalty_phi(stiffness, distance, d)
                                           : barrier_phi(stiffness, distance, d);
  }
  // The gap below which the surfaces are refused: the barrier's 0 is
  // infinite, the skin's penalty is finite there and refuses only d < 0.
  bool forbidden_between_bodies(double d) const {
    return model == ContactModel::kPenalty ? !(d >= 0.0) : !(d > 0.0);
  }
};

}  // namespace springlab
