// The force of one element kind (element_kind.h): the unit a model is
// assembled from. An element kind's file implements this interface (springs,
// gravity; later finite elements as "generalized springs") and registers a
// factory for it; every integrator then runs it unchanged, and the shared
// tests (tests/test_element_kinds.cc: Jacobians vs finite differences,
// force = -grad energy, the definite part) cover it.
//
// Terms work on the arrays of *all* particles in the model's internal order:
// free particles first (indices < free_particles), fixed ones after. Fixed
// particles have zero velocity. Jacobian blocks are only written for pairs of
// free particles: fixed particles are not unknowns (the projection
// q = P^T q_free + q_fixed of the course codes, done once, not per force).
#pragma once

#include <array>
#include <limits>
#include <memory>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "models/core/fast_solver_views.h"
#include "models/core/mechanical_system.h"
#include "models/core/vertex_blocks.h"

namespace springlab {

// Something the terms of one model share, made by the first that needs it
// (ParticleOrder::shared).
class SharedByTerms {
 public:
  virtual ~SharedByTerms() = default;
};

// How scene particle indices map to the model's internal order (free first).
struct ParticleOrder {
  int dim = 2;
  int free_particles = 0;
  std::vector<int> internal_of_scene;  // scene index -> internal index
  std::vector<int> scene_of_internal;  // internal index -> scene index (-1: a kind's own unknowns)
  // The kinds' own unknowns (element_kind.h OwnUnknowns: a free rigid
  // body's 12), as "pseudo-particles" of dim unknowns at internal indices
  // [free_particles, free_particles + own_particles): after the free
  // particles, before the fixed ones, each kind's in one run starting at
  // first_own(its name).
  int own_particles = 0;
  std::vector<std::pair<std::string_view, int>> own_first;  // kind name, first internal index
  // Where the kind's own unknowns start; -1 for a kind that declares none.
  int first_own(std::string_view kind) const {
    for (const auto& [name, first] : own_first) {
      if (name == kind) return first;
    }
    return -1;
  }
  // What the terms of one model share, by a key of the kind's choosing: a
  // fluid's particles as SPH sees them (sph_particles.h), read by its
  // pressure and its viscosity, one neighbour search per configuration, not
  // one per term. The first term to need one makes it.
  mutable std::vector<std::pair<std::string, std::shared_ptr<SharedByTerms>>> shared;
  std::shared_ptr<SharedByTerms> find_shared(const std::string& key) const {
    for (const auto& [k, object] : shared) {
      if (k == key) return object;
    }
    return nullptr;
  }
};

// A read-only view of the configuration at which forces are evaluated.
struct Configuration {
  double t = 0.0;
  const double* x = nullptr;  // positions, particle p at x[p*dim .. p*dim+dim)
  // Velocities, same layout (fixed particles: 0); null when no term of the
  // model declares a velocity_dependence(), which spares the model copying v.
  const double* v = nullptr;
  int dim = 2;
  int free_particles = 0;
  bool is_free(int p) const { return p < free_particles; }
};

// Collects the dim x dim blocks (a, b) of free particles that any term writes.
class JacobianPatternBuilder {
 public:
  explicit JacobianPatternBuilder(int dim) : dim_(dim) {}
  void add_block(int a, int b) { blocks_.emplace_back(a, b); }
  int dim() const { return dim_; }
  const std::vector<std::pair<int, int>>& blocks() const { return blocks_; }

 private:
  int dim_;
  std::vector<std::pair<int, int>> blocks_;
};

// Where a block lives in the CSC value array of the shared pattern:
// entry (row a*dim + r, column b*dim + c) is values[offset[c] + r], because a
// block's rows are contiguous within each of its columns.
struct BlockSlot {
  std::array<int, 3> offset{-1, -1, -1};
  bool valid() const { return offset[0] >= 0; }
};

// Looks up the slot of block (a, b) in a compressed pattern that contains it.
BlockSlot find_block_slot(const SparseMatrix& pattern, int dim, int a, int b);

// The four blocks coupling particles a and b (a spring, a damper): a slot is
// invalid where its row or column particle is fixed.
struct PairSlots {
  BlockSlot aa, ab, ba, bb;
};
// Declares the off-diagonal blocks (the diagonal ones always exist).
void declare_pair_blocks(JacobianPatternBuilder& builder, int a, int b, int free_particles);
PairSlots find_pair_slots(const SparseMatrix& pattern, int dim, int a, int b, int free_particles);

// Value index of each diagonal entry (k, k) of a compressed pattern, k < rows.
std::vector<int> diagonal_slots(const SparseMatrix& pattern);

// Adds s * K to block slot `slot` of `values` (K is dim x dim, row-major).
template <int D>
inline void add_block(double* values, const BlockSlot& slot, const double (&K)[D][D], double s) {
  for (int c = 0; c < D; ++c) {
    double* col = values + slot.offset[c];
    for (int r = 0; r < D; ++r) col[r] += s * K[r][c];
  }
}

// For a pair force with F_b = -F_a: given B = dF_a/d(.)_a, adds
// s B to blocks (a,a) and (b,b) and -s B to blocks (a,b) and (b,a).
template <int D>
inline void add_pair_blocks(double* values, const PairSlots& slots, const double (&B)[D][D],
                            double s) {
  if (slots.aa.valid()) add_block<D>(values, slots.aa, B, s);
  if (slots.bb.valid()) add_block<D>(values, slots.bb, B, s);
  if (slots.ab.valid()) {
    add_block<D>(values, slots.ab, B, -s);
    add_block<D>(values, slots.ba, B, -s);
  }
}

class ForceTerm {
 public:
  virtual ~ForceTerm() = default;
  virtual std::string_view name() const = 0;

