// The geometry of contact between rigid bodies (docs/physics.md "Contact
// between bodies"), shared by its normal force (body_body_contact.cc) and its
// friction (body_body_friction.cc): which pairs meet, which vertices of one
// are inside the other (a box), through which face, and the gap's gradient.
//
// A pair (a, b): the surface vertices x = p_a + A_a X of body a against box
// b (half sides h, principal frame), through the face of b facing a's
// centre: with Z = A_b^{-1} (p_a - p_b), the axis i maximizing |Z_i| / h_i,
// the side s = sign(Z_i). A vertex is over that face when
// Y = A_b^{-1} (x - p_b) has |Y_k| < h_k for k != i and s Y_i > -h_i, and
// through it when its gap
//   d = s a_i . (x - p_b) - h_i a_i . a_i      (= s Y_i - h_i when A_b is a rotation)
// is negative (the penalty's own switch, so the energy is continuous as
// the vertex enters, strained A_b or not).
// has the gradient, on the pair's 8 unknowns u = (p_a, a_1, a_2, a_3 of a,
// then p_b, a_1, a_2, a_3 of b),
//   dd/dq_alpha = w_alpha s a_i (w = (1, X)),  dd/dp_b = -s a_i,
//   dd/da_i(b) = s (x - p_b) - 2 h_i a_i.
// b's material point Y under the vertex follows from x = p_b + A_b Y:
//   dY = A_b^{-1} sum_u c_u dq_u,   c = (w_0, w_1, w_2, w_3, -1, -Y_1, -Y_2, -Y_3),
// and the velocity of the vertex relative to b's material point under it is
//   v_rel = (p_a' + A_a' X) - (p_b' + A_b' Y) = sum_u c_u v_u.
#pragma once

#include <Eigen/Core>
#include <Eigen/LU>
#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

#include "models/bodies/bodies.h"
#include "models/core/force_term.h"

namespace springlab {

class BodyPairs {
 public:
  // One body as the pairs see it: where its unknowns are (or its fixed p,
  // A), its surface vertices' X, and for a box its half sides; the
  // bounding radius max |X|.
  struct Member {
    int first = -1;  // -1: fixed
    Eigen::Vector3d p0 = Eigen::Vector3d::Zero();
    Eigen::Matrix3d A0 = Eigen::Matrix3d::Identity();
    std::vector<Eigen::Vector3d> X;
    bool box = false;
    Eigen::Vector3d half = Eigen::Vector3d::Zero();
    double radius = 0.0;
    double friction = 0.0;  // the body's mu against other bodies

    Eigen::Vector3d p(const double* x) const {
      return first < 0 ? p0 : Eigen::Vector3d(x[3 * first], x[3 * first + 1], x[3 * first + 2]);
    }
    Eigen::Matrix3d A(const double* x) const {
      if (first < 0) return A0;
      Eigen::Matrix3d A;
      for (int i = 0; i < 3; ++i) {
        for (int r = 0; r < 3; ++r) A(r, i) = x[3 * (first + 1 + i) + r];
      }
      return A;
    }
  };

  struct Pair {
    int a = 0, b = 0;           // the vertices' body, the box
    std::array<int, 8> index{};  // internal indices of the 8 unknowns; -1 where fixed
    double friction = 0.0;       // sqrt(mu_a mu_b)
  };

  // A vertex inside a box: the pair, the vertex, the face (axis i, side s),
  // the gap d, the vertex x, b's p, A and material point Y under the vertex,
  // and the coefficients c of dY = A_b^{-1} sum_u c_u dq_u.
  struct Touch {
    std::size_t pair = 0;
    int vertex = 0;
    int axis = 0;
    double side = 1.0;
    double d = 0.0;
    Eigen::Vector3d x, pb, Y;
    Eigen::Matrix3d Ab;
    std::array<double, 8> c{};
  };

  // The pairs of a scene: every body against every box, not two fixed ones,
  // not two joined by a body spring (a joint).
  BodyPairs(const Scene& scene, const BodyLayout& layout);

