#include "experiments/io/vtk_bodies.h"

namespace springlab {

VtkBodies::VtkBodies(const Scene& scene, int first_unknown)
    : layout_(body_layout(scene, first_unknown)) {
  for (const RigidBody& b : layout_.bodies) points_ += static_cast<int>(b.X.size());
}

void VtkBodies::append_cells(int first_point, std::vector<Cell>& cells) const {
  int base = first_point;
  for (const RigidBody& b : layout_.bodies) {
    for (const SurfaceTriangle& t : b.triangles) {
      cells.push_back({.size = 3, .nodes = {base + t[0], base + t[1], base + t[2], 0}});
    }
    base += static_cast<int>(b.X.size());
  }
}

void VtkBodies::append_fixed(std::vector<unsigned char>& fixed) const {
  for (const RigidBody& b : layout_.bodies) fixed.insert(fixed.end(), b.X.size(), b.fixed ? 1 : 0);
}

void VtkBodies::states(const Vector& x, const Vector& v, Eigen::MatrixXd& positions,
                       Eigen::MatrixXd& velocities) const {
  positions.resize(points_, 3);
  velocities.resize(points_, 3);
  Eigen::Index row = 0;
  for (std::size_t b = 0; b < layout_.bodies.size(); ++b) {
    const RigidBody& body = layout_.bodies[b];
    const BodyState s = body_state(body, layout_.first[b], x.data(), v.data());
    for (const Eigen::Vector3d& X : body.X) {
      positions.row(row) = (s.p + s.A * X).transpose();
      velocities.row(row) = (s.dp + s.dA * X).transpose();
      ++row;
    }
  }
}

}  // namespace springlab