  // f += F(configuration); f has one entry per coordinate of every particle.
  virtual void add_force(const Configuration& c, double* f) const = 0;

  // The potential whose negative gradient is this force (0 for dissipative
  // and driving forces, which store no energy). The energy report shows it
  // in its kind's column (ElementKind::energy).
  virtual double potential_energy(const Configuration&) const { return 0.0; }
  // Conservative terms derive entirely from potential_energy; the others'
  // power F.v is the work rate the damping budget accounts for.
  virtual bool conservative() const = 0;

  // A constant force (gravity) depends on none of t, x, v: the model
  // evaluates it once and starts every evaluation of f from it instead of
  // from zero, which saves a pass over f per evaluation.
  virtual bool constant() const { return false; }

  // Stiff forces (large Jacobians: springs, damping) are the ones an IMEX
  // method treats implicitly; the others (gravity, wind) explicitly.
  virtual bool stiff() const { return true; }

  virtual VelocityDependence velocity_dependence() const { return VelocityDependence::kNone; }
  virtual bool symmetric_jacobians() const { return true; }

  // Jacobian support: declare blocks once, cache their slots once the pattern
  // is final, then add dF/dx and dF/dv values (either pointer may be null)
  // into the value arrays of the shared pattern at every evaluation.
  virtual void declare_jacobian_blocks(JacobianPatternBuilder&) const {}
  virtual void bind_jacobian(const SparseMatrix& /*pattern*/) {}
  virtual void add_jacobians(const Configuration&, double* /*dfdx*/, double* /*dfdv*/) const {}
  // A term whose couplings follow the state (a fluid's neighbour pairs)
  // says so; its declared blocks then hold every coupling only near the
  // configuration it declared them at. pattern_holds(c): they still hold
  // at c. follow_pattern(c): declare around c from now on (the model then
  // rebuilds the pattern, declare_jacobian_blocks and bind_jacobian again).
  virtual bool pattern_varies() const { return false; }
  // Why, completing "the Jacobian pattern changes as ..."
  // (MechanicalSystem::pattern_change).
  virtual std::string pattern_change() const { return "its couplings change with the state"; }
  virtual bool pattern_holds(const Configuration&) const { return true; }
  virtual void follow_pattern(const Configuration&) {}
  // Products with the Jacobians without assembling them (MechanicalSystem::
  // jacobian_products): a term that can says so, and adds dF/dx p (its
  // definite part with `definite`) and dF/dv p at c to the outputs (either
  // may be null). p and the outputs hold every particle (internal order,
  // as add_force's f); p is 0 on the fixed ones. Exactly the assembled
  // Jacobians times p, summed in another order.
  virtual bool has_jacobian_products() const { return false; }
  virtual void add_jacobian_products(const Configuration& /*c*/, bool /*definite*/,
                                     const double* /*p*/, double* /*dfdx_p*/,
                                     double* /*dfdv_p*/) const {}
  // dF/dx made negative semidefinite where it is not (MechanicalSystem::
  // definite_jacobians); a term whose dF/dx always is one keeps the default.
  virtual void add_definite_stiffness(const Configuration& c, double* dfdx) const {
    add_jacobians(c, dfdx, nullptr);
  }

