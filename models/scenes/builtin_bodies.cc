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
#include <utility>
#include <vector>

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
  box.contact_damping = p.at("contact_damping");
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

// The box scenes' common parameters after their own: material, friction,
// gravity and contact (set_box_contact).
std::vector<ParameterSpec> box_params(std::vector<ParameterSpec> own) {
  return with(std::move(own),
              {param("density", 1000, "density [kg/m^3]", Range::kPositive),
               param("rigidity", 1e6, "rigidity kappa [Pa]", Range::kPositive),
               param("friction", 0.5, "Coulomb coefficient mu of the ground and of every box",
                     Range::kNonNegative),
               param("contact_damping", 2.0,
                     "every box's contact damping alpha [s/m] along the normal (after Hunt and "
                     "Crossley: -alpha f_n v_n when slow, at most f_n); 0: elastic contact",
                     Range::kNonNegative),
               param("g", 9.81, "gravitational acceleration, pointing down [m/s^2]", Range::kAny),
               choice("contact", "barrier",
                      "contact model of the ground and between boxes (IPC's barrier, or the "
                      "penalty)",
                      {"penalty", "barrier"}),
               param("contact_stiffness", 1e5,
                     "contact stiffness: the penalty's k_c or the barrier's kappa [N/m]",
                     Range::kPositive),
               param("distance", 1e-3,
                     "contact distance: the barrier's dhat, or the penalty's skin between boxes "
                     "[m]",
                     Range::kPositive)});
}

const SceneEntry& box_pile_scene() {
  static const SceneEntry entry = scene_entry(
      "box-pile",
      "n boxes, each shrink times the one below, turned and tilted, dropped onto one "
      "another and onto the ground, with friction",
      box_params({param("n", 3, "number of boxes", Range::kWhole, 1, 1000),
                  param("size", 0.2,
                        "longest side of the bottom box (sides size, 0.5 size, 0.75 size) [m]",
                        Range::kPositive),
                  param("shrink", 0.8, "each box's sides over the one's below, in (0, 1]",
                        Range::kPositive),
                  param("drop", 0.1, "each box's start above the one below, in its heights",
                        Range::kNonNegative),
                  param("tilt", 0.05, "each box but the first tilted about x [rad]",
                        Range::kAny)}),
      build_box_pile);
  return entry;
}

const SceneEntry& box_tower_scene() {
  static const SceneEntry entry = scene_entry(
      "box-tower",
      "n equal boxes, each turned against the one below, dropped onto one another into a "
      "tower",
      box_params({param("n", 10, "number of boxes", Range::kWhole, 1, 1000),
                  param("size", 0.2,
                        "longest side of each box (sides size, 0.5 size, 0.75 size) [m]",
                        Range::kPositive),
                  param("turn", 0.1, "each box turned about the vertical by +-turn [rad]",
                        Range::kAny),
                  param("gap", 0.1, "each box's start above the one below, in its heights",
                        Range::kPositive)}),
      build_box_tower);
  return entry;
}

const SceneEntry& box_drop_scene() {
  static const SceneEntry entry = scene_entry(
      "box-drop",
      "n boxes dropped in layers, each turned its own way, into a square bin (the ground "
      "and four walls), coming to rest",
      box_params({param("n", 100, "number of boxes", Range::kWhole, 1, 10000),
                  param("size", 0.1,
                        "longest side of each box (sides size, 0.7 size, 0.5 size) [m]",
                        Range::kPositive),
                  param("columns", 5, "boxes along each side of a layer", Range::kWhole, 1, 100),
                  param("width", 0.8, "the bin's inner width [m]", Range::kPositive),
                  param("height", 0.15, "height of the lowest layer's centres [m]",
                        Range::kPositive)}),
      build_box_drop);
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