  const std::vector<Pair>& pairs() const { return pairs_; }
  const Member& member(int body) const { return members_[static_cast<std::size_t>(body)]; }

  // Visits every vertex over a box's contact face at positions x (its
  // gap d of either sign).
  template <typename Visit>
  void for_each_inside(const double* x, Visit visit) const {
    for (std::size_t k = 0; k < pairs_.size(); ++k) {
      const Member& a = member(pairs_[k].a);
      const Member& b = member(pairs_[k].b);
      const Eigen::Vector3d pa = a.p(x), pb = b.p(x);
      const Eigen::Matrix3d Aa = a.A(x), Ab = b.A(x);
      // Bounding spheres (radii scaled by the largest column stretch).
      const double reach_a = a.radius * Aa.colwise().norm().maxCoeff();
      const double reach_b = b.radius * Ab.colwise().norm().maxCoeff();
      if ((pa - pb).norm() > reach_a + reach_b) continue;
      const Eigen::PartialPivLU<Eigen::Matrix3d> inverse(Ab);
      const Eigen::Vector3d Z = inverse.solve(pa - pb);
      int axis = 0;
      Z.cwiseAbs().cwiseQuotient(b.half).maxCoeff(&axis);
      const double side = Z[axis] >= 0.0 ? 1.0 : -1.0;
      for (std::size_t v = 0; v < a.X.size(); ++v) {
        Touch t;
        t.x = pa + Aa * a.X[v];
        t.Y = inverse.solve(t.x - pb);
        // Over the face (within its sides) and short of the opposite one;
        // whether it is through the face is d's sign, so that the penalty
        // starts at d = 0 even where A_b is strained (there d = 0 and
        // Y_i = s h_i differ by the shear a_i . a_k).
        bool over = side * t.Y[axis] > -b.half[axis];
        for (int k = 0; k < 3; ++k) over = over && (k == axis || std::abs(t.Y[k]) < b.half[k]);
        if (!over) continue;
        t.pair = k;
        t.vertex = static_cast<int>(v);
        t.axis = axis;
        t.side = side;
        t.pb = pb;
        t.Ab = Ab;
        const Eigen::Vector3d ai = Ab.col(axis);
        t.d = side * ai.dot(t.x - pb) - b.half[axis] * ai.squaredNorm();
        const Eigen::Vector3d& X = a.X[v];
        t.c = {1.0, X.x(), X.y(), X.z(), -1.0, -t.Y.x(), -t.Y.y(), -t.Y.z()};
        visit(t);
      }
    }
  }

  // The gap's gradient on the pair's 8 unknowns (zero entries where fixed
  // are skipped by the callers through Pair::index).
  std::array<Eigen::Vector3d, 8> gap_gradient(const Touch& t) const {
    const Pair& pair = pairs_[t.pair];
    const double h = member(pair.b).half[t.axis];
    const Eigen::Vector3d ai = t.Ab.col(t.axis);
    const Eigen::Vector3d n = t.side * ai;
    std::array<Eigen::Vector3d, 8> g;
    for (int u = 0; u < 4; ++u) g[static_cast<std::size_t>(u)] = t.c[static_cast<std::size_t>(u)] * n;
    g[4] = -n;
    for (int k = 0; k < 3; ++k) g[static_cast<std::size_t>(5 + k)].setZero();
    g[static_cast<std::size_t>(5 + t.axis)] = t.side * (t.x - t.pb) - 2.0 * h * ai;
    return g;
  }

  // The 8 x 8 blocks of every pair in the Jacobian pattern, and their slots
  // (pair k's block (u, w) at k * 64 + 8 u + w; invalid where fixed).
  void declare_blocks(JacobianPatternBuilder& builder) const;
  std::vector<BlockSlot> find_slots(const SparseMatrix& pattern) const;

 private:
  std::vector<Member> members_;
  std::vector<Pair> pairs_;
};

}  // namespace springlab
