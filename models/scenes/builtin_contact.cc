// The built-in contact scene `slope` (docs/scenes.md "Built-in scenes"): one particle on an
// inclined plane, the closed forms of Coulomb friction (docs/physics.md "Contact with
// planes"). The plane passes through the origin and descends along +x at
// `angle` degrees:
//   normal n = (sin theta, cos theta),  down-slope tangent s = (cos theta, -sin theta),
// under gravity (0, -g). The particle starts at its resting depth
// d = -m g cos(theta) / k_c (penalty: k_c (-d) = the weight's normal
// component), moving down the slope at `speed`. With tan(theta) < mu it
// stays (creeping at less than the smoothing speed); with tan(theta) > mu it
// slides with acceleration g (sin theta - mu cos theta); at angle 0 a
// particle launched at speed v0 stops after v0^2 / (2 mu g). A fixed
// particle marks the foot of the slope, `length` down it.
#include <cmath>
#include <map>
#include <numbers>
#include <sstream>
#include <string>

#include "models/contact/contact.h"
#include "models/springs/gravity.h"
#include "models/core/scene.h"
#include "models/springs/springs.h"

#include "models/scenes/scene_entry.h"

namespace springlab {

using Values = SceneValues;

Scene build_slope(const Values& p) {
  if (!(p.at("angle") >= 0.0 && p.at("angle") < 90.0)) {
    std::ostringstream message;
    message << "scene 'slope': parameter 'angle' must be in [0, 90) degrees (got " << p.at("angle")
            << ")";
    throw SceneError(message.str());
  }
  const double theta = p.at("angle") * std::numbers::pi / 180.0;
  const double m = p.at("mass"), g = p.at("g"), k_c = p.at("contact_stiffness");
  const Eigen::Vector3d n(std::sin(theta), std::cos(theta), 0.0);
  const Eigen::Vector3d down_slope(std::cos(theta), -std::sin(theta), 0.0);
  Scene scene;
  scene.dimension = 2;
  scene.block<Gravity>().acceleration = {0.0, -g, 0.0};
  scene.block<Springs>();
  Particle particle;
  particle.mass = m;
  particle.x = -(m * g * std::cos(theta) / k_c) * n;
  particle.v = p.at("speed") * down_slope;
  scene.particles.push_back(particle);
  // The foot of the slope: a fixed particle joined to nothing (it exerts no
  // force) that gives the scene its size, the d of the divergence rule's
  // E_s = ... + m |g| d (docs/command-line.md "The command line"): a lone particle has d = 0, and
  // a slide would be called a blow-up once its kinetic energy passed 1000
  // times the tiny contact energy.
  Particle foot;
  foot.x = p.at("length") * down_slope;
  foot.fixed = true;
  scene.particles.push_back(foot);
  Plane plane;
  plane.normal = n;
  plane.friction = p.at("friction");
  scene.block<Planes>().push_back(plane);
  Contact& contact = scene.block<Contact>();
  contact.stiffness = k_c;
  contact.smoothing = p.at("smoothing");
  return scene;
}

const SceneEntry& slope_scene() {
  static const SceneEntry entry = scene_entry(
      "slope",
          "one particle resting on (or launched down) an inclined plane with Coulomb friction: "
          "sticks when tan(angle) < friction, else slides at g (sin - friction cos)",
         {param("angle", 30, "inclination of the plane [degrees], in [0, 90)", Range::kAny),
          param("friction", 0.5, "Coulomb coefficient mu of the plane", Range::kNonNegative),
          param("speed", 0, "initial speed down the slope [m/s]", Range::kAny),
          param("mass", 1, "mass of the particle [kg]", Range::kPositive),
          param("length", 10,
                "length of the slope [m]: a fixed particle marks its foot (it sets the scene's "
                "size in the energy scale E_s)",
                Range::kPositive),
          param("g", 9.81, "gravitational acceleration, pointing down [m/s^2]", Range::kAny),
          param("contact_stiffness", 1e5, "penalty stiffness k_c [N/m]", Range::kPositive),
          param("smoothing", 1e-3, "friction's smoothing speed eps_v [m/s]", Range::kPositive)},
         build_slope);
  return entry;
}

}  // namespace springlab
