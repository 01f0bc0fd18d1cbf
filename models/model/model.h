// The model: the mechanical system of docs/physics.md "The physics"
// assembled from a Scene, whatever it holds (springs, finite elements,
// contact and friction, drag and wind, affine bodies, fluids): the state
// holds only the free unknowns (free particles, and each body's 12 as four
// pseudo-particles), forces come from the terms of the registered element
// kinds (element_kind.h) the scene has, and both Jacobians share one sparsity
// pattern built here (once, or anew when a term's couplings move: a fluid's
// neighbours, ForceTerm::pattern_holds). The fast solvers' views
// (FastSolverViews, fast_solver_views.h: part 3 of mechanical_system.h's
// map) are gathered here from the same terms.
//
// Not thread-safe: evaluation uses the model's scratch arrays. Use one model
// per thread (they are cheap to build from the Scene).
#pragma once

#include <array>
#include <memory>
#include <string>
#include <vector>

#include "models/core/energies.h"
#include "models/core/fast_solver_views.h"
#include "models/core/force_term.h"
#include "models/core/mechanical_system.h"
#include "models/core/scene.h"
#include "models/model/energy_layout.h"
#include "models/core/verdict.h"
#include "models/core/vertex_blocks.h"

namespace springlab {

class Model final : public MechanicalSystem,
                    public FastSolverViews,
                    public VertexBlockView {
 public:
  explicit Model(const Scene& scene);

  // MechanicalSystem
  using MechanicalSystem::force;
  using MechanicalSystem::jacobians;
  Eigen::Index dofs() const override { return mass_.size(); }
  const Vector& mass() const override { return mass_; }
  void force(ForcePart part, double t, const Vector& x, const Vector& v,
             Vector& f) const override;
  void jacobians(ForcePart part, double t, const Vector& x, const Vector& v, SparseMatrix* dfdx,
                 SparseMatrix* dfdv) const override;
  void definite_jacobians(double t, const Vector& x, const Vector& v, SparseMatrix* dfdx,
                          SparseMatrix* dfdv) const override;
  bool has_jacobian_products() const override;
  void jacobian_products(bool definite, double t, const Vector& x, const Vector& v,
                         const Vector& p, Vector* dfdx_p, Vector* dfdv_p) const override;
  bool derives_from_potentials() const override { return derives_from_potentials_; }
  double position_potential(double t, const Vector& x) const override;
  double velocity_potential(double t, const Vector& v) const override;
  // Power of the non-conservative forces (drag, spring damping, wind): the
  // rate at which they change the mechanical energy.
  double nonconservative_power(double t, const Vector& x, const Vector& v) const override;
  bool has_own_discrete_gradients() const override { return has_own_discrete_gradients_; }
  void add_own_discrete_gradient_difference(double t, const Vector& x, const Vector& x_m,
                                            const Vector& y, Vector& f) const override;
  void add_own_discrete_gradient_jacobian_difference(double t, const Vector& x, const Vector& x_m,
                                                     const Vector& y, bool definite, double s,
                                                     SparseMatrix& out) const override;
  // Built when first asked for (here or by the Jacobians): a method that
  // never assembles a Jacobian pays nothing for it (issue 46.5: 2.9 GB of
  // pattern for 400 boxes' contact pairs under symplectic Euler).
  const SparseMatrix& jacobian_pattern() const override {
    ensure_pattern();
    return pattern_;
  }
  // Whether the pattern has been built (tests).
  bool pattern_built() const { return pattern_built_; }
  bool pattern_varies() const override { return pattern_varies_; }
  std::string pattern_change() const override;
  long pattern_version() const override { return pattern_version_; }
  bool jacobian_symmetric() const override { return symmetric_; }
  VelocityDependence velocity_dependence() const override { return velocity_dependence_; }
  bool has_forbidden_states() const override;
  // Why x is a forbidden state (a barrier's gap closed), naming the element
  // in scene terms; empty when it is not one.
  std::string forbidden_state(const Vector& x) const;
  double admissible_fraction(const Vector& x, const Vector& dx) const override;
  bool has_trust_region() const override;
  double trusted_fraction(const Vector& x, const Vector& dx) const override;
  void lag_normal_forces(const Vector* x_lag, const Vector* v_lag, double h) const override;
  bool follow_lagged_contacts(const Vector* x, const Vector* v, double h) const override;
  const FastSolverViews* fast_solver_views() const override { return this; }

  // FastSolverViews (fast_solver_views.h), gathered from the same terms.
  bool projective_form(std::vector<DistanceConstraint>& constraints,
                       std::vector<ProjectiveElement>& elements,
                       Refusal& why) const override;
  bool laplacian_form(std::vector<DistanceConstraint>& constraints,
                      std::vector<ProjectiveElement>& elements) const override;
  bool position_based_form(std::vector<DistanceConstraint>& constraints,
                           std::vector<ProjectiveElement>& elements,
                           std::vector<std::unique_ptr<PositionProjection>>& projections,
                           Refusal& why) const override;
  void plane_constraints(std::vector<PlaneConstraint>& out) const override;
  void external_force(double t, const Vector& x, const Vector& v, Vector& f) const override;
  int dimension_of_state() const override { return order_.dim; }
  const VertexBlockView* vertex_block_view() const override { return this; }

  // VertexBlockView (vertex_blocks.h), from the same terms.
  bool vertex_form(Refusal& why) const override;
  Eigen::Index all_particles() const override {
    return static_cast<Eigen::Index>(order_.scene_of_internal.size());
  }
  void fill_fixed(Vector& x_all) const override;
  bool reads_velocity() const override { return reads_velocity_; }
  void constant_force(double* f) const override;
  void vertex_blocks(double t, const double* x_all, const double* v_all, const int* particles,
                     int count, bool definite, const VertexBlocks& out) const override;
  double vertex_admissible_fraction(const double* x_all, int particle,
                                    const double* dx) const override;

  int dimension() const { return order_.dim; }
  int particle_count() const { return static_cast<int>(order_.internal_of_scene.size()); }
  int free_particle_count() const { return order_.free_particles; }
  // Which unknowns a scene particle has: internal index p (free when
  // p < free_particle_count(), its coordinates at x[p * dim ..]).
  const ParticleOrder& particle_order() const { return order_; }
  const Scene& scene() const { return scene_; }

  // Initial state of the free degrees of freedom.
  const Vector& initial_positions() const { return x0_; }
  const Vector& initial_velocities() const { return v0_; }

  // The energy report's columns (energies.h: kinetic, spring, gravity,
  // total, then those of the kinds the scene has) and their values at (x, v).
  const EnergyLayout& energy_layout() const { return *energy_layout_; }
  const std::vector<std::string>& energy_columns() const { return energy_layout_->columns; }
  Energies energies(const Vector& x, const Vector& v) const;
  // F.v of the forces whose kind reports in energy column `column` (a work
  // column: viscous-work), at (t, x, v): its rate, which the time series
  // accumulate (EnergyColumn::work).
  double column_power(std::size_t column, double t, const Vector& x, const Vector& v) const;
  // The same into `out` (made by energies() once), without allocating.
  void energies(const Vector& x, const Vector& v, Energies& out) const;

  // docs/command-line.md "Divergence"'s energy scale E_s = T(0) + U_spring(0) + sum_free m
  // (|g| d + |w_max|^2/2) (U_spring: every potential that counts with the spring energy; d the
  // scene's extent of motion, scene_extent.h).
  double energy_scale() const { return energy_scale_; }

  // The divergence rules of the scene's kinds (verdict.h: fluids, bodies),
  // measured on the state (x, v) whose total energy (energies(x, v).total())
  // is `total`: one Verdict per quantity into `out` (cleared first), each
  // with its value, bound and where. Empty when no kind of the scene has a
  // rule (springs and elements: the energy rule alone).
  bool has_divergence_rules() const { return !rules_.empty(); }
  void measure_divergence(const Vector& x, const Vector& v, double total,
                          std::vector<Verdict>& out) const;

  // Positions/velocities of all particles in scene order, one row each
  // (fixed particles at their fixed place, with zero velocity).
  Eigen::MatrixXd scene_positions(const Vector& x) const;
  Eigen::MatrixXd scene_velocities(const Vector& v) const;

  const std::vector<std::unique_ptr<ForceTerm>>& terms() const { return terms_; }

 private:
  Configuration configure(double t, const Vector& x, const Vector& v) const;
  // The configuration of what x_all_ and v_all_ hold now.
  Configuration stored_configuration(double t) const;
  void assemble_jacobians(ForcePart part, bool definite, double t, const Vector& x,
                          const Vector& v, SparseMatrix* dfdx, SparseMatrix* dfdv) const;

  Scene scene_;
  ParticleOrder order_;
  Vector mass_;
  Vector x0_, v0_;
  std::vector<std::unique_ptr<ForceTerm>> terms_;
  // The energy column each term's potential goes to (a position in the
  // layout), or -1 when its kind stores no energy.
  std::vector<long> term_column_;
  mutable Vector dx_all_;  // admissible_fraction's step, all particles
  std::shared_ptr<const EnergyLayout> energy_layout_;
  mutable SparseMatrix pattern_;
  bool pattern_varies_ = false;
  mutable long pattern_version_ = 0;
  mutable bool pattern_built_ = false;
  // Builds pattern_ from the terms' declared blocks and binds them to it.
  void build_pattern() const;
  void ensure_pattern() const {
    if (!pattern_built_) build_pattern();
  }
  // What every term says now (friction's answers change while it lags).
  mutable bool symmetric_ = true;
  mutable bool derives_from_potentials_ = true;
  VelocityDependence velocity_dependence_ = VelocityDependence::kNone;
  double energy_scale_ = 0.0;
  std::vector<std::unique_ptr<DivergenceRule>> rules_;
  bool fed_ = false;  // a term of a kind that feeds energy in (wind): not unforced

  // Sum of the constant terms (gravity) in each ForcePart, all particles:
  // force() starts f from it (see ForceTerm::constant()).
  std::array<Vector, 3> constant_force_;
  // Whether any term reads Configuration::v (else configure() skips copying v).
  bool reads_velocity_ = false;

  // Scratch: all particles, internal order. The fixed tail of x_all_ holds
  // the fixed positions and never changes; v_all_'s fixed tail stays 0.
  mutable Vector x_all_, v_all_, f_all_;
  // jacobian_products' direction and products, all particles.
  mutable Vector p_all_, dfdx_p_all_, dfdv_p_all_;
  // The second configuration of a discrete gradient (y), all particles.
  mutable Vector y_all_;
  // Scratch values on the pattern (add_own_discrete_gradient_jacobian_difference).
  mutable Vector own_values_;
  bool has_own_discrete_gradients_ = false;
  // projective_form and laplacian_form: the stiff conservative terms'
  // distance constraints, and their elements in the form asked for; false
  // where a term has neither form (why says which).
  enum class ElementForm { kProjective, kLaplacian };
  // With `projections`, a term that projects positions itself adds its
  // projection instead of failing.
  bool stiff_forms(std::vector<DistanceConstraint>& out, std::vector<ProjectiveElement>& elements,
                   ElementForm form, Refusal& why,
                   std::vector<std::unique_ptr<PositionProjection>>* projections = nullptr) const;
  // Which terms the fast solvers solve as constraints (distance
  // constraints, elements, position projections, contact planes:
  // external_force skips them); set
  // at its first call.
  mutable std::vector<char> constraint_terms_;
};

}  // namespace springlab
