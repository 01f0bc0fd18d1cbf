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
//     body_body_contact.cc, body_body_friction.cc);
//   box-tower: n equal boxes, each turned against the one below, dropped
//     onto one another into a tower;
//   box-drop: n boxes dropped in layers into a bin (the ground and four
//     walls), coming to rest on and against one another.
#include <Eigen/Geometry>
#include <cmath>
#include <cstdint>
#include <map>
#include <numbers>
#include <sstream>
#include <string>

#include "models/bodies.h"
#include "models/body_springs.h"
#include "models/contact.h"
#include "models/gravity.h"
#include "models/scene.h"
#include "models/springs.h"

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

// The contact of the box scenes: the ground's and the bodies' model
// ("contact": 0 penalty, 1 barrier), its stiffness (k_c or kappa) and its
// distance (the penalty's skin between bodies, the barrier's dhat).
void set_box_contact(const Values& p, Scene& scene) {
  Contact& contact = scene.block<Contact>();
  contact.model = p.at("contact") == 1.0 ? ContactModel::kBarrier : ContactModel::kPenalty;
  contact.stiffness = p.at("contact_stiffness");
  contact.distance = p.at("distance");
}

Body scene_box(const Values& p, const Eigen::Vector3d& size) {
  Body box;
  box.shape = Body::Shape::kBox;
  box.size = size;
  box.density = p.at("density");
  box.rigidity = p.at("rigidity");
  box.friction = p.at("friction");
  return box;
}

// The ground, with the boxes' friction.
Plane ground(const Values& p) {
  Plane plane;
  plane.normal = {0.0, 1.0, 0.0};
  plane.friction = p.at("friction");
  return plane;
}

// Box i has sides (s, 0.5 s, 0.75 s) f^i (f = shrink), its shortest side
// vertical, turned about the vertical by 0.15 i rad and tilted by 0.05 rad
// (i > 0), its lowest corner `drop` of its height above the highest of the
// box below (above the ground for i = 0). Every box has the ground's friction mu
// against the others (body_body_friction.cc): a tilted box lands on an
// edge, and without friction the push of the box below, tilting under it,
// would slide it off.
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
    Body box = scene_box(p, scale * Eigen::Vector3d(s, 0.5 * s, 0.75 * s));
    // Turned about the vertical, then tilted about x by `tilt` (i > 0).
    const Eigen::AngleAxisd turn(Eigen::AngleAxisd(0.15 * i, Eigen::Vector3d::UnitY()) *
                                 Eigen::AngleAxisd(i > 0 ? p.at("tilt") : 0.0, Eigen::Vector3d::UnitX()));
    const Eigen::Vector3d r = turn.angle() * turn.axis();
    box.orientation = {r.x(), r.y(), r.z()};
    // Half its extent along the vertical, turned: sum_j |Q_yj| size_j / 2.
    const double reach = 0.5 * turn.toRotationMatrix().row(1).cwiseAbs().dot(box.size);
    const double start = top + p.at("drop") * box.size.y();
    box.position = Eigen::Vector3d(0.0, start + reach, 0.0);
    top = start + 2.0 * reach;
    scene.block<Bodies>().push_back(box);
  }
  scene.block<Planes>().push_back(ground(p));
  set_box_contact(p, scene);
  return scene;
}

// n equal boxes of sides (s, 0.5 s, 0.75 s), box i turned about the
// vertical by +-`turn` (alternately), each starting `gap` of its height
// above the one below (the ground for the first): they fall onto each
// other edge across edge and stand as a tower.
Scene build_box_tower(const Values& p) {
  const int n = static_cast<int>(p.at("n"));
  const double s = p.at("size"), gap = p.at("gap") * 0.5 * s;
  Scene scene;
  scene.dimension = 3;
  scene.block<Gravity>().acceleration = {0.0, -p.at("g"), 0.0};
  scene.block<Springs>();
  const double height = 0.5 * s;
  for (int i = 0; i < n; ++i) {
    Body box = scene_box(p, Eigen::Vector3d(s, height, 0.75 * s));
    box.orientation = {0.0, (i % 2 == 0 ? 1.0 : -1.0) * p.at("turn"), 0.0};
    box.position = Eigen::Vector3d(0.0, (i + 1) * gap + (i + 0.5) * height, 0.0);
    scene.block<Bodies>().push_back(box);
  }
  scene.block<Planes>().push_back(ground(p));
  set_box_contact(p, scene);
  return scene;
}

// n boxes of sides (s, 0.7 s, 0.5 s) in layers of `columns` x `columns`
// over a square bin (the ground and four walls, `width` on a side), each
// at its grid point with a turn of its own (a fixed sequence, the same for
// every run), and dropped into it.
Scene build_box_drop(const Values& p) {
  const int n = static_cast<int>(p.at("n"));
  const int columns = static_cast<int>(p.at("columns"));
  const double s = p.at("size"), width = p.at("width");
  const double spacing = 1.5 * s;
  if (!(columns * spacing <= width)) {
    std::ostringstream message;
    message << "scene 'box-drop': " << columns << " columns of boxes 1.5 size apart need a bin "
            << "at least " << columns * spacing << " m wide (parameter 'width' is " << width
            << " m)";
    throw SceneError(message.str());
  }
  Scene scene;
  scene.dimension = 3;
  scene.block<Gravity>().acceleration = {0.0, -p.at("g"), 0.0};
  scene.block<Springs>();
  // A fixed sequence of numbers in [0, 1) (a linear congruential generator,
  // Numerical Recipes' constants: the same turns on every machine).
  std::uint32_t state = 12345;
  auto next = [&state] {
    state = 1664525u * state + 1013904223u;
    return state / 4294967296.0;
  };
  const double corner = -0.5 * (columns - 1) * spacing;
  for (int i = 0; i < n; ++i) {
    Body box = scene_box(p, Eigen::Vector3d(s, 0.7 * s, 0.5 * s));
    const int layer = i / (columns * columns), row = (i / columns) % columns, column = i % columns;
    Eigen::Vector3d axis(next() - 0.5, next() - 0.5, next() - 0.5);
    const double angle = 3.0 * next();
    axis = axis.norm() > 0.0 ? Eigen::Vector3d(axis.normalized()) : Eigen::Vector3d::UnitY();
    box.orientation = {angle * axis.x(), angle * axis.y(), angle * axis.z()};
    box.position = Eigen::Vector3d(corner + column * spacing, p.at("height") + layer * spacing,
                                   corner + row * spacing);
    scene.block<Bodies>().push_back(box);
  }
  scene.block<Planes>().push_back(ground(p));
  for (int side = 0; side < 4; ++side) {
    Plane wall = ground(p);
    const double sign = side % 2 == 0 ? 1.0 : -1.0;
    wall.normal = side < 2 ? Eigen::Vector3d(sign, 0.0, 0.0) : Eigen::Vector3d(0.0, 0.0, sign);
    wall.point = -0.5 * width * wall.normal;
    scene.block<Planes>().push_back(wall);
  }
  set_box_contact(p, scene);
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
