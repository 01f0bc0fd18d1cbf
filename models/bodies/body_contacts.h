// Where rigid bodies meet (docs/physics.md "Contact between bodies"): the
// geometry shared by the normal force (body_body_contact.cc) and friction
// (body_body_friction.cc).
//
// A contact is two material points, X_a on body a and X_b on body b, and a
// unit normal n from b's point to a's; its gap
//
//   d = n . (x_a - x_b),   x_a = p_a + A_a X_a,  x_b = p_b + A_b X_b,
//
// is linear in the pair's 24 unknowns (p and the columns of A of each):
//   dd/dp_a = n,  dd/d(a_i of a) = X_a,i n,  dd/dp_b = -n,  dd/d(a_i of b) = -X_b,i n,
// i.e. dd/dq_u = w_u n with w = (1, X_a, -1, -X_b) on the pair's 8
// pseudo-particles (p_a, a_1, a_2, a_3 of a, then of b). Contacts come from
// the surfaces' distances at one state:
//   - each surface vertex of one body against the other's surface: the
//     nearest point over its triangles (point-triangle distances,
//     body_distance.h), one contact per vertex and body;
//   - each feature edge of one against each feature edge of the other
//     (segment-segment distances): where edges cross with no vertex near,
//     as two boxes edge to edge.
// Feature edges are the edges between triangles that are not coplanar (a
// box's 12, not the diagonals that split its faces): a diagonal is no edge
// of the solid, and its distance to another edge is never the surfaces'.
// At that state the gap of each contact is the distance of its two pieces,
// and n its direction; the bodies' distance is the smallest.
//
// Which pairs of bodies: a sweep and prune over the bodies' bounding boxes
// (each grown by a margin) along the axis where their centres spread most
// (Baraff, "Dynamic simulation of non-penetrating rigid bodies", 1992, sec.
// 6.3): the boxes sorted by their lower end, each compared with the ones
// whose interval it overlaps. Time n log n plus the overlapping pairs,
// memory linear in the bodies; never two fixed bodies, never two joined by
// a spring (a joint).
//
// Interpenetration (what neither the barrier nor the penalty between bodies
// allows): an edge of one surface through a triangle of the other, or a
// body wholly inside the other (a vertex's winding number).
#pragma once

#include <Eigen/Core>
#include <array>
#include <string>
#include <utility>
#include <vector>

#include "models/bodies/bodies.h"
#include "models/bodies/body_distance.h"

namespace springlab {

class Scene;

struct BodyContact {
  int a = 0, b = 0;                                // bodies (scene indices)
  Eigen::Vector3d Xa = Eigen::Vector3d::Zero();   // material point of a (principal frame)
  Eigen::Vector3d Xb = Eigen::Vector3d::Zero();   // material point of b
  Eigen::Vector3d n = Eigen::Vector3d::UnitY();   // unit normal, from b's point to a's
  double d = 0.0;                                  // the gap at the state it was found at
  // The two pieces whose distance it is: a's points (one vertex or an
  // edge's two), b's (a triangle's three or an edge's two), as vertex
  // indices of each body, and the closest points' weights on them.
  std::array<int, 3> va{}, vb{};
  SimplexDistance simplex;
};

// An interpenetration found: which bodies, and how (for the message).
struct BodyOverlap {
  int a = -1, b = -1;
  int edge_from = -1, edge_to = -1;  // a's edge (vertex indices) through b's triangle
  int triangle = -1;                 // -1: a lies inside b
  bool found() const { return a >= 0; }
  std::string text() const;
};

class BodyContactFinder {
 public:
  // One body's surface as contact sees it.
  struct Surface {
    int first = -1;  // internal index of p; -1: a fixed body
    Eigen::Vector3d p0 = Eigen::Vector3d::Zero();
    Eigen::Matrix3d A0 = Eigen::Matrix3d::Identity();
    std::vector<Eigen::Vector3d> X;  // rest coordinates of the vertices (principal frame)
    std::vector<SurfaceTriangle> triangles;
    std::vector<std::array<int, 2>> edges;          // every edge once
    std::vector<std::array<int, 2>> feature_edges;  // between triangles not coplanar
    double radius = 0.0;                            // max |X|
    double friction = 0.0;                          // mu against other bodies
    double contact_damping = 0.0;                   // alpha [s/m] (bodies.h)

