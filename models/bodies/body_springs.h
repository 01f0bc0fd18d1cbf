// Springs with a body point at one end or both (docs/physics.md "Springs to
// body points"): a spring of the scene's "springs" whose `i` or `j` is
// `{"body": b, "X": [x, y, z]}` instead of a particle index. They are kept
// apart from the particle springs (springs.h), whose fast loop, damping,
// drawing and fast-solver constraints know particles only; this block is
// the "body-spring" element kind's (body_springs.cc, body_spring_force.cc).
//
// X is given in the body's own frame: the frame its `vertices` (or its
// shape, centred at the origin) are written in, before `orientation` and
// `position` move it. The model converts it to the principal frame,
// X_p = R^T (X - c) (bodies.h), where the point is at x = p + A X_p.
#pragma once

#include <Eigen/Core>
#include <vector>

namespace springlab {

class Scene;

// One end of a body spring: a particle (body < 0) or a point of a body.
struct SpringEnd {
  int particle = -1;                            // scene particle index, when body < 0
  int body = -1;                                // scene body index
  Eigen::Vector3d X = Eigen::Vector3d::Zero();  // the point, in the body's own frame [m]
  bool is_body() const { return body >= 0; }
};

// k and rest as for particle springs (springs.h); no damping (refused).
struct BodySpring {
  SpringEnd i, j;  // at least one a body point
  double k = 0.0;
  double rest = 0.0;  // resolved: the ends' distance at rest when the file omits it
};

// `scene.block<BodySprings>()`. In a scene file they sit in "springs" among
// the particle springs, in any order; written back after them.
using BodySprings = std::vector<BodySpring>;

// Where the end is at t = 0 (a particle's rest position X; a body point's
// place p(0) + A(0) X_p, i.e. the point turned and moved with its body).
Eigen::Vector3d spring_end_rest_point(const Scene& scene, const SpringEnd& end);

}  // namespace springlab
