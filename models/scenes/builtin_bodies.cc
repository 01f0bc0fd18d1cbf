// The built-in rigid body scenes (docs/scenes.md "Built-in scenes",
// docs/physics.md "Rigid bodies (affine bodies)"):
//   tumbling-box: a box with three distinct principal moments, no gravity,
//     spun about its middle axis with a small perturbation about the other
//     two: the rotation about the intermediate axis is unstable, and the box
//     flips over and back (the Dzhanibekov or tennis-racket effect) while
//     its angular momentum stays fixed;
//   box-on-slope: a cube resting on a plane inclined at `angle` with
//     friction mu: it sticks when tan(angle) < mu (creeping below the
//     smoothing speed) and slides with a = g (sin - mu cos) otherwise;
//   box-chain: n boxes hinged end to end by zero-length springs between
//     body points (body_springs.h), the first to a fixed particle: a
//     multiple pendulum released from horizontal;
//   box-pile: n boxes, each smaller than the one below, dropped onto one
//     another and the ground (body-body contact and friction,
//     body_body_contact.cc, body_body_friction.cc).
#include <Eigen/Geometry>
#include <cmath>
#include <map>
#include <numbers>
#include <sstream>
#include <string>

#include "models/bodies/bodies.h"
#include "models/bodies/body_springs.h"
#include "models/contact/contact.h"
#include "models/springs/gravity.h"
#include "models/core/scene.h"
#include "models/springs/springs.h"

