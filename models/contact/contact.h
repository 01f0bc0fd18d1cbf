// Contact in a scene (docs/physics.md "Contact with planes"): the blocks of scene data of the
// "contact" kind (contact_kind.cc: how contact is modelled) and the "plane" kind
// (planes.cc: the half-spaces free particles must not enter, and their
// force; friction_force.cc: Coulomb friction along them).
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <vector>

namespace springlab {

// The half-space n.(x - point) >= 0, n = normal / |normal| (`normal` is
// kept as given, nonzero).
struct Plane {
  Eigen::Vector3d point = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal = Eigen::Vector3d::UnitY();
  // Coulomb mu >= 0 (docs/physics.md "Contact with planes"; friction_force.cc).
  double friction = 0.0;
};
using Planes = std::vector<Plane>;

enum class ContactModel { kPenalty, kBarrier };

// `scene.get<Contact>()`: defaults when the scene file has no "contact".
struct Contact {
  ContactModel model = ContactModel::kPenalty;
  // k_c [N/m] of the penalty k_c/2 min(d, 0)^2; kappa [N/m] of the barrier
  // kappa b(d). Absent from the file: the model's default below.
  double stiffness = 0.0;
  double distance = 0.0;    // the barrier's dhat [m]; absent: the default
  double smoothing = 1e-3;  // friction's eps_v [m/s]
  double stiffness_or_default() const {
    return stiffness > 0.0 ? stiffness : (model == ContactModel::kPenalty ? 1e4 : 1e3);
  }
  double distance_or_default() const { return distance > 0.0 ? distance : 1e-2; }
};

inline constexpr std::size_t kMaxScenePlanes = 10'000;

class Reporter;
class Scene;
// With the barrier, every free particle must start outside every plane
// (gap > 0): the barrier's energy is infinite at d <= 0. Refused naming the
// plane, the particle and its gap (planes.cc). It needs the particles, so the
// friction kind (read after them) calls it.
void check_barrier_start(const Scene& scene, const Reporter& r);

}  // namespace springlab
