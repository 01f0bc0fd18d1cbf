#include "models/model/model.h"

#include <algorithm>
#include <limits>
#include <cmath>
#include <cstring>
#include <vector>

#include <Eigen/SparseCore>

#include "models/core/element_kind.h"
#include "models/core/sparse_pattern.h"
#include "models/model/element_registry.h"
#include "models/model/energy_layout.h"
#include "models/model/scene_extent.h"

namespace springlab {
namespace {

// Free particles first, each group in scene order: then the free unknowns are
// the head of the all-particle arrays and the projection onto them is a copy.
ParticleOrder make_order(const Scene& scene) {
  ParticleOrder order;
  order.dim = scene.dimension;
  const int n = static_cast<int>(scene.particles.size());
  order.internal_of_scene.assign(static_cast<std::size_t>(n), -1);
  for (int pass = 0; pass < 2; ++pass) {
    const bool want_fixed = pass == 1;
    for (int p = 0; p < n; ++p) {
      if (scene.particles[static_cast<std::size_t>(p)].fixed != want_fixed) continue;
      order.internal_of_scene[static_cast<std::size_t>(p)] =
          static_cast<int>(order.scene_of_internal.size());
      order.scene_of_internal.push_back(p);
    }
    if (pass == 0) {
      order.free_particles = static_cast<int>(order.scene_of_internal.size());
      // The kinds' own unknowns follow the free particles (element_kind.h
      // OwnUnknowns), each kind's in one run.
      for (const ElementKind* kind : element_kinds()) {
        if (kind->own_unknowns.count == nullptr) continue;
        order.own_first.emplace_back(kind->name, order.free_particles + order.own_particles);
        order.own_particles += kind->own_unknowns.count(scene);
      }
      order.scene_of_internal.insert(order.scene_of_internal.end(),
                                     static_cast<std::size_t>(order.own_particles), -1);
    }
  }
  return order;
}

bool in_part(const ForceTerm& term, ForcePart part) {
  return part == ForcePart::kAll || term.stiff() == (part == ForcePart::kStiff);
}

}  // namespace

Model::Model(const Scene& scene) : scene_(scene), order_(make_order(scene)) {
  const int dim = order_.dim;
  const int all = static_cast<int>(order_.scene_of_internal.size());
  const int unknown_particles = order_.free_particles + order_.own_particles;
  const Eigen::Index n = static_cast<Eigen::Index>(unknown_particles) * dim;

  mass_.resize(n);
  x0_.resize(n);
  v0_.resize(n);
  x_all_.setZero(static_cast<Eigen::Index>(all) * dim);
  v_all_.setZero(x_all_.size());
  f_all_.setZero(x_all_.size());
  // The kinds' own unknowns (a free body's p and A), from the kind.
  std::vector<StartPoint> points;  // their elements' points, for E_s below
  for (const ElementKind* kind : element_kinds()) {
    const OwnUnknowns& own = kind->own_unknowns;
    if (own.count == nullptr) continue;
    // Its elements' points, those that cannot move too (a fixed body's).
    if (own.start_points != nullptr) own.start_points(scene_, points);
    const Eigen::Index at = static_cast<Eigen::Index>(order_.first_own(kind->name)) * dim;
    const Eigen::Index size = static_cast<Eigen::Index>(own.count(scene_)) * dim;
    if (size == 0) continue;
    own.initial_state(scene_, x0_.data() + at, v0_.data() + at, mass_.data() + at);
    x_all_.segment(at, size) = x0_.segment(at, size);
  }
  for (int p = 0; p < all; ++p) {
    if (order_.scene_of_internal[p] < 0) continue;  // a kind's own unknowns (above)
    const Particle& particle = scene_.particles[static_cast<std::size_t>(order_.scene_of_internal[p])];
    for (int r = 0; r < dim; ++r) {
      x_all_[p * dim + r] = particle.x[r];
      if (p < order_.free_particles) {
        mass_[p * dim + r] = particle.mass;
        x0_[p * dim + r] = particle.x[r];
        v0_[p * dim + r] = particle.v[r];
      }
    }
  }

  energy_layout_ = std::make_shared<const EnergyLayout>(springlab::energy_layout(scene_));
  for (const ElementKind* kind : element_kinds()) {
    if (kind->make == nullptr) continue;
    if (auto term = kind->make(scene_, order_)) {
      terms_.push_back(std::move(term));
      fed_ = fed_ || kind->feeds_energy;
      const std::size_t column =
          kind->energy.name.empty() ? energy_layout_->columns.size()
                                    : energy_layout_->find(kind->energy.name);
      term_column_.push_back(column < energy_layout_->columns.size() ? static_cast<long>(column)
                                                                     : -1);
    }
  }

  for (const auto& term : terms_) {
    pattern_varies_ = pattern_varies_ || term->pattern_varies();
    symmetric_ = symmetric_ && term->symmetric_jacobians();
    derives_from_potentials_ = derives_from_potentials_ && term->derives_from_potentials();
    velocity_dependence_ = std::max(velocity_dependence_, term->velocity_dependence());
    has_own_discrete_gradients_ = has_own_discrete_gradients_ || term->has_discrete_gradient();
  }
  y_all_ = x_all_;  // the fixed tail, which never changes
  reads_velocity_ = velocity_dependence_ != VelocityDependence::kNone;

  const Configuration initial = configure(0.0, x0_, v0_);
  for (ForcePart part : {ForcePart::kAll, ForcePart::kStiff, ForcePart::kNonstiff}) {
    Vector& base = constant_force_[static_cast<std::size_t>(part)];
    base.setZero(x_all_.size());
    for (const auto& term : terms_) {
      if (term->constant() && in_part(*term, part)) term->add_force(initial, base.data());
    }
  }

  // docs/command-line.md "Divergence": E_s = T(0) + U_spring(0) + sum_free m_i (|g| d +
  // |w_max|^2 / 2), d the scene's extent of motion (scene_extent.h); each kind gives its term
  // per unit of free mass (gravity |g| d, wind |w_max|^2 / 2).
  const double diameter = extent_of_motion(scene_, points);
  double per_mass = 0.0;
  for (const ElementKind* kind : element_kinds()) {
    if (kind->energy_scale_per_mass != nullptr) {
      per_mass += kind->energy_scale_per_mass(scene_, diameter);
    }
  }
  const Energies e0 = energies(x0_, v0_);
  double free_mass = mass_.head(static_cast<Eigen::Index>(order_.free_particles) * dim).sum() / dim;
  for (const ElementKind* kind : element_kinds()) {
    if (kind->own_unknowns.add_free_mass != nullptr) kind->own_unknowns.add_free_mass(scene_, free_mass);
  }
  energy_scale_ = e0.kinetic_and_spring() + free_mass * per_mass;

  // The kinds' divergence rules (verdict.h), given the scene's energy.
  VerdictScale scale{
      .energy_initial = e0.total(), .energy_scale = energy_scale_, .unforced = !fed_};
  plane_constraints(scale.planes);
  for (const ElementKind* kind : element_kinds()) {
    if (kind->divergence_rule == nullptr) continue;
    if (auto rule = kind->divergence_rule(scene_, order_, scale)) rules_.push_back(std::move(rule));
  }
}

void Model::measure_divergence(const Vector& x, const Vector& v, double total,
                                      std::vector<Verdict>& out) const {
  out.clear();
  if (rules_.empty()) return;
  const Configuration c = configure(0.0, x, v);
  for (const auto& rule : rules_) rule->measure(c, total, out);
}

// One pattern for dF/dx and dF/dv: the full diagonal plus every block a
// term declares. Values stay zero here; terms cache their slots in it.
void Model::build_pattern() const {
  const int dim = order_.dim;
  const int unknown_particles = order_.free_particles + order_.own_particles;
  const Eigen::Index n = static_cast<Eigen::Index>(unknown_particles) * dim;
  JacobianPatternBuilder builder(dim);
  for (int p = 0; p < unknown_particles; ++p) builder.add_block(p, p);
  for (const auto& term : terms_) term->declare_jacobian_blocks(builder);
  // The compressed pattern straight from the blocks (a, b) (row, column
  // particle; repeated ones once): each block column's row particles,
  // bucketed by a counting sort, then sorted and made unique, give the same
  // rows to each of its dim columns. (A fluid's pattern is rebuilt as it
  // flows: setFromTriplets of dim^2 entries per block cost 5 % of an
  // implicit dam break.)
  const std::size_t columns = static_cast<std::size_t>(unknown_particles);
  std::vector<int> start(columns + 1, 0);
  for (const auto& block : builder.blocks()) ++start[static_cast<std::size_t>(block.second) + 1];
  for (std::size_t b = 0; b < columns; ++b) start[b + 1] += start[b];
  std::vector<int> rows(builder.blocks().size()), fill(start.begin(), start.end() - 1);
  for (const auto& [a, b] : builder.blocks()) rows[static_cast<std::size_t>(fill[static_cast<std::size_t>(b)]++)] = a;
  std::vector<int> count(columns);  // distinct row particles per block column
  Eigen::Index nonzeros = 0;
  for (std::size_t b = 0; b < columns; ++b) {
    const auto first = rows.begin() + start[b], last = rows.begin() + start[b + 1];
    std::sort(first, last);
    count[b] = static_cast<int>(std::unique(first, last) - first);
    nonzeros += static_cast<Eigen::Index>(count[b]) * dim * dim;
  }
  pattern_ = SparseMatrix();
  pattern_.resize(n, n);
  pattern_.resizeNonZeros(nonzeros);
  int* outer = pattern_.outerIndexPtr();
  int* inner = pattern_.innerIndexPtr();
  int at = 0;
  for (std::size_t b = 0; b < columns; ++b) {
    for (int c = 0; c < dim; ++c) {
      outer[b * static_cast<std::size_t>(dim) + static_cast<std::size_t>(c)] = at;
      for (int k = 0; k < count[b]; ++k) {
        const int a = rows[static_cast<std::size_t>(start[b] + k)];
        for (int r = 0; r < dim; ++r) inner[at++] = a * dim + r;
      }
    }
  }
  outer[n] = at;
  std::fill(pattern_.valuePtr(), pattern_.valuePtr() + pattern_.nonZeros(), 0.0);
  for (const auto& term : terms_) term->bind_jacobian(pattern_);
  pattern_built_ = true;
}

Configuration Model::stored_configuration(double t) const {
  Configuration c;
  c.t = t;
  c.x = x_all_.data();
  c.v = reads_velocity_ ? v_all_.data() : nullptr;
  c.dim = order_.dim;
  c.free_particles = order_.free_particles;
  return c;
}

// The copies of force() and configure() by memcpy: Eigen's loop moves 16
// bytes an iteration on the default target, and the step's three copies of
// the state took 5.1 or 5.6 us per step of the 1000-particle chain
// depending on where the linker placed those loops (benchmarks/README.md,
// the run/kernel ratio).
namespace {
void copy(const Vector& from, Eigen::Index n, Vector& to) {
  std::memcpy(to.data(), from.data(), sizeof(double) * static_cast<std::size_t>(n));
}
}  // namespace

Configuration Model::configure(double t, const Vector& x, const Vector& v) const {
  const Eigen::Index n = dofs();
  copy(x, n, x_all_);
  if (reads_velocity_) copy(v, n, v_all_);
  return stored_configuration(t);
}

void Model::force(ForcePart part, double t, const Vector& x, const Vector& v,
                            Vector& f) const {
  const Configuration c = configure(t, x, v);
  // One pass initializes f with the constant forces (instead of zero-fill,
  // then a pass that adds gravity).
  const Vector& constant = constant_force_[static_cast<std::size_t>(part)];
  copy(constant, constant.size(), f_all_);
  for (const auto& term : terms_) {
    if (!term->constant() && in_part(*term, part)) term->add_force(c, f_all_.data());
  }
  f.resize(dofs());
  copy(f_all_, dofs(), f);
}

void Model::jacobians(ForcePart part, double t, const Vector& x, const Vector& v,
                                SparseMatrix* dfdx, SparseMatrix* dfdv) const {
  assemble_jacobians(part, /*definite=*/false, t, x, v, dfdx, dfdv);
}

void Model::definite_jacobians(double t, const Vector& x, const Vector& v,
                                         SparseMatrix* dfdx, SparseMatrix* dfdv) const {
  assemble_jacobians(ForcePart::kAll, /*definite=*/true, t, x, v, dfdx, dfdv);
}

// The potentials read only the half of the configuration they depend on:
// each sets that half, the other holds whatever was stored last.
double Model::position_potential(double t, const Vector& x) const {
  x_all_.head(dofs()) = x;
  const Configuration c = stored_configuration(t);
  double sum = 0.0;
  for (const auto& term : terms_) sum += term->potential_energy(c);
  return sum;
}

std::string Model::forbidden_state(const Vector& x) const {
  x_all_.head(dofs()) = x;
  const Configuration c = stored_configuration(0.0);
  for (const auto& term : terms_) {
    if (!term->forbids_states()) continue;
    std::string why = term->forbidden_state(c);
    if (!why.empty()) return why;
  }
  return {};
}

double Model::admissible_fraction(const Vector& x, const Vector& dx) const {
  double fraction = std::numeric_limits<double>::infinity();
  if (!has_forbidden_states()) return fraction;
  x_all_.head(dofs()) = x;
  dx_all_.setZero(x_all_.size());
  dx_all_.head(dofs()) = dx;
  const Configuration c = stored_configuration(0.0);
  for (const auto& term : terms_) {
    if (term->forbids_states()) {
      fraction = std::min(fraction, term->admissible_fraction(c, dx_all_.data()));
    }
  }
  return fraction;
}

bool Model::has_trust_region() const {
  for (const auto& term : terms_) {
    if (term->has_trust_region()) return true;
  }
  return false;
}

double Model::trusted_fraction(const Vector& x, const Vector& dx) const {
  double fraction = std::numeric_limits<double>::infinity();
  if (!has_trust_region()) return fraction;
  x_all_.head(dofs()) = x;
  dx_all_.setZero(x_all_.size());
  dx_all_.head(dofs()) = dx;
  const Configuration c = stored_configuration(0.0);
  for (const auto& term : terms_) {
    if (term->has_trust_region()) {
      fraction = std::min(fraction, term->trusted_fraction(c, dx_all_.data()));
    }
  }
  return fraction;
}

double Model::velocity_potential(double t, const Vector& v) const {
  if (!derives_from_potentials_ || !reads_velocity_) return 0.0;  // no term has a W
  v_all_.head(dofs()) = v;
  const Configuration c = stored_configuration(t);
  double sum = 0.0;
  for (const auto& term : terms_) sum += term->velocity_potential(c);
  return sum;
}

void Model::assemble_jacobians(ForcePart part, bool definite, double t, const Vector& x,
                                         const Vector& v, SparseMatrix* dfdx,
                                         SparseMatrix* dfdv) const {
  ensure_pattern();
  const Configuration c = configure(t, x, v);
  if (pattern_varies_) {
    // A term whose couplings moved past its declared blocks declares anew
    // around c, and the pattern is rebuilt: a new version.
    bool holds = true;
    for (const auto& term : terms_) {
      if (term->pattern_varies() && !term->pattern_holds(c)) holds = false;
    }
    if (!holds) {
      for (const auto& term : terms_) {
        if (term->pattern_varies()) term->follow_pattern(c);
      }
      build_pattern();
      ++pattern_version_;
    }
  }
  for (SparseMatrix* m : {dfdx, dfdv}) {
    if (m == nullptr) continue;
    // (With a varying pattern an equal count does not mean an equal
    // pattern: the indices are compared, cheaper than a copy.)
    if (pattern_varies_ ? !same_pattern(*m, pattern_)
                        : m->nonZeros() != pattern_.nonZeros() || m->rows() != pattern_.rows()) {
      *m = pattern_;
    }
    std::fill(m->valuePtr(), m->valuePtr() + m->nonZeros(), 0.0);
  }
  double* dx = dfdx != nullptr ? dfdx->valuePtr() : nullptr;
  double* dv = dfdv != nullptr ? dfdv->valuePtr() : nullptr;
  for (const auto& term : terms_) {
    if (!in_part(*term, part)) continue;
    if (definite) {
      if (dx != nullptr) term->add_definite_stiffness(c, dx);
      if (dv != nullptr) term->add_jacobians(c, nullptr, dv);
    } else {
      term->add_jacobians(c, dx, dv);
    }
  }
}

bool Model::has_jacobian_products() const {
  for (const auto& term : terms_) {
    if (!term->constant() && !term->has_jacobian_products()) return false;
  }
  return true;
}

void Model::jacobian_products(bool definite, double t, const Vector& x, const Vector& v,
                              const Vector& p, Vector* dfdx_p, Vector* dfdv_p) const {
  const Configuration c = configure(t, x, v);
  const Eigen::Index n = dofs(), all = x_all_.size();
  p_all_.setZero(all);
  p_all_.head(n) = p;
  double* px = nullptr;
  double* pv = nullptr;
  if (dfdx_p != nullptr) {
    dfdx_p_all_.setZero(all);
    px = dfdx_p_all_.data();
  }
  if (dfdv_p != nullptr) {
    dfdv_p_all_.setZero(all);
    pv = dfdv_p_all_.data();
  }
  for (const auto& term : terms_) {
    if (!term->constant()) term->add_jacobian_products(c, definite, p_all_.data(), px, pv);
  }
  if (dfdx_p != nullptr) *dfdx_p = dfdx_p_all_.head(n);
  if (dfdv_p != nullptr) *dfdv_p = dfdv_p_all_.head(n);
}

Energies Model::energies(const Vector& x, const Vector& v) const {
  Energies e(energy_layout_);
  energies(x, v, e);
  return e;
}

void Model::energies(const Vector& x, const Vector& v, Energies& e) const {
  const Configuration c = configure(0.0, x, v);
  e.clear();
  e.set_kinetic(0.5 * mass_.dot(v.cwiseProduct(v)));
  for (std::size_t k = 0; k < terms_.size(); ++k) {
    if (term_column_[k] >= 0) {
      e.add(static_cast<std::size_t>(term_column_[k]), terms_[k]->potential_energy(c));
    }
  }
  e.finish();
}

double Model::column_power(std::size_t column, double t, const Vector& x,
                                  const Vector& v) const {
  const Configuration c = configure(t, x, v);
  f_all_.setZero();
  for (std::size_t k = 0; k < terms_.size(); ++k) {
    if (term_column_[k] == static_cast<long>(column)) terms_[k]->add_force(c, f_all_.data());
  }
  return f_all_.head(dofs()).dot(v);
}

double Model::nonconservative_power(double t, const Vector& x, const Vector& v) const {
  const Configuration c = configure(t, x, v);
  f_all_.setZero();
  for (const auto& term : terms_) {
    if (!term->conservative()) term->add_force(c, f_all_.data());
  }
  return f_all_.head(dofs()).dot(v);
}

void Model::add_own_discrete_gradient_difference(double t, const Vector& x,
                                                        const Vector& x_m, const Vector& y,
                                                        Vector& f) const {
  // -F_k(x_m), then -g_k(x, y), of the terms with their own discrete
  // gradient (conservative: none reads v).
  const Eigen::Index n = dofs();
  f_all_.setZero();
  x_all_.head(n) = x_m;
  const Configuration mid = stored_configuration(t);
  for (const auto& term : terms_) {
    if (term->has_discrete_gradient()) term->add_force(mid, f_all_.data());
  }
  f_all_ = -f_all_;
  x_all_.head(n) = x;
  y_all_.head(n) = y;
  const Configuration from = stored_configuration(t);
  Configuration to = from;
  to.x = y_all_.data();
  for (const auto& term : terms_) {
    if (term->has_discrete_gradient()) term->add_discrete_gradient_force(from, to, f_all_.data());
  }
  f += f_all_.head(n);
}

void Model::add_own_discrete_gradient_jacobian_difference(double t, const Vector& x,
                                                                 const Vector& x_m,
                                                                 const Vector& y, bool definite,
                                                                 double s,
                                                                 SparseMatrix& out) const {
  // -dF_k/dx(x_m) (exact or definite), then -2 dg_k/dy(x, y), of the terms
  // with their own discrete gradient, on out's pattern (the model's).
  ensure_pattern();
  const Eigen::Index n = dofs();
  own_values_.setZero(out.nonZeros());
  x_all_.head(n) = x_m;
  const Configuration mid = stored_configuration(t);
  for (const auto& term : terms_) {
    if (!term->has_discrete_gradient()) continue;
    if (definite) {
      term->add_definite_stiffness(mid, own_values_.data());
    } else {
      term->add_jacobians(mid, own_values_.data(), nullptr);
    }
  }
  own_values_ = -own_values_;
  x_all_.head(n) = x;
  y_all_.head(n) = y;
  const Configuration from = stored_configuration(t);
  Configuration to = from;
  to.x = y_all_.data();
  for (const auto& term : terms_) {
    if (term->has_discrete_gradient()) {
      term->add_discrete_gradient_jacobian(from, to, definite, own_values_.data());
    }
  }
  Eigen::Map<Vector>(out.valuePtr(), out.nonZeros()) += s * own_values_;
}

Eigen::MatrixXd Model::scene_positions(const Vector& x) const {
  const int dim = order_.dim;
  Eigen::MatrixXd out(particle_count(), dim);
  for (int s = 0; s < particle_count(); ++s) {
    const int p = order_.internal_of_scene[static_cast<std::size_t>(s)];
    for (int r = 0; r < dim; ++r) {
      out(s, r) = p < order_.free_particles ? x[p * dim + r] : x_all_[p * dim + r];
    }
  }
  return out;
}

Eigen::MatrixXd Model::scene_velocities(const Vector& v) const {
  const int dim = order_.dim;
  Eigen::MatrixXd out = Eigen::MatrixXd::Zero(particle_count(), dim);
  for (int s = 0; s < particle_count(); ++s) {
    const int p = order_.internal_of_scene[static_cast<std::size_t>(s)];
    if (p >= order_.free_particles) continue;
    for (int r = 0; r < dim; ++r) out(s, r) = v[p * dim + r];
  }
  return out;
}

std::string Model::pattern_change() const {
  for (const auto& term : terms_) {
    if (term->pattern_varies()) return term->pattern_change();
  }
  return MechanicalSystem::pattern_change();
}

bool Model::has_forbidden_states() const {
  for (const auto& term : terms_) {
    if (term->forbids_states()) return true;
  }
  return false;
}

bool Model::projective_form(std::vector<DistanceConstraint>& constraints,
                                   std::vector<ProjectiveElement>& elements,
                                   Refusal& why) const {
  return stiff_forms(constraints, elements, ElementForm::kProjective, why);
}

bool Model::laplacian_form(std::vector<DistanceConstraint>& constraints,
                                  std::vector<ProjectiveElement>& elements) const {
  Refusal why;
  return stiff_forms(constraints, elements, ElementForm::kLaplacian, why);
}

bool Model::position_based_form(
    std::vector<DistanceConstraint>& constraints, std::vector<ProjectiveElement>& elements,
    std::vector<std::unique_ptr<PositionProjection>>& projections, Refusal& why) const {
  return stiff_forms(constraints, elements, ElementForm::kProjective, why, &projections);
}

bool Model::stiff_forms(std::vector<DistanceConstraint>& out,
                               std::vector<ProjectiveElement>& elements, ElementForm form,
                               Refusal& why,
                               std::vector<std::unique_ptr<PositionProjection>>* projections) const {
  out.clear();
  elements.clear();
  if (projections != nullptr) projections->clear();
  std::vector<DistanceConstraint> all;
  std::vector<PlaneConstraint> planes;
  std::vector<ProjectiveElement> projective;
  for (const auto& term : terms_) {
    if (term->plane_constraints(planes)) continue;           // plane_constraints
    if (!term->conservative() || !term->stiff()) continue;  // external: explicit
    if (term->distance_constraints(all)) continue;
    if (projections != nullptr && term->projects_positions()) {
      projections->push_back(term->position_projection());
      continue;
    }
    const bool has_form = form == ElementForm::kProjective
                              ? term->projective_elements(projective, why)
                              : term->laplacian_elements(projective);
    if (!has_form) return false;
  }
  // Internal indices: free particles first. A fixed end becomes an anchor;
  // a constraint between two fixed particles moves nothing.
  const int dim = order_.dim, free = order_.free_particles;
  for (DistanceConstraint c : all) {
    if (c.a >= free) std::swap(c.a, c.b);
    if (c.a >= free) continue;
    if (c.b >= free) {
      for (int r = 0; r < dim; ++r) c.anchor[r] = x_all_[c.b * dim + r];
      c.b = -1;
    }
    out.push_back(c);
  }
  // Likewise a fixed node of an element becomes a place.
  for (ProjectiveElement e : projective) {
    e.fixed.assign(e.nodes.size(), Eigen::Vector3d::Zero());
    bool moves = false;
    for (std::size_t j = 0; j < e.nodes.size(); ++j) {
      if (e.nodes[j] < free) {
        moves = true;
        continue;
      }
      for (int r = 0; r < dim; ++r) e.fixed[j][r] = x_all_[e.nodes[j] * dim + r];
      e.nodes[j] = -1;
    }
    if (moves) elements.push_back(std::move(e));
  }
  return true;
}

void Model::lag_normal_forces(const Vector* x_lag, const Vector* v_lag, double h) const {
  if (x_lag != nullptr) x_all_.head(dofs()) = *x_lag;
  if (x_lag != nullptr && v_lag != nullptr) v_all_.head(dofs()) = *v_lag;
  Configuration c = stored_configuration(0.0);
  c.v = x_lag != nullptr && v_lag != nullptr ? v_all_.data() : nullptr;
  symmetric_ = true;
  derives_from_potentials_ = true;
  for (const auto& term : terms_) {
    term->lag(x_lag != nullptr ? &c : nullptr, h);
    symmetric_ = symmetric_ && term->symmetric_jacobians();
    derives_from_potentials_ = derives_from_potentials_ && term->derives_from_potentials();
  }
}

bool Model::follow_lagged_contacts(const Vector* x, const Vector* v, double h) const {
  if (x != nullptr) x_all_.head(dofs()) = *x;
  if (x != nullptr && v != nullptr) v_all_.head(dofs()) = *v;
  Configuration c = stored_configuration(0.0);
  c.v = x != nullptr && v != nullptr ? v_all_.data() : nullptr;
  bool changed = false;
  for (const auto& term : terms_) {
    if (term->follow_lag(x != nullptr ? &c : nullptr, h)) changed = true;
  }
  return changed;
}

void Model::plane_constraints(std::vector<PlaneConstraint>& out) const {
  out.clear();
  for (const auto& term : terms_) term->plane_constraints(out);
}

void Model::external_force(double t, const Vector& x, const Vector& v, Vector& f) const {
  const Configuration c = configure(t, x, v);
  if (constraint_terms_.empty()) {
    std::vector<DistanceConstraint> probe;
    std::vector<PlaneConstraint> planes;
    std::vector<ProjectiveElement> elements;
    for (const auto& term : terms_) {
      constraint_terms_.push_back(
          term->plane_constraints(planes) ||
          (term->conservative() && term->stiff() &&
           (term->distance_constraints(probe) || term->laplacian_elements(elements) ||
            term->projects_positions())));
    }
  }
  f_all_.setZero(x_all_.size());
  for (std::size_t k = 0; k < terms_.size(); ++k) {
    if (!constraint_terms_[k]) terms_[k]->add_force(c, f_all_.data());
  }
  f = f_all_.head(dofs());
}

}  // namespace springlab
