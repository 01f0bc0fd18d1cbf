// The model's VertexBlockView (models/core/vertex_blocks.h): vertex block
// descent's per-particle forces and blocks, gathered from the same terms as
// force() and jacobians() (each term's ForceTerm::add_vertex_blocks).
#include <algorithm>
#include <cstring>
#include <limits>
#include <string>

#include "models/core/element_kind.h"
#include "models/model/model.h"
#include "models/model/element_registry.h"

namespace springlab {

bool Model::vertex_form(Refusal& why) const {
  // A kind's own unknowns (element_kind.h OwnUnknowns) are not particles.
  for (const ElementKind* kind : element_kinds()) {
    const OwnUnknowns& own = kind->own_unknowns;
    if (own.count == nullptr || own.count(scene_) == 0) continue;
    why.text = std::string(own.not_per_particle);
    return false;
  }
  for (const auto& term : terms_) {
    if (term->constant() || term->has_vertex_blocks()) continue;
    why.text = "this scene's " + std::string(term->name()) +
          " forces have no per-particle form (vbd moves one particle at a time, with the "
          "elements around it); use implicit-euler";
    return false;
  }
  return true;
}

void Model::fill_fixed(Vector& x_all) const {
  // x_all_'s tail holds the fixed places (and never changes).
  const Eigen::Index head = dofs();
  const Eigen::Index tail = x_all_.size() - head;
  x_all.conservativeResize(x_all_.size());
  if (tail > 0) x_all.tail(tail) = x_all_.tail(tail);
}

void Model::constant_force(double* f) const {
  const Vector& constant = constant_force_[static_cast<std::size_t>(ForcePart::kAll)];
  std::memcpy(f, constant.data(), sizeof(double) * static_cast<std::size_t>(dofs()));
}

void Model::vertex_blocks(double t, const double* x_all, const double* v_all,
                                 const int* particles, int count, bool definite,
                                 const VertexBlocks& out) const {
  const int dim = order_.dim;
  Configuration c;
  c.t = t;
  c.x = x_all;
  c.v = reads_velocity_ ? v_all : nullptr;
  c.dim = dim;
  c.free_particles = order_.free_particles;
  // F starts from the constant forces (gravity), as force() does.
  const double* constant = constant_force_[static_cast<std::size_t>(ForcePart::kAll)].data();
  for (int k = 0; k < count; ++k) {
    std::memcpy(out.f + k * dim, constant + particles[k] * dim, sizeof(double) * dim);
  }
  std::fill(out.dfdx, out.dfdx + static_cast<std::ptrdiff_t>(count) * dim * dim, 0.0);
  const VertexBlocks blocks{out.f, out.dfdx, reads_velocity_ ? out.dfdv : nullptr};
  if (blocks.dfdv != nullptr) {
    std::fill(blocks.dfdv, blocks.dfdv + static_cast<std::ptrdiff_t>(count) * dim * dim, 0.0);
  }
  for (const auto& term : terms_) {
    if (!term->constant()) term->add_vertex_blocks(c, particles, count, definite, blocks);
  }
}

double Model::vertex_admissible_fraction(const double* x_all, int particle,
                                                const double* dx) const {
  double fraction = std::numeric_limits<double>::infinity();
  Configuration c;
  c.x = x_all;
  c.dim = order_.dim;
  c.free_particles = order_.free_particles;
  for (const auto& term : terms_) {
    if (term->forbids_states()) {
      fraction = std::min(fraction, term->vertex_admissible_fraction(c, particle, dx));
    }
  }
  return fraction;
}

}  // namespace springlab
