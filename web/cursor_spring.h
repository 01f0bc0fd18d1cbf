// The lab page's mouse (docs/browser-lab.md): a zero-length spring of
// stiffness k_c from one free particle p to the cursor c,
//   V_c = k_c/2 |x_p - c|^2,   F_p = -k_c (x_p - c),   dF_p/dx_p = -k_c I,
// added to a model's forces while the user drags. CursorSpring is the
// model as the integrators see it (a MechanicalSystem, and its
// FastSolverViews): every call goes to the model, plus the spring where it
// applies, so every method runs the dragged scene unchanged. The fast
// solvers (projective dynamics, XPBD) take it with the external forces,
// explicitly (external_force()).
//
// The stiffness: k_c = m_p w_max^2 / 4, so the spring's own frequency is
// w_max / 2 and the system's highest frequency grows by at most
// sqrt(1 + 1/4) = 1.12 (Weyl's inequality on M^-1/2 K M^-1/2): the step
// limits drawn on the dt slider still hold, nearly, while dragging.
#pragma once

#include <Eigen/Core>

#include "models/model/model.h"

namespace springlab {

class CursorSpring final : public MechanicalSystem, public FastSolverViews {
 public:
  // w_max: the model's highest angular frequency (modal_analysis.h); 0
  // when unknown (k_c is then 100 m_p, a 10 rad/s spring).
  CursorSpring(const Model& model, double w_max);

  // Pulls scene particle `particle` toward `cursor` (scene coordinates);
  // false, and nothing pulled, when the particle is fixed or out of range.
  bool grab(int particle, const Eigen::Vector3d& cursor);
  void release() { unknown_ = -1; }
  bool active() const { return unknown_ >= 0; }
  double stiffness() const { return k_; }

  // MechanicalSystem: the model's, plus the spring.
  using MechanicalSystem::force;
  using MechanicalSystem::jacobians;
  Eigen::Index dofs() const override { return model_.dofs(); }
  const Vector& mass() const override { return model_.mass(); }
  void force(ForcePart part, double t, const Vector& x, const Vector& v,
             Vector& f) const override;
  void jacobians(ForcePart part, double t, const Vector& x, const Vector& v, SparseMatrix* dfdx,
                 SparseMatrix* dfdv) const override;
  void definite_jacobians(double t, const Vector& x, const Vector& v, SparseMatrix* dfdx,
                          SparseMatrix* dfdv) const override;
  bool derives_from_potentials() const override { return model_.derives_from_potentials(); }
  double position_potential(double t, const Vector& x) const override;
  double velocity_potential(double t, const Vector& v) const override {
    return model_.velocity_potential(t, v);
  }
  double nonconservative_power(double t, const Vector& x, const Vector& v) const override {
    return model_.nonconservative_power(t, x, v);
  }
  // The cursor's spring keeps the generic discrete gradient.
  bool has_own_discrete_gradients() const override { return model_.has_own_discrete_gradients(); }
  void add_own_discrete_gradient_difference(double t, const Vector& x, const Vector& x_m,
                                            const Vector& y, Vector& f) const override {
    model_.add_own_discrete_gradient_difference(t, x, x_m, y, f);
  }
  void add_own_discrete_gradient_jacobian_difference(double t, const Vector& x, const Vector& x_m,
                                                     const Vector& y, bool definite, double s,
                                                     SparseMatrix& out) const override {
    model_.add_own_discrete_gradient_jacobian_difference(t, x, x_m, y, definite, s, out);
  }
  const SparseMatrix& jacobian_pattern() const override { return model_.jacobian_pattern(); }
  bool pattern_varies() const override { return model_.pattern_varies(); }
  std::string pattern_change() const override { return model_.pattern_change(); }
  long pattern_version() const override { return model_.pattern_version(); }
  bool jacobian_symmetric() const override { return model_.jacobian_symmetric(); }
  VelocityDependence velocity_dependence() const override {
    return model_.velocity_dependence();
  }
  bool has_forbidden_states() const override { return model_.has_forbidden_states(); }
  double admissible_fraction(const Vector& x, const Vector& dx) const override {
    return model_.admissible_fraction(x, dx);
  }
  bool has_trust_region() const override { return model_.has_trust_region(); }
  double trusted_fraction(const Vector& x, const Vector& dx) const override {
    return model_.trusted_fraction(x, dx);
  }
  void lag_normal_forces(const Vector* x_lag, const Vector* v_lag, double h) const override {
    model_.lag_normal_forces(x_lag, v_lag, h);
  }
  bool follow_lagged_contacts(const Vector* x, const Vector* v, double h) const override {
    return model_.follow_lagged_contacts(x, v, h);
  }
  const FastSolverViews* fast_solver_views() const override { return this; }

  // FastSolverViews: the model's, with the spring among the external forces.
  bool projective_form(std::vector<DistanceConstraint>& constraints,
                       std::vector<ProjectiveElement>& elements,
                       Refusal& why) const override {
    return model_.projective_form(constraints, elements, why);
  }
  bool position_based_form(std::vector<DistanceConstraint>& constraints,
                           std::vector<ProjectiveElement>& elements,
                           std::vector<std::unique_ptr<PositionProjection>>& projections,
                           Refusal& why) const override {
    return model_.position_based_form(constraints, elements, projections, why);
  }
  bool laplacian_form(std::vector<DistanceConstraint>& constraints,
                      std::vector<ProjectiveElement>& elements) const override {
    return model_.laplacian_form(constraints, elements);
  }
  void plane_constraints(std::vector<PlaneConstraint>& out) const override {
    model_.plane_constraints(out);
  }
  void external_force(double t, const Vector& x, const Vector& v, Vector& f) const override;
  int dimension_of_state() const override { return model_.dimension_of_state(); }

 private:
  // f += F_c (the spring's force on its particle's unknowns).
  void add_force(const Vector& x, Vector& f) const;
  // dfdx -= k_c on the particle's diagonal entries (every pattern has the
  // full diagonal; a fluid's pattern changes, so they are looked up in it).
  void add_stiffness(SparseMatrix* dfdx) const;

  const Model& model_;
  double k_ = 0.0;
  int dim_ = 3;
  int unknown_ = -1;  // first unknown of the pulled particle; -1: none
  Eigen::Vector3d cursor_ = Eigen::Vector3d::Zero();
};

}  // namespace springlab
