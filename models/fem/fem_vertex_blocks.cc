// Finite elements in vertex block descent (models/vertex_blocks.h; vbd,
// integrators/vbd.h): each particle's share of its elements' forces and
// its own 3 x 3 (d x d) block of their stiffness, written plainly for every
// element shape and material from the material's P and dP
// (models/materials/material.h), as fem_force.cc's reference is. With
// E_e = W Psi(F), F = sum_j x_j g_j^T, node a of element e at particle p:
//   F_p += -W P g_a,
//   dF_p/dx_p e_r += -W dP[e_r g_a^T] g_a     (r = 1..d: column r),
// the diagonal block of fem_force.cc's stiffness. Definite: that block's
// positive eigenvalues set to zero (the element's 3 x 3 Hessian block
// projected to semidefinite; vbd asks only where the particle's whole block
// is indefinite).
//
// The cap (VertexBlockView::vertex_admissible_fraction): a solid element
// (F square) of a material with no energy at J <= 0 (neo-Hookean) stays
// uninverted while p moves by a dx for a < -1 / (g_a^T F^-1 dx): by the
// matrix determinant lemma det(F + a dx g_a^T) = det F (1 + a g_a^T F^-1 dx),
// linear in a. Membranes (3 x 2 F) reach J = 0 only when the triangle
// collapses; they have no cap.
#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>

#include "models/fem/fem_elements.h"

namespace springlab {

void ElementTerm::build_vertex_elements() const {
  const std::size_t elements = element_count();
  vertex_shapes_.resize(elements);
  std::vector<int> counts(static_cast<std::size_t>(free_particles_) + 1, 0);
  for (std::size_t e = 0; e < elements; ++e) {
    const Shape s = shape(e);
    VertexShape& v = vertex_shapes_[e];
    v.count = static_cast<int>(s.nodes.size());
    for (int j = 0; j < v.count; ++j) v.nodes[static_cast<std::size_t>(j)] = s.nodes[static_cast<std::size_t>(j)];
    v.G = s.G;
    v.W = s.W;
    v.model = s.model;
    v.lame = s.lame;
    for (int j = 0; j < v.count; ++j) {
      const int p = v.nodes[static_cast<std::size_t>(j)];
      if (p < free_particles_) ++counts[static_cast<std::size_t>(p) + 1];
    }
  }
  for (std::size_t p = 0; p < static_cast<std::size_t>(free_particles_); ++p) counts[p + 1] += counts[p];
  vertex_first_ = counts;
  vertex_elements_.resize(static_cast<std::size_t>(counts.back()));
  std::vector<int> next(counts.begin(), counts.end() - 1);
  for (std::size_t e = 0; e < elements; ++e) {
    const VertexShape& v = vertex_shapes_[e];
    for (int j = 0; j < v.count; ++j) {
      const int p = v.nodes[static_cast<std::size_t>(j)];
      if (p < free_particles_) {
        vertex_elements_[static_cast<std::size_t>(next[static_cast<std::size_t>(p)]++)] = {static_cast<int>(e), j};
      }
    }
  }
}

Mat ElementTerm::vertex_deformation(const Configuration& c, const VertexShape& e) const {
  const int dim = c.dim;
  const int k = static_cast<int>(e.G.cols());
  Mat F = Mat::Zero(dim, k);
  for (int j = 0; j < e.count; ++j) {
    const double* x = c.x + e.nodes[static_cast<std::size_t>(j)] * dim;
    for (int r = 0; r < dim; ++r) {
      for (int s = 0; s < k; ++s) F(r, s) += x[r] * e.G(j, s);
    }
  }
  return F;
}

void ElementTerm::add_vertex_blocks(const Configuration& c, const int* particles, int count,
                                    bool definite, const VertexBlocks& out) const {
  if (vertex_first_.empty()) build_vertex_elements();
  const int dim = c.dim;
  for (int n = 0; n < count; ++n) {
    const int p = particles[n];
    double* f = out.f + n * dim;
    double* K = out.dfdx + n * dim * dim;
    const int end = vertex_first_[static_cast<std::size_t>(p) + 1];
    for (int i = vertex_first_[static_cast<std::size_t>(p)]; i < end; ++i) {
      const VertexElement& ve = vertex_elements_[static_cast<std::size_t>(i)];
      const VertexShape& e = vertex_shapes_[static_cast<std::size_t>(ve.element)];
      const int k = static_cast<int>(e.G.cols());
      const Mat F = vertex_deformation(c, e);
      const auto g = e.G.row(ve.slot);
      const Mat P = e.model->P(F, e.lame);
      Eigen::Matrix3d block = Eigen::Matrix3d::Zero();  // dF_p/dx_p, top-left d x d
      for (int r = 0; r < dim; ++r) {
        f[r] -= e.W * (P.row(r) * g.transpose())(0, 0);
        Mat dF = Mat::Zero(dim, k);
        dF.row(r) = g;  // e_r g_a^T
        const Mat dP = e.model->dP(F, dF, e.lame);
        for (int q = 0; q < dim; ++q) block(q, r) = -e.W * (dP.row(q) * g.transpose())(0, 0);
      }
      if (definite) {
        // The element's Hessian block -block with its negative eigenvalues
        // set to 0 (make_definite, fem_elements.h).
        Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, 3, 3> small =
            block.topLeftCorner(dim, dim);
        make_definite(small);
        block.topLeftCorner(dim, dim) = small;
      }
      for (int r = 0; r < dim; ++r) {
        for (int q = 0; q < dim; ++q) K[r * dim + q] += block(r, q);
      }
    }
  }
}

double ElementTerm::vertex_admissible_fraction(const Configuration& c, int particle,
                                               const double* dx) const {
  double fraction = std::numeric_limits<double>::infinity();
  if (!forbids_states_) return fraction;
  if (vertex_first_.empty()) build_vertex_elements();
  const int dim = c.dim;
  const int end = vertex_first_[static_cast<std::size_t>(particle) + 1];
  for (int i = vertex_first_[static_cast<std::size_t>(particle)]; i < end; ++i) {
    const VertexElement& ve = vertex_elements_[static_cast<std::size_t>(i)];
    const VertexShape& e = vertex_shapes_[static_cast<std::size_t>(ve.element)];
    if (e.model->finite_everywhere || e.G.cols() != dim) continue;  // no cap (see above)
    const Mat F = vertex_deformation(c, e);
    const double J = F.determinant();
    if (!(J > 0.0)) return 0.0;  // inverted already: no step keeps it allowed
    Eigen::Matrix<double, Eigen::Dynamic, 1, 0, 3, 1> u(dim);
    for (int r = 0; r < dim; ++r) u[r] = dx[r];
    // g_a^T F^-1 dx
    const double s = e.G.row(ve.slot).dot(F.partialPivLu().solve(u));
    if (s < 0.0) fraction = std::min(fraction, -1.0 / s);
  }
  return fraction;
}

}  // namespace springlab
