// Rigid bodies as affine bodies (docs/physics.md "Rigid bodies (affine
// bodies)"; Lan, Kaufman, Li, Jiang, Yang, "Affine Body Dynamics: Fast,
// Stable & Intersection-free Simulation of Stiff Materials", ACM TOG 41(4),
// 2022): the scene's "bodies" block and what the model derives from it.
//
// A body point with rest coordinates X (principal frame, origin at the centre
// of mass) is at x = p + A X. The 12 unknowns of a free body are p and the
// columns a_1, a_2, a_3 of A, held in the model's state as four 3-vectors
// ("pseudo-particles") after the free particles: internal indices
// free_particles + 4 b + {0, 1, 2, 3} for the b-th free body, with the
// diagonal masses m, J_1, J_2, J_3 (J_i = integral rho X_i^2 dV). A fixed
// body is not in the state: it stays where it starts and exerts nothing.
#pragma once

#include <Eigen/Core>
#include <array>
#include <optional>
#include <string_view>
#include <vector>

#include "models/bodies/mass_properties.h"
#include "models/core/force_term.h"

namespace springlab {

class Scene;

inline constexpr double kDefaultRigidity = 1e6;  // kappa [Pa]
inline constexpr int kDefaultCylinderSegments = 32;
inline constexpr std::size_t kMaxSceneBodies = 10'000;
inline constexpr std::size_t kMaxBodyVertices = 1'000'000;
// The surface vertices of all a scene's bodies together (a cylinder has
// 2 segments + 2): each is held by several of the model's terms (issue
// 46.7: 100 cylinders of 100000 segments, a 10 KB file, took 2 GB).
inline constexpr std::size_t kMaxSceneBodyVertices = 1'000'000;


// One entry of "bodies", as the file gives it.
struct Body {
  enum class Shape { kMesh, kBox, kCylinder };
  Shape shape = Shape::kBox;
  std::vector<Eigen::Vector3d> vertices;  // kMesh
  std::vector<SurfaceTriangle> triangles;  // kMesh
  Eigen::Vector3d size = Eigen::Vector3d::Ones();  // kBox: side lengths along x, y, z [m]
  double radius = 0.5, height = 1.0;               // kCylinder, about z [m]
  int segments = kDefaultCylinderSegments;         // kCylinder
  double density = 1000.0;                         // rho [kg/m^3]
  // The centre of mass's initial place; absent: where the mesh puts it
  // (built-in shapes are centred at the origin).
  std::optional<Eigen::Vector3d> position;
  // As given: 4 numbers (quaternion w, x, y, z; normalised on use) or 3 (a
  // rotation vector, angle times unit axis [rad]); empty: no rotation. It
  // turns the mesh about its centre of mass.
  std::vector<double> orientation;
  // The initial A itself (rows), instead of orientation: a strained start
  // (the derivative tests; docs/physics.md).
  std::optional<Eigen::Matrix3d> affine;
  Eigen::Vector3d v = Eigen::Vector3d::Zero();      // centre of mass velocity [m/s]
  Eigen::Vector3d omega = Eigen::Vector3d::Zero();  // angular velocity, world frame [rad/s]
  bool fixed = false;
  double rigidity = kDefaultRigidity;  // kappa [Pa]
  // Coulomb mu against other bodies (a pair uses sqrt(mu_a mu_b);
  // body_body_friction.cc); the planes' friction is the plane's own.
  double friction = 0.0;
  // alpha [s/m] of the damping along the normal of its contacts, after
  // Hunt and Crossley: -alpha f_n v_n while slow, at most f_n
  // (contact_potential.h's normal_damping; docs/physics.md "Contact between
  // bodies"; a pair uses (alpha_a + alpha_b) / 2, a plane the body's own
  // alpha): collisions that dissipate (body_body_friction.cc, body_forces.cc).
  double contact_damping = 0.0;
};
using Bodies = std::vector<Body>;

// The surface vertices of one body: a box's 8, a cylinder's 2 segments + 2,
// a mesh's own.
std::size_t body_surface_vertices(const Body& body);

// The surface of a body (its mesh, or its shape's), in the file's frame.
void body_surface(const Body& body, std::vector<Eigen::Vector3d>& vertices,
                  std::vector<SurfaceTriangle>& triangles);

// The rotation Q of `orientation` (identity when empty).
Eigen::Matrix3d body_rotation(const Body& body);

// What the model needs of one body.
struct RigidBody {
  MassProperties mass;             // m, V, c, R, J
  std::vector<Eigen::Vector3d> X;  // rest coordinates of the surface vertices
  std::vector<SurfaceTriangle> triangles;
  Eigen::Vector3d p0, v0;          // initial p and dp/dt
  Eigen::Matrix3d A0, Adot0;       // initial A = Q R (or `affine`), dA/dt = [omega]x A
  double rigidity = 0.0;
  bool fixed = false;
};
RigidBody rigid_body(const Body& body);

// The bodies of a scene, derived (in scene order), and the internal index of
// each one's p pseudo-particle (-1: a fixed body), given where the bodies'
// unknowns start (0 where only the bodies' shapes are wanted).
struct BodyLayout {
  std::vector<RigidBody> bodies;
  std::vector<int> first;  // internal index of p; a_i at first + 1 + i
  int pseudo_particles = 0;
};
BodyLayout body_layout(const Scene& scene, int first_unknown);
// The same for one model's internal order, where the body kind's own
// unknowns (element_kind.h OwnUnknowns) start at order.first_own(kBodyKind).
inline constexpr std::string_view kBodyKind = "body";
BodyLayout body_layout(const Scene& scene, const ParticleOrder& order);

// 4 per free body.
int body_pseudo_particles(const Scene& scene);

// The state of a free body's unknowns (the model's initial state, mass).
void body_initial_state(const RigidBody& body, double* x, double* v, double* mass);

// One body's p, A and momenta at a state (the --json "bodies"): linear
// momentum P = m dp/dt; angular momentum about the origin
//   L = integral rho x cross v dV = m p x dp/dt + sum_i J_i a_i x da_i/dt
// (the first moments and the products of inertia vanish in the principal
// frame), and about the centre of mass L_c = L - p x P.
struct BodyState {
  Eigen::Vector3d p, dp;
  Eigen::Matrix3d A, dA;
  Eigen::Vector3d linear_momentum, angular_momentum, angular_momentum_about_centre;
};
BodyState body_state(const RigidBody& body, int first, const double* x, const double* v);

}  // namespace springlab