  // Whether F = -d potential_energy/dx - d velocity_potential/dv, with the
  // velocity potential W(t, v) a function of t and v alone (see
  // MechanicalSystem::derives_from_potentials). Conservative terms do;
  // dissipative ones that do (drag, wind) say so and supply W.
  virtual bool derives_from_potentials() const { return conservative(); }
  // A conservative term may give its own discrete gradient of
  // potential_energy between two configurations x and y: a vector g with
  //   g . (y - x) = V(y) - V(x)   exactly, and g = grad V(x) when y = x
  // (Gonzalez, "Time integration and discrete Hamiltonian systems", J.
  // Nonlinear Sci. 6, 1996, Def. 3.1). The discrete-gradient method uses it
  // in place of its generic one for this term's share of the energy: a
  // term built from invariants (the rigid bodies' rigidity, a function of
  // A^T A) so keeps the first integrals its energy's symmetry gives
  // (Gonzalez 1996, sec. 4; Gonzalez and Simo 1996). x and y share t and
  // the fixed particles. f += -g (the discrete gradient as a force).
  virtual bool has_discrete_gradient() const { return false; }
  virtual void add_discrete_gradient_force(const Configuration& /*x*/, const Configuration& /*y*/,
                                           double* /*f*/) const {}
  // The Jacobian of that force for Newton's matrix of the discrete-gradient
  // step, on the term's declared blocks of the pattern: the derivative of
  // -g(x, 2 m - x) with respect to the midpoint m = (x + y) / 2, x held,
  //   dfdm += -2 dg/dy (x, y),
  // which at y = x is add_jacobians' dF/dx (2 dg/dy = the Hessian of V
  // there). It need not be symmetric (the step's matrix is then factored
  // by LU); with `definite`, a symmetric negative semidefinite part of it,
  // as add_definite_stiffness gives of dF/dx.
  virtual void add_discrete_gradient_jacobian(const Configuration& /*x*/,
                                              const Configuration& /*y*/, bool /*definite*/,
                                              double* /*dfdm*/) const {}
  // Whether potential_energy can be +infinity (MechanicalSystem::
  // has_forbidden_states).
  virtual bool forbids_states() const { return false; }
  // Where the configuration is forbidden (potential +infinity), one phrase
  // naming the element in scene terms ("particle 3 is through plane 0 ...");
  // empty where it is not.
  virtual std::string forbidden_state(const Configuration&) const { return {}; }
  // MechanicalSystem::admissible_fraction for this term; dx has the layout
  // of c.x (fixed particles: 0).
  virtual double admissible_fraction(const Configuration&, const double* /*dx*/) const {
    return std::numeric_limits<double>::infinity();
  }
  // MechanicalSystem::has_trust_region and trusted_fraction for this term
  // (dx as above): a fluid's pressure, whose water particles should move at
  // most h/2 per update of an iterative solve (fluid_pressure_force.cc).
  virtual bool has_trust_region() const { return false; }
  virtual double trusted_fraction(const Configuration&, const double* /*dx*/) const {
    return std::numeric_limits<double>::infinity();
  }
  // Vertex block descent's view (models/vertex_blocks.h, VertexBlockView):
  // for each of `count` free particles p (the k-th's blocks at out.f +
  // k dim, out.dfdx + k dim^2, out.dfdv + k dim^2, row-major), adds this
  // term's force on p from its elements around p, dF_p/dx_p and, where
  // out.dfdv is not null, dF_p/dv_p; with `definite`, each element's share
  // of dF_p/dx_p made negative semidefinite (VertexBlockView::
  // vertex_blocks). A term without it (has_vertex_blocks false) makes the
  // system refuse vbd, naming the term; a constant term (gravity) needs
  // none (the model adds its force itself).
  virtual bool has_vertex_blocks() const { return false; }
  virtual void add_vertex_blocks(const Configuration& /*c*/, const int* /*particles*/,
                                 int /*count*/, bool /*definite*/,
                                 const VertexBlocks& /*out*/) const {}
  // VertexBlockView::vertex_admissible_fraction for this term: moving free
  // particle p alone by a dx keeps its energy finite for a below it.
  virtual double vertex_admissible_fraction(const Configuration& /*c*/, int /*particle*/,
                                            const double* /*dx*/) const {
    return std::numeric_limits<double>::infinity();
  }
  // A stiff conservative term that is a set of distance constraints
  // (FastSolverViews::projective_form) appends them with internal
  // particle indices (b may be fixed: the model ties it to its place) and
  // returns true.
  virtual bool distance_constraints(std::vector<DistanceConstraint>& /*out*/) const {
    return false;
  }
  // A stiff conservative term of projective elements (FastSolverViews::
  // projective_form) appends them with internal node indices (fixed ones
  // too: the model turns them into places) and returns true; false, with
  // `why`, where its energy has no projective form.
  virtual bool projective_elements(std::vector<ProjectiveElement>& /*out*/,
                                   Refusal& why) const {
    why.text = std::string(name()) + " forces have no projective form";
    return false;
  }
  // A stiff conservative term with neither form whose constraints a
  // position-based solver can project (FastSolverViews::
  // position_based_form) returns them; nullptr where it has none.
  virtual std::unique_ptr<PositionProjection> position_projection() const { return nullptr; }
  virtual bool projects_positions() const { return false; }
  // The same elements for quasi-Newton's initial Hessian (FastSolverViews::
  // laplacian_form), any material, without a projection.
  virtual bool laplacian_elements(std::vector<ProjectiveElement>& /*out*/) const { return false; }
  virtual double velocity_potential(const Configuration&) const { return 0.0; }
  // A term the fast solvers see as contact planes (FastSolverViews::
  // plane_constraints) appends them and returns true; so does friction,
  // which they solve with the planes (appending none).
  virtual bool plane_constraints(std::vector<PlaneConstraint>& /*out*/) const { return false; }
  // MechanicalSystem::lag_normal_forces: c the lagged configuration (its v
  // the step's start velocity, or null), h the step's length; or nullptr to
  // evaluate live again. Friction lags its normal forces; contact between
  // bodies keeps the contacts it finds there.
  virtual void lag(const Configuration* /*c*/, double /*h*/) {}
  // MechanicalSystem::follow_lagged_contacts: while lagged, the contacts a
  // term keeps found again at c (null: those of before the last call);
  // true when they changed.
  virtual bool follow_lag(const Configuration* /*c*/, double /*h*/) { return false; }
};

}  // namespace springlab
