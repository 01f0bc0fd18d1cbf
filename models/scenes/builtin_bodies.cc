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

#include "models/scenes/scene_entry.h"

namespace springlab {

using Values = SceneValues;

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

const SceneEntry& box_chain_scene() {
  static const SceneEntry entry = scene_entry(
      "box-chain",
          "n boxes hinged end to end by stiff zero-length springs between body points, the "
          "first to a fixed point, released from horizontal: a multiple pendulum",
         {param("n", 3, "number of boxes", Range::kWhole, 1, 1000),
          param("length", 0.2, "length of each box along the chain [m]", Range::kPositive),
          param("width", 0.05, "its two other sides [m]", Range::kPositive),
          param("k", 1e4, "stiffness of each joint's spring [N/m]", Range::kNonNegative),
          param("density", 1000, "density [kg/m^3]", Range::kPositive),
          param("rigidity", 1e6, "rigidity kappa [Pa]", Range::kPositive),
          param("g", 9.81, "gravitational acceleration, pointing down [m/s^2]", Range::kAny)},
         build_box_chain);
  return entry;
}

const SceneEntry& box_on_slope_scene() {
  static const SceneEntry entry = scene_entry(
      "box-on-slope",
          "a cube resting on (or launched down) an inclined plane with Coulomb friction: sticks "
          "when tan(angle) < friction, else slides at g (sin - friction cos)",
         {param("angle", 20, "inclination of the plane [degrees], in [0, 90)", Range::kAny),
          param("friction", 0.5, "Coulomb coefficient mu of the plane", Range::kNonNegative),
          param("speed", 0, "initial speed down the slope [m/s]", Range::kAny),
          param("size", 0.2, "side of the cube [m]", Range::kPositive),
          param("density", 1000, "density [kg/m^3]", Range::kPositive),
          param("rigidity", 1e6, "rigidity kappa [Pa]", Range::kPositive),
          param("g", 9.81, "gravitational acceleration, pointing down [m/s^2]", Range::kAny),
          param("contact_stiffness", 1e5, "penalty stiffness k_c per vertex [N/m]",
                Range::kPositive),
          param("smoothing", 1e-3, "friction's smoothing speed eps_v [m/s]", Range::kPositive)},
         build_box_on_slope);
  return entry;
}

const SceneEntry& box_pile_scene() {
  static const SceneEntry entry = scene_entry(
      "box-pile",
          "n boxes, each shrink times the one below, turned and tilted, dropped onto one "
          "another and onto the ground, with friction",
         {param("n", 3, "number of boxes", Range::kWhole, 1, 1000),
          param("size", 0.2, "longest side of the bottom box (sides size, 0.75 size, 0.5 size) [m]",
                Range::kPositive),
          param("shrink", 0.7, "each box's sides over the one's below, in (0, 1]", Range::kPositive),
          param("density", 1000, "density [kg/m^3]", Range::kPositive),
          param("rigidity", 1e6, "rigidity kappa [Pa]", Range::kPositive),
          param("friction", 0.5, "Coulomb coefficient mu of the ground and of every box",
                Range::kNonNegative),
          param("g", 9.81, "gravitational acceleration, pointing down [m/s^2]", Range::kAny),
          param("contact_stiffness", 1e5, "penalty stiffness k_c per vertex [N/m]",
                Range::kPositive)},
         build_box_pile);
  return entry;
}

const SceneEntry& tumbling_box_scene() {
  static const SceneEntry entry = scene_entry(
      "tumbling-box",
          "a box with three distinct principal moments spun about its middle axis, no gravity: "
          "it flips over and back (the Dzhanibekov effect)",
         {param("size_x", 0.3, "side along x, the axis of least inertia [m]", Range::kPositive),
          param("size_y", 0.2, "side along y, the middle axis, spun about [m]", Range::kPositive),
          param("size_z", 0.1, "side along z, the axis of most inertia [m]", Range::kPositive),
          param("spin", 6.283185307179586, "angular velocity about y [rad/s]", Range::kAny),
          param("perturbation", 0.01, "angular velocity about x and z, as a fraction of spin",
                Range::kAny),
          param("density", 1000, "density [kg/m^3]", Range::kPositive),
          param("rigidity", 1e6, "rigidity kappa of kappa V |A^T A - I|^2 [Pa]", Range::kPositive)},
         build_tumbling_box);
  return entry;
}

}  // namespace springlab