    // At the model's state x (all particles; null: the initial state).
    Eigen::Vector3d p(const double* x) const;
    Eigen::Matrix3d A(const double* x) const;
  };

  BodyContactFinder(const Scene& scene, const BodyLayout& layout);

  int size() const { return static_cast<int>(surfaces_.size()); }
  const Surface& surface(int body) const { return surfaces_[static_cast<std::size_t>(body)]; }
  // Whether the pair may meet (not both fixed, not joined).
  bool may_meet(int a, int b) const;

  // Places every body at x (the model's state, all particles; null: the
  // initial state): its vertices in the world and its bounding box. The
  // queries below read the last placement.
  void place(const double* x);
  const std::vector<Eigen::Vector3d>& world(int body) const {
    return world_[static_cast<std::size_t>(body)];
  }

  // The pairs (a < b) that may meet whose boxes, body k's grown by
  // grow[k] on every side, overlap (sweep and prune), in a fixed order.
  void near_pairs(const std::vector<double>& grow, std::vector<std::pair<int, int>>& out) const;
  // The contacts of pair (a, b) whose gap is below r (appended).
  void contacts(int a, int b, double r, std::vector<BodyContact>& out) const;
  // All contacts below r, over the pairs whose boxes come within r.
  void all_contacts(double r, std::vector<BodyContact>& out) const;
  // The contacts an implicit step of length h keeps (body_body_contact.cc),
  // at the placed state with velocities v (the model's, all particles;
  // null: h is not read): those below r, and those that can come below r
  // within the step. Each body can move twice h (|p'| + |A'|_F R) + 2 g h^2
  // in it (R its bounding radius, g gravity's magnitude), and the pair's
  // contacts are searched below r plus both its bodies' reach (not at the
  // rate they approach at the start: in a pile the box below stops within
  // the step when it lands, and the one above, falling with it at the
  // start, closes the gap).
  void step_contacts(double r, const double* v, double h, double g,
                     std::vector<BodyContact>& out) const;
  // The first interpenetration, if any.
  BodyOverlap overlap() const;

  // The derivatives of a contact found at the placed state with respect to
  // the pair's 24 unknowns (a's p, a_1, a_2, a_3, then b's), where its
  // pieces' distance D moves with them (body_distance.h, on the active
  // points y_v = p + A Y_v of each body, dy_v/dq = (1, Y_v) (x) I):
  // dD/dq, d2D/dq2, dn/dq (n = P / D) and the material points' dX_a/dq,
  // dX_b/dq (the closest points slide over the pieces). D > 0.
  struct Derivatives {
    Eigen::Matrix<double, 24, 1> gradient;
    Eigen::Matrix<double, 24, 24> hessian;
    Eigen::Matrix<double, 3, 24> dn, dXa, dXb;
  };
  Derivatives derivatives(const BodyContact& c) const;

 private:
  void vertices_against(int a, int b, double r, std::vector<BodyContact>& out) const;
  void edges_against(int a, int b, double r, std::vector<BodyContact>& out) const;
  BodyOverlap crossing(int a, int b) const;

  std::vector<Surface> surfaces_;
  std::vector<std::pair<int, int>> joined_;  // sorted (a < b)
  std::vector<std::vector<Eigen::Vector3d>> world_;
  std::vector<Eigen::Vector3d> lo_, hi_;     // bounding boxes
  mutable std::vector<double> grow_;         // scratch
};

}  // namespace springlab
