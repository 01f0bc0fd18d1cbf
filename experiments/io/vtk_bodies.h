// The rigid bodies in --vtk frames (vtk_series.h; docs/physics.md "Rigid
// bodies (affine bodies)"): each body's closed surface as triangles, its
// vertices as points after the particles', at x = p + A X with velocity
// dp/dt + dA/dt X (a fixed body where it starts, at rest, flagged fixed).
#pragma once

#include <Eigen/Core>
#include <vector>

#include "models/bodies/bodies.h"
#include "models/model/model.h"
#include "models/core/element_kind.h"

namespace springlab {

class VtkBodies {
 public:
  VtkBodies(const Scene& scene, int first_unknown);
  int points() const { return points_; }
  // Appends each body's triangles, numbering its points from `first_point`.
  void append_cells(int first_point, std::vector<Cell>& cells) const;
  // 1 per point of a fixed body, else 0.
  void append_fixed(std::vector<unsigned char>& fixed) const;
  // points() x 3: the surface vertices' positions and velocities at (x, v).
  void states(const Vector& x, const Vector& v, Eigen::MatrixXd& positions,
              Eigen::MatrixXd& velocities) const;

 private:
  BodyLayout layout_;
  int points_ = 0;
};

}  // namespace springlab