namespace springlab {

using Values = std::map<std::string, double>;

// Box sides along x, y, z: (size_x, size_y, size_z) with size_x > size_y >
// size_z, so the principal moments I_x < I_y < I_z and y is the middle
// axis. The angular velocity is spin (perturbation, 1, perturbation).
Scene build_tumbling_box(const Values& p) {
  const Eigen::Vector3d size(p.at("size_x"), p.at("size_y"), p.at("size_z"));
  Scene scene;
  scene.dimension = 3;
  scene.block<Springs>();
  Body box;
  box.shape = Body::Shape::kBox;
  box.size = size;
  box.density = p.at("density");
  box.rigidity = p.at("rigidity");
  box.position = Eigen::Vector3d::Zero();
  const double spin = p.at("spin"), e = p.at("perturbation");
  box.omega = spin * Eigen::Vector3d(e, 1.0, e);
  scene.block<Bodies>().push_back(box);
  return scene;
}

// The plane through the origin descends along +x at `angle`:
//   n = (sin theta, cos theta, 0), down-slope s = (cos theta, -sin theta, 0).
// The cube is turned about z by -theta (its y axis along n) and rests on
// its bottom face, sunk to the penalty's resting depth
// m g cos(theta) / (4 k_c) (four corners share the weight's normal part).
Scene build_box_on_slope(const Values& p) {
  if (!(p.at("angle") >= 0.0 && p.at("angle") < 90.0)) {
    std::ostringstream message;
    message << "scene 'box-on-slope': parameter 'angle' must be in [0, 90) degrees (got "
            << p.at("angle") << ")";
    throw SceneError(message.str());
  }
  const double theta = p.at("angle") * std::numbers::pi / 180.0;
  const double s = p.at("size"), rho = p.at("density"), g = p.at("g");
  const double k_c = p.at("contact_stiffness");
  const double m = rho * s * s * s;
  const Eigen::Vector3d n(std::sin(theta), std::cos(theta), 0.0);
  const Eigen::Vector3d down_slope(std::cos(theta), -std::sin(theta), 0.0);
  Scene scene;
  scene.dimension = 3;
  scene.block<Gravity>().acceleration = {0.0, -g, 0.0};
  scene.block<Springs>();
  Body box;
  box.shape = Body::Shape::kBox;
  box.size = Eigen::Vector3d::Constant(s);
  box.density = rho;
  box.rigidity = p.at("rigidity");
  box.orientation = {0.0, 0.0, -theta};
  box.position = (0.5 * s - m * g * std::cos(theta) / (4.0 * k_c)) * n;
  box.v = p.at("speed") * down_slope;
  scene.block<Bodies>().push_back(box);
  Plane plane;
  plane.normal = n;
  plane.friction = p.at("friction");
  scene.block<Planes>().push_back(plane);
  Contact& contact = scene.block<Contact>();
  contact.stiffness = k_c;
  contact.smoothing = p.at("smoothing");
  return scene;
}

// Box i has sides (s, 0.75 s, 0.5 s) f^i (f = shrink), its shortest side
// vertical, turned about the vertical by 0.15 i rad and tilted by 0.05 rad
// (i > 0), and starts a quarter of its height above the top of the box
// below (the ground for i = 0). Every box has the ground's friction mu
// against the others (body_body_friction.cc): a tilted box lands on an
// edge, and without friction the push of the box below, tilting under it,
// would slide it off. With f = 0.8 each box's corners lie
// inside the top face of the one below (the corner (0.4, 0.3) s turned by
// 0.15 rad is at (0.351, 0.356) s, inside (0.5, 0.375) s), which is what
// vertex-in-box contact needs (docs/physics.md "Contact between bodies").
Scene build_box_pile(const Values& p) {
  const int n = static_cast<int>(p.at("n"));
  const double s = p.at("size"), f = p.at("shrink");
  if (!(f <= 1.0)) {
    std::ostringstream message;
    message << "scene 'box-pile': parameter 'shrink' must be in (0, 1] (got " << f << ")";
    throw SceneError(message.str());
  }
  Scene scene;
  scene.dimension = 3;
  scene.block<Gravity>().acceleration = {0.0, -p.at("g"), 0.0};
  scene.block<Springs>();
  double top = 0.0;
  double scale = 1.0;
  for (int i = 0; i < n; ++i, scale *= f) {
    Body box;
    box.shape = Body::Shape::kBox;
    box.size = scale * Eigen::Vector3d(s, 0.5 * s, 0.75 * s);
    box.density = p.at("density");
    box.rigidity = p.at("rigidity");
    // Turned about the vertical, then tilted about x by 0.05 rad (i > 0).
    const Eigen::AngleAxisd turn(Eigen::AngleAxisd(0.15 * i, Eigen::Vector3d::UnitY()) *
                                 Eigen::AngleAxisd(i > 0 ? 0.05 : 0.0, Eigen::Vector3d::UnitX()));
    const Eigen::Vector3d r = turn.angle() * turn.axis();
    box.orientation = {r.x(), r.y(), r.z()};
    box.friction = p.at("friction");
    const double height = box.size.y();
    box.position = Eigen::Vector3d(0.0, top + 0.25 * height + 0.5 * height, 0.0);
    top += 1.25 * height;
    scene.block<Bodies>().push_back(box);
  }
  Plane ground;
  ground.normal = {0.0, 1.0, 0.0};
  ground.friction = p.at("friction");
  scene.block<Planes>().push_back(ground);
  Contact& contact = scene.block<Contact>();
  contact.stiffness = p.at("contact_stiffness");
  return scene;
}

// Boxes of sides (length, width, width) laid end to end along +x from the
// fixed particle at the origin; each joint a zero-length spring of stiffness
// k between the end points (+-length/2, 0, 0) of neighbours (the first: the
// particle and box 0's left end), a ball joint as stiff as k.
Scene build_box_chain(const Values& p) {
  const int n = static_cast<int>(p.at("n"));
  const double length = p.at("length"), width = p.at("width");
  Scene scene;
  scene.dimension = 3;
  scene.block<Gravity>().acceleration = {0.0, -p.at("g"), 0.0};
  scene.block<Springs>();
  Particle anchor;
  anchor.fixed = true;
  scene.particles.push_back(anchor);
  const Eigen::Vector3d left(-0.5 * length, 0.0, 0.0), right(0.5 * length, 0.0, 0.0);
  for (int b = 0; b < n; ++b) {
    Body box;
    box.shape = Body::Shape::kBox;
    box.size = Eigen::Vector3d(length, width, width);
    box.density = p.at("density");
    box.rigidity = p.at("rigidity");
    box.position = Eigen::Vector3d((b + 0.5) * length, 0.0, 0.0);
    scene.block<Bodies>().push_back(box);
    BodySpring joint;
    joint.k = p.at("k");
    joint.rest = 0.0;
    if (b == 0) {
      joint.i.particle = 0;
    } else {
      joint.i.body = b - 1;
      joint.i.X = right;
    }
    joint.j.body = b;
    joint.j.X = left;
    scene.block<BodySprings>().push_back(joint);
  }
  return scene;
}

}  // namespace springlab
