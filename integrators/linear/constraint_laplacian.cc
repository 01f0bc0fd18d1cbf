#include "integrators/linear/constraint_laplacian.h"

namespace springlab {

SparseMatrix constraint_laplacian(const std::vector<DistanceConstraint>& constraints,
                                  Eigen::Index particles) {
  return constraint_laplacian(constraints, {}, particles);
}

SparseMatrix constraint_laplacian(const std::vector<DistanceConstraint>& constraints,
                                  const std::vector<ProjectiveElement>& elements,
                                  Eigen::Index particles) {
  std::vector<Eigen::Triplet<double>> entries;
  for (const ProjectiveElement& e : elements) {
    const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, 4, 4> GGt =
        e.weight * e.G * e.G.transpose();
    for (std::size_t i = 0; i < e.nodes.size(); ++i) {
      for (std::size_t j = 0; j < e.nodes.size(); ++j) {
        if (e.nodes[i] >= 0 && e.nodes[j] >= 0) {
          entries.emplace_back(e.nodes[i], e.nodes[j],
                               GGt(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)));
        }
      }
    }
  }
  for (const DistanceConstraint& c : constraints) {
    entries.emplace_back(c.a, c.a, c.stiffness);
    if (c.b >= 0) {
      entries.emplace_back(c.b, c.b, c.stiffness);
      entries.emplace_back(c.a, c.b, -c.stiffness);
      entries.emplace_back(c.b, c.a, -c.stiffness);
    }
  }
  for (Eigen::Index i = 0; i < particles; ++i) entries.emplace_back(i, i, 0.0);
  SparseMatrix L(particles, particles);
  L.setFromTriplets(entries.begin(), entries.end());
  L.makeCompressed();
  return L;
}

}  // namespace springlab
