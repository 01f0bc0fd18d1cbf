// The "body" element kind (bodies.h, docs/physics.md "Rigid bodies (affine
// bodies)"): the scene key "bodies", the derived bodies, and each free
// body's rigidity, the orthogonality energy of Lan et al. 2022 (eq. 6):
//
//   E = kappa V |A^T A - I|_F^2 = kappa V |G|_F^2,   G = A^T A - I,
//   dE/dA = 4 kappa V A G,  so the force on column a_j is
//   F_j = -4 kappa V sum_k a_k G_kj,
//   dF_j/da_k = -4 kappa V (G_kj I + delta_jk A A^T + a_k a_j^T).
//
// Its second variation is d2E[dA, dA] = 4 kappa V (tr(dA G dA^T) +
// 2 |sym(A^T dA)|^2): the second part is never negative, the first is
// where G is not, so the definite part (Newton's matrix) replaces G by its
// positive part G+ (eigenvalues clamped at 0) in the first term; it is the
// exact Hessian wherever A has no singular value below 1.
//
// Why this energy and not ARAP's kappa V |A - R(A)|^2: it is a polynomial
// of A (no polar decomposition, whose derivative is singular where A has
// repeated or vanishing singular values), its gradient and Hessian are the
// three lines above, and it is invariant under A -> Q A for every rotation
// Q, so the angular momentum of the affine body is a first integral (what
// implicit-midpoint conserves exactly). ARAP's one advantage, a projective
// form for projective dynamics, would not help: those fast solvers work on
// particles and know nothing of the body's coordinates.
#include "models/bodies/bodies.h"

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <memory>
#include <random>
#include <sstream>

#include "models/contact/contact.h"
#include "models/core/element_kind.h"

namespace springlab {

// ---- Derived bodies (bodies.h). ----

void body_surface(const Body& body, std::vector<Eigen::Vector3d>& vertices,
                  std::vector<SurfaceTriangle>& triangles) {
  switch (body.shape) {
    case Body::Shape::kMesh:
      vertices = body.vertices;
      triangles = body.triangles;
      return;
    case Body::Shape::kBox:
      box_surface(body.size, vertices, triangles);
      return;
    case Body::Shape::kCylinder:
      cylinder_surface(body.radius, body.height, body.segments, vertices, triangles);
      return;
  }
}

std::size_t body_surface_vertices(const Body& body) {
  switch (body.shape) {
    case Body::Shape::kMesh:
      return body.vertices.size();
    case Body::Shape::kBox:
      return 8;
    case Body::Shape::kCylinder:
      return 2 * static_cast<std::size_t>(std::max(body.segments, 0)) + 2;  // cylinder_surface
  }
  return 0;
}

Eigen::Matrix3d body_rotation(const Body& body) {
  const std::vector<double>& o = body.orientation;
  if (o.size() == 4) {
    return Eigen::Quaterniond(o[0], o[1], o[2], o[3]).normalized().toRotationMatrix();
  }
  if (o.size() == 3) {
    const Eigen::Vector3d w(o[0], o[1], o[2]);
    const double angle = w.norm();
    if (angle == 0.0) return Eigen::Matrix3d::Identity();
    return Eigen::AngleAxisd(angle, w / angle).toRotationMatrix();
  }
  return Eigen::Matrix3d::Identity();
}

namespace {
Eigen::Matrix3d cross_matrix(const Eigen::Vector3d& w) {
  Eigen::Matrix3d m;
  m << 0.0, -w.z(), w.y(), w.z(), 0.0, -w.x(), -w.y(), w.x(), 0.0;
  return m;
}
}  // namespace

RigidBody rigid_body(const Body& body) {
  RigidBody b;
  std::vector<Eigen::Vector3d> vertices;
  body_surface(body, vertices, b.triangles);
  b.mass = mass_properties(vertices, b.triangles, body.density);
  const Eigen::Matrix3d& R = b.mass.frame;
  b.X.reserve(vertices.size());
  for (const Eigen::Vector3d& x : vertices) b.X.push_back(R.transpose() * (x - b.mass.centre));
  // x = p + A X with X = R^T (x_mesh - c): turning the mesh by Q about its
  // centre gives A = Q R.
  b.A0 = body.affine ? *body.affine : Eigen::Matrix3d(body_rotation(body) * R);
  b.p0 = body.position ? *body.position : b.mass.centre;
  b.v0 = body.v;
  b.Adot0 = cross_matrix(body.omega) * b.A0;  // d(x - p)/dt = omega x (x - p)
  b.rigidity = body.rigidity;
  b.fixed = body.fixed;
  return b;
}

int body_pseudo_particles(const Scene& scene) {
  int n = 0;
  for (const Body& b : scene.get<Bodies>()) n += b.fixed ? 0 : 4;
  return n;
}

BodyLayout body_layout(const Scene& scene, int first_unknown) {
  BodyLayout layout;
  for (const Body& body : scene.get<Bodies>()) {
    layout.bodies.push_back(rigid_body(body));
    layout.first.push_back(body.fixed ? -1 : first_unknown + layout.pseudo_particles);
    if (!body.fixed) layout.pseudo_particles += 4;
  }
  return layout;
}

BodyLayout body_layout(const Scene& scene, const ParticleOrder& order) {
  return body_layout(scene, order.first_own(kBodyKind));
}

void body_initial_state(const RigidBody& body, double* x, double* v, double* mass) {
  for (int r = 0; r < 3; ++r) {
    x[r] = body.p0[r];
    v[r] = body.v0[r];
    mass[r] = body.mass.mass;
    for (int i = 0; i < 3; ++i) {
      x[3 * (i + 1) + r] = body.A0(r, i);
      v[3 * (i + 1) + r] = body.Adot0(r, i);
      mass[3 * (i + 1) + r] = body.mass.J[i];
    }
  }
}

BodyState body_state(const RigidBody& body, int first, const double* x, const double* v) {
  BodyState s;
  if (first < 0) {
    s.p = body.p0;
    s.A = body.A0;
    s.dp.setZero();
    s.dA.setZero();
  } else {
    const double* q = x + 3 * first;
    const double* w = v + 3 * first;
    s.p = Eigen::Vector3d(q[0], q[1], q[2]);
    s.dp = Eigen::Vector3d(w[0], w[1], w[2]);
    for (int i = 0; i < 3; ++i) {
      s.A.col(i) = Eigen::Vector3d(q[3 * (i + 1)], q[3 * (i + 1) + 1], q[3 * (i + 1) + 2]);
      s.dA.col(i) = Eigen::Vector3d(w[3 * (i + 1)], w[3 * (i + 1) + 1], w[3 * (i + 1) + 2]);
    }
  }
  const double m = body.mass.mass;
  s.linear_momentum = m * s.dp;
  s.angular_momentum_about_centre.setZero();
  for (int i = 0; i < 3; ++i) {
    s.angular_momentum_about_centre += body.mass.J[i] * s.A.col(i).cross(s.dA.col(i));
  }
  s.angular_momentum = s.angular_momentum_about_centre + s.p.cross(s.linear_momentum);
  return s;
}

namespace {

// ---- The rigidity force. ----

class RigidityForce final : public ForceTerm {
 public:
  explicit RigidityForce(const BodyLayout& layout) {
    for (std::size_t b = 0; b < layout.bodies.size(); ++b) {
      if (layout.first[b] < 0) continue;
      bodies_.push_back({layout.first[b],
                         4.0 * layout.bodies[b].rigidity * layout.bodies[b].mass.volume,
                         layout.bodies[b].rigidity * layout.bodies[b].mass.volume});
    }
  }

  std::string_view name() const override { return "rigidity"; }
  bool conservative() const override { return true; }

  bool projective_elements(std::vector<ProjectiveElement>&, Refusal& why) const override {
    why.text = "rigid bodies have no projective form (the affine body's rigidity kappa V |A^T A - I|^2 "
          "is not a projective energy of particles); use implicit-euler or another Newton method";
    return false;
  }

  double potential_energy(const Configuration& c) const override {
    double sum = 0.0;
    for (const Entry& e : bodies_) sum += e.kappa_v * strain(c, e).squaredNorm();
    return sum;
  }

  void add_force(const Configuration& c, double* f) const override {
    for (const Entry& e : bodies_) {
      const Eigen::Matrix3d A = affine(c, e);
      const Eigen::Matrix3d AG = A * (A.transpose() * A - Eigen::Matrix3d::Identity());
      for (int j = 0; j < 3; ++j) {
        for (int r = 0; r < 3; ++r) f[(e.first + 1 + j) * 3 + r] -= e.four_kappa_v * AG(r, j);
      }
    }
  }

  // The rigidity's own discrete gradient (ForceTerm::has_discrete_gradient),
  // built from the invariant C = A^T A as Gonzalez builds them (J.
  // Nonlinear Sci. 6, 1996, sec. 4; Gonzalez and Simo, CMAME 134, 1996).
  // E = kappa V |C - I|^2 is quadratic in C, with S(C) = dE/dC =
  // 2 kappa V (C - I); for a quadratic the midpoint slope is exact:
  //   E(C_y) - E(C_x) = S(C_avg) : (C_y - C_x),   C_avg = (C_x + C_y) / 2,
  // and C_y - C_x = A_m^T D + D^T A_m (A_m = (A_x + A_y) / 2, D = A_y - A_x),
  // so with S symmetric
  //   g = 2 A_m S(C_avg) = 4 kappa V A_m G_avg,   G_avg = (C_x + C_y) / 2 - I,
  // has g : D = E(A_y) - E(A_x) exactly and is dE/dA (4 kappa V A G) at
  // y = x. Its force on column j, -4 kappa V sum_k a_m,k (G_avg)_kj, is A_m
  // times a symmetric matrix: the torque sum_j a_m,j x F_j =
  // -4 kappa V sum_jk (G_avg)_kj a_m,j x a_m,k vanishes, so the discrete
  // gradient keeps the affine body's angular momentum exactly (Gonzalez's
  // generic correction along D does not: discrete_gradient.h).
  bool has_discrete_gradient() const override { return true; }
  void add_discrete_gradient_force(const Configuration& x, const Configuration& y,
                                   double* f) const override {
    for (const Entry& e : bodies_) {
      const Eigen::Matrix3d Ax = affine(x, e), Ay = affine(y, e);
      const Eigen::Matrix3d G_avg = 0.5 * (Ax.transpose() * Ax + Ay.transpose() * Ay) -
                                    Eigen::Matrix3d::Identity();
      const Eigen::Matrix3d g = (0.5 * (Ax + Ay)) * G_avg;
      for (int j = 0; j < 3; ++j) {
        for (int r = 0; r < 3; ++r) f[(e.first + 1 + j) * 3 + r] -= e.four_kappa_v * g(r, j);
      }
    }
  }

  // Its Jacobian for the discrete-gradient step's Newton matrix
  // (ForceTerm::add_discrete_gradient_jacobian). With A_y moved by dA,
  // A_x held,
  //   dg = 2 kappa V [dA G_avg + A_m (dA^T A_y + A_y^T dA)],
  // where the midpoint Hessian, the matrix of the generic discrete
  // gradient, gives H(A_m) dA / 2 = 2 kappa V [dA G_m + A_m (dA^T A_m +
  // A_m^T dA)], G_m = A_m^T A_m - I. With A_x = A_m - D/2, A_y = A_m + D/2,
  // G_avg = G_m + D^T D / 4, and the two differ by
  //   2 kappa V [dA D^T D / 4 + A_m (dA^T D + D^T dA) / 2],
  // O(|D|), which the midpoint Hessian misses: along a body's turn in the
  // step (A_y ~ R A_x) G_m ~ -D^T D / 4 while G_avg ~ 0. As the force on
  // column j against column k, -2 dg/dy is the block
  //   dF_j/da_k = -4 kappa V (G_avg,kj I + delta_jk A_m A_y^T + a_m,k a_y,j^T)
  // (add_stiffness's at y = x). Its 9 x 9 matrix is not symmetric: the
  // skew part, from A_y - A_m = D/2, is O(|D|) like the difference, and
  // as large: along a turn of the end, A_y -> (I + W) A_y (W skew), the
  // exact dg vanishes (g = 0 between two rotations, G_avg = 0), the
  // symmetric part's does not. Newton's matrix takes it whole (sparse LU:
  // velocity_step.cc); its symmetric part alone cost 49 Newton iterations
  // per step on box-chain at 10 ms, the midpoint Hessian 40.5, the exact
  // block 4.18. With `definite` (Newton's definite matrix, symmetric
  // positive definite) the symmetric part's positive part (negative
  // eigenvalues set to 0).
  void add_discrete_gradient_jacobian(const Configuration& x, const Configuration& y,
                                      bool definite, double* dfdm) const override {
    using Matrix9d = Eigen::Matrix<double, 9, 9>;
    for (std::size_t b = 0; b < bodies_.size(); ++b) {
      const Entry& e = bodies_[b];
      const Eigen::Matrix3d Ax = affine(x, e), Ay = affine(y, e), Am = 0.5 * (Ax + Ay);
      const Eigen::Matrix3d G_avg = 0.5 * (Ax.transpose() * Ax + Ay.transpose() * Ay) -
                                    Eigen::Matrix3d::Identity();
      const Eigen::Matrix3d AmAyt = Am * Ay.transpose();
      Matrix9d S;  // 2 dg/dy / (4 kappa V): rows 3 j + r, columns 3 k + q
      for (int j = 0; j < 3; ++j) {
        for (int k = 0; k < 3; ++k) {
          S.block<3, 3>(3 * j, 3 * k) = G_avg(k, j) * Eigen::Matrix3d::Identity() +
                                        Am.col(k) * Ay.col(j).transpose();
          if (j == k) S.block<3, 3>(3 * j, 3 * k) += AmAyt;
        }
      }
      if (definite) {
        // The symmetric part, projected as add_stiffness projects G: only
        // beyond round-off (S is dimensionless).
        S = 0.5 * (S + S.transpose()).eval();
        const Eigen::SelfAdjointEigenSolver<Matrix9d> eigen(S);
        if (eigen.eigenvalues()[0] < -1e-12) {
          S = eigen.eigenvectors() * eigen.eigenvalues().cwiseMax(0.0).asDiagonal() *
              eigen.eigenvectors().transpose();
        }
      }
      for (int j = 0; j < 3; ++j) {
        for (int k = 0; k < 3; ++k) {
          double K[3][3];
          for (int r = 0; r < 3; ++r) {
            for (int q = 0; q < 3; ++q) K[r][q] = S(3 * j + r, 3 * k + q);
          }
          add_block<3>(dfdm, slots_[b * 9 + static_cast<std::size_t>(j * 3 + k)], K,
                       -e.four_kappa_v);
        }
      }
    }
  }

  void declare_jacobian_blocks(JacobianPatternBuilder& builder) const override {
    for (const Entry& e : bodies_) {
      for (int j = 0; j < 3; ++j) {
        for (int k = 0; k < 3; ++k) {
          if (j != k) builder.add_block(e.first + 1 + j, e.first + 1 + k);
        }
      }
    }
  }

  void bind_jacobian(const SparseMatrix& pattern) override {
    slots_.clear();
    for (const Entry& e : bodies_) {
      for (int j = 0; j < 3; ++j) {
        for (int k = 0; k < 3; ++k) {
          slots_.push_back(find_block_slot(pattern, 3, e.first + 1 + j, e.first + 1 + k));
        }
      }
    }
  }

  void add_jacobians(const Configuration& c, double* dfdx, double*) const override {
    if (dfdx != nullptr) add_stiffness(c, dfdx, false);
  }
  void add_definite_stiffness(const Configuration& c, double* dfdx) const override {
    add_stiffness(c, dfdx, true);
  }

 private:
  struct Entry {
    int first;
    double four_kappa_v, kappa_v;
  };

  static Eigen::Matrix3d affine(const Configuration& c, const Entry& e) {
    Eigen::Matrix3d A;
    for (int i = 0; i < 3; ++i) {
      for (int r = 0; r < 3; ++r) A(r, i) = c.x[(e.first + 1 + i) * 3 + r];
    }
    return A;
  }
  static Eigen::Matrix3d strain(const Configuration& c, const Entry& e) {
    const Eigen::Matrix3d A = affine(c, e);
    return A.transpose() * A - Eigen::Matrix3d::Identity();
  }

  // dF_j/da_k = -4 kappa V (G_kj I + delta_jk A A^T + a_k a_j^T), G -> G+
  // when definite.
  void add_stiffness(const Configuration& c, double* dfdx, bool definite) const {
    for (std::size_t b = 0; b < bodies_.size(); ++b) {
      const Entry& e = bodies_[b];
      const Eigen::Matrix3d A = affine(c, e);
      Eigen::Matrix3d G = A.transpose() * A - Eigen::Matrix3d::Identity();
      if (definite) {
        // G's positive part where G has a negative eigenvalue beyond
        // round-off (G is dimensionless; a rotation's G is ~1e-16): else G
        // itself, so the definite part is bitwise the exact one there.
        const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(G);
        if (eigen.eigenvalues()[0] < -1e-12) {
          G = eigen.eigenvectors() * eigen.eigenvalues().cwiseMax(0.0).asDiagonal() *
              eigen.eigenvectors().transpose();
        }
      }
      const Eigen::Matrix3d AAt = A * A.transpose();
      for (int j = 0; j < 3; ++j) {
        for (int k = 0; k < 3; ++k) {
          double K[3][3];
          for (int r = 0; r < 3; ++r) {
            for (int q = 0; q < 3; ++q) {
              K[r][q] = (r == q ? G(k, j) : 0.0) + (j == k ? AAt(r, q) : 0.0) + A(r, k) * A(q, j);
            }
          }
          add_block<3>(dfdx, slots_[b * 9 + static_cast<std::size_t>(j * 3 + k)], K,
                       -e.four_kappa_v);
        }
      }
    }
  }

  std::vector<Entry> bodies_;
  std::vector<BlockSlot> slots_;
};

std::unique_ptr<ForceTerm> make_rigidity_force(const Scene& scene, const ParticleOrder& order) {
  if (body_pseudo_particles(scene) == 0) return nullptr;
  return std::make_unique<RigidityForce>(body_layout(scene, order));
}

// ---- Reading, checking, writing. ----

const char* shape_name(Body::Shape s) {
  switch (s) {
    case Body::Shape::kBox:
      return "box";
    case Body::Shape::kCylinder:
      return "cylinder";
    case Body::Shape::kMesh:
      break;
  }
  return "mesh";
}

// Every check of one body, for files and built scenes alike.
void check_body(const Reporter& r, const std::string& where, const Body& b) {
  if (b.shape == Body::Shape::kMesh) {
    for (std::size_t k = 0; k < b.vertices.size(); ++k) {
      check_vector(r, field(where, element("vertices", k)), b.vertices[k], 3);
    }
  } else if (b.shape == Body::Shape::kBox) {
    for (int i = 0; i < 3; ++i) check_positive(r, field(where, "size[" + std::to_string(i) + "]"), b.size[i]);
  } else {
    check_positive(r, field(where, "radius"), b.radius);
    check_positive(r, field(where, "height"), b.height);
    if (b.segments < 3 || b.segments > 100000) {
      r.fail(field(where, "segments"),
             "must be a whole number from 3 to 100000 (got " + std::to_string(b.segments) + ")");
    }
  }
  check_positive(r, field(where, "density"), b.density);
  check_positive(r, field(where, "rigidity"), b.rigidity);
  check_nonnegative(r, field(where, "friction"), b.friction);
  check_nonnegative(r, field(where, "contact_damping"), b.contact_damping);
  if (b.position) check_vector(r, field(where, "position"), *b.position, 3);
  check_vector(r, field(where, "v"), b.v, 3);
  check_vector(r, field(where, "omega"), b.omega, 3);
  if (!b.orientation.empty()) {
    if (b.orientation.size() != 3 && b.orientation.size() != 4) {
      r.fail(field(where, "orientation"),
             "expected a quaternion [w, x, y, z] or a rotation vector [x, y, z] (got " +
                 std::to_string(b.orientation.size()) + " numbers)");
    }
    double norm2 = 0.0;
    for (double q : b.orientation) {
      check_finite(r, field(where, "orientation"), q);
      norm2 += q * q;
    }
    if (b.orientation.size() == 4 && !(norm2 > 0.0)) {
      r.fail(field(where, "orientation"), "a quaternion must be nonzero");
    }
  }
  if (b.affine) {
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) check_finite(r, field(where, "affine"), (*b.affine)(i, j));
    }
    // A = Q (I + S) with det A > 0: a zero A flattens the body to a point
    // and a mirror (det A < 0) turns it inside out; neither is a strained
    // body, and the rigidity's energy cannot bring them back.
    const double det = b.affine->determinant();
    if (!(det > 0.0)) {
      r.fail(field(where, "affine"),
             "must keep the body's orientation and volume (det A > 0; got det A = " +
                 shortest_text(det) + (det < 0.0 ? ": a mirror image)" : ": the body flattened)"));
    }
  }
  std::vector<Eigen::Vector3d> vertices;
  std::vector<SurfaceTriangle> triangles;
  body_surface(b, vertices, triangles);
  const std::string problem = surface_problem(vertices, triangles);
  if (!problem.empty()) r.fail(where, problem);
}

int read_index(const Reporter& r, const std::string& where, const Json& j) {
  const double value = read_number(r, where, j);
  if (value != std::floor(value) || std::abs(value) > 2e9) {
    r.fail(where, "expected a whole vertex index (got " + shortest_text(value) + ")");
  }
  return static_cast<int>(value);
}

Body read_body(const Reporter& r, const std::string& where, const Json& j) {
  require_object(r, where, j);
  check_keys(r, where, j,
             {"vertices", "triangles", "shape", "size", "radius", "height", "segments", "density",
              "position", "orientation", "affine", "v", "omega", "fixed", "rigidity", "friction",
              "contact_damping"},
             {});
  Body b;
  const bool mesh = j.contains("vertices") || j.contains("triangles");
  if (mesh && j.contains("shape")) {
    r.fail(where, "give either a mesh (vertices and triangles) or a shape, not both");
  }
  if (mesh) {
    if (!j.contains("vertices") || !j.contains("triangles")) {
      r.fail(where, "a mesh needs both vertices and triangles");
    }
    b.shape = Body::Shape::kMesh;
    const Json& vs = j.at("vertices");
    require_array(r, field(where, "vertices"), vs);
    if (vs.size() > kMaxBodyVertices) {
      r.fail(field(where, "vertices"), std::to_string(vs.size()) + " vertices, over the cap of " +
                                           std::to_string(kMaxBodyVertices) + " per body");
    }
    for (std::size_t k = 0; k < vs.size(); ++k) {
      b.vertices.push_back(read_vector(r, field(where, element("vertices", k)), vs[k], 3));
    }
    const Json& ts = j.at("triangles");
    require_array(r, field(where, "triangles"), ts);
    if (ts.size() > 2 * kMaxBodyVertices) {
      r.fail(field(where, "triangles"), "too many triangles (" + std::to_string(ts.size()) + ")");
    }
    for (std::size_t k = 0; k < ts.size(); ++k) {
      const std::string at = field(where, element("triangles", k));
      require_array(r, at, ts[k]);
      if (ts[k].size() != 3) {
        r.fail(at, "expected 3 vertex indices (got " + std::to_string(ts[k].size()) + ")");
      }
      SurfaceTriangle t;
      for (std::size_t c = 0; c < 3; ++c) t[c] = read_index(r, element(at, c), ts[k][c]);
      b.triangles.push_back(t);
    }
  } else if (j.contains("shape")) {
    const Json& s = j.at("shape");
    const std::string name = s.is_string() ? s.get<std::string>() : s.dump();
    if (name == "box") {
      b.shape = Body::Shape::kBox;
    } else if (name == "cylinder") {
      b.shape = Body::Shape::kCylinder;
    } else {
      r.fail(field(where, "shape"), "unknown shape " + (s.is_string() ? json_string(name) : name) +
                                        " (shapes: box, cylinder)");
    }
  } else {
    r.fail(where, "a body needs a mesh (vertices and triangles) or a shape (box, cylinder)");
  }
  auto only_for = [&](const char* key, Body::Shape shape) {
    if (j.contains(key) && b.shape != shape) {
      r.fail(field(where, key), std::string("belongs to a ") + shape_name(shape) + ", not a " +
                                    shape_name(b.shape));
    }
  };
  only_for("size", Body::Shape::kBox);
  only_for("radius", Body::Shape::kCylinder);
  only_for("height", Body::Shape::kCylinder);
  only_for("segments", Body::Shape::kCylinder);
  if (j.contains("size")) b.size = read_vector(r, field(where, "size"), j.at("size"), 3);
  if (j.contains("radius")) b.radius = read_number(r, field(where, "radius"), j.at("radius"));
  if (j.contains("height")) b.height = read_number(r, field(where, "height"), j.at("height"));
  if (j.contains("segments")) {
    const double s = read_number(r, field(where, "segments"), j.at("segments"));
    if (s != std::floor(s) || s < 3 || s > 100000) {
      r.fail(field(where, "segments"),
             "must be a whole number from 3 to 100000 (got " + shortest_text(s) + ")");
    }
    b.segments = static_cast<int>(s);
  }
  if (j.contains("density")) b.density = read_number(r, field(where, "density"), j.at("density"));
  if (j.contains("rigidity")) {
    b.rigidity = read_number(r, field(where, "rigidity"), j.at("rigidity"));
  }
  if (j.contains("position")) {
    b.position = read_vector(r, field(where, "position"), j.at("position"), 3);
  }
  if (j.contains("orientation") && j.contains("affine")) {
    r.fail(where, "give orientation or affine, not both");
  }
  if (j.contains("orientation")) {
    const Json& o = j.at("orientation");
    require_array(r, field(where, "orientation"), o);
    for (std::size_t k = 0; k < o.size() && k < 5; ++k) {
      b.orientation.push_back(read_number(r, element(field(where, "orientation"), k), o[k]));
    }
    if (o.size() > 4) b.orientation.push_back(0.0);  // reported by check_body
  }
  if (j.contains("affine")) {
    const Json& a = j.at("affine");
    require_array(r, field(where, "affine"), a);
    if (a.size() != 3) r.fail(field(where, "affine"), "expected 3 rows of 3 numbers");
    Eigen::Matrix3d A;
    for (std::size_t i = 0; i < 3; ++i) {
      A.row(static_cast<Eigen::Index>(i)) =
          read_vector(r, element(field(where, "affine"), i), a[i], 3).transpose();
    }
    b.affine = A;
  }
  if (j.contains("v")) b.v = read_vector(r, field(where, "v"), j.at("v"), 3);
  if (j.contains("omega")) b.omega = read_vector(r, field(where, "omega"), j.at("omega"), 3);
  if (j.contains("fixed")) b.fixed = read_bool(r, field(where, "fixed"), j.at("fixed"));
  if (j.contains("friction")) {
    b.friction = read_number(r, field(where, "friction"), j.at("friction"));
  }
  if (j.contains("contact_damping")) {
    b.contact_damping = read_number(r, field(where, "contact_damping"), j.at("contact_damping"));
  }
  check_body(r, where, b);
  return b;
}

void check_dimension_and_unknowns(const Scene& scene, const Reporter& r) {
  if (scene.dimension != 3) r.fail("bodies", "rigid bodies need a 3-D scene (dimension 3)");
  const bool free_particle = std::any_of(scene.particles.begin(), scene.particles.end(),
                                         [](const Particle& p) { return !p.fixed; });
  if (!free_particle && body_pseudo_particles(scene) == 0) {
    r.fail("bodies", "scene has no free particle and no free body");
  }
}

// The scene's surface vertices so far (`total`, before body k) and body k's:
// over kMaxSceneBodyVertices, the body that crosses it is named, with what
// makes its vertices (a cylinder's segments).
void count_surface_vertices(const Reporter& r, std::size_t k, const Body& b, std::size_t& total) {
  const std::size_t own = body_surface_vertices(b);
  total += own;
  if (total <= kMaxSceneBodyVertices) return;
  std::string what = std::to_string(own) + " surface vertices";
  if (b.shape == Body::Shape::kCylinder) {
    what = "a cylinder of " + std::to_string(b.segments) + " segments (" + what + ")";
  }
  r.fail(element("bodies", k), what + " brings the scene's bodies to " + std::to_string(total) +
                                   " surface vertices, over the cap of " +
                                   std::to_string(kMaxSceneBodyVertices) + " per scene");
}

void read_bodies(const Json& document, const Reporter& r, Scene& scene) {
  if (!document.contains("bodies")) return;
  const Json& list = document.at("bodies");
  require_array(r, "bodies", list);
  if (list.empty()) return;
  if (scene.dimension != 3) r.fail("bodies", "rigid bodies need a 3-D scene (dimension 3)");
  Bodies& out = scene.block<Bodies>();
  std::size_t vertices = 0;
  for (std::size_t k = 0; k < list.size(); ++k) {
    out.push_back(read_body(r, element("bodies", k), list[k]));
    count_surface_vertices(r, k, out.back(), vertices);
  }
  check_dimension_and_unknowns(scene, r);
}

void validate_bodies(const Scene& scene, const Reporter& r) {
  const Bodies& bodies = scene.get<Bodies>();
  if (bodies.empty()) return;
  check_dimension_and_unknowns(scene, r);
  std::size_t vertices = 0;
  for (std::size_t k = 0; k < bodies.size(); ++k) {
    count_surface_vertices(r, k, bodies[k], vertices);
    check_body(r, element("bodies", k), bodies[k]);
  }
}

std::string json_numbers(const std::vector<double>& values) {
  std::string out = "[";
  for (std::size_t k = 0; k < values.size(); ++k) out += (k ? ", " : "") + json_number(values[k]);
  return out + "]";
}

void write_bodies(const Scene& scene, std::vector<std::pair<std::string, std::string>>& entries) {
  const Bodies* bodies = scene.find<Bodies>();
  if (bodies == nullptr || bodies->empty()) return;
  JsonLines lines;
  for (const Body& b : *bodies) {
    std::string text = "{";
    if (b.shape == Body::Shape::kMesh) {
      text += "\"vertices\": [";
      for (std::size_t k = 0; k < b.vertices.size(); ++k) {
        text += (k ? ", " : "") + json_vector(b.vertices[k], 3);
      }
      text += "], \"triangles\": [";
      for (std::size_t k = 0; k < b.triangles.size(); ++k) {
        const SurfaceTriangle& t = b.triangles[k];
        text += (k ? ", [" : "[") + std::to_string(t[0]) + ", " + std::to_string(t[1]) + ", " +
                std::to_string(t[2]) + "]";
      }
      text += "]";
    } else if (b.shape == Body::Shape::kBox) {
      text += "\"shape\": \"box\", \"size\": " + json_vector(b.size, 3);
    } else {
      text += "\"shape\": \"cylinder\", \"radius\": " + json_number(b.radius) +
              ", \"height\": " + json_number(b.height) +
              ", \"segments\": " + std::to_string(b.segments);
    }
    text += ", \"density\": " + json_number(b.density);
    if (b.position) text += ", \"position\": " + json_vector(*b.position, 3);
    if (!b.orientation.empty()) text += ", \"orientation\": " + json_numbers(b.orientation);
    if (b.affine) {
      text += ", \"affine\": [";
      for (int i = 0; i < 3; ++i) {
        text += (i ? ", " : "") + json_vector(b.affine->row(i).transpose(), 3);
      }
      text += "]";
    }
    if (!b.v.isZero()) text += ", \"v\": " + json_vector(b.v, 3);
    if (!b.omega.isZero()) text += ", \"omega\": " + json_vector(b.omega, 3);
    if (b.fixed) text += ", \"fixed\": true";
    text += ", \"rigidity\": " + json_number(b.rigidity);
    if (b.friction != 0.0) text += ", \"friction\": " + json_number(b.friction);
    if (b.contact_damping != 0.0) {
      text += ", \"contact_damping\": " + json_number(b.contact_damping);
    }
    text += "}";
    lines.add(text);
  }
  entries.emplace_back("bodies", lines.str());
}

std::size_t count_bodies(const Scene& scene) { return scene.get<Bodies>().size(); }

// The kind's part of the model's memory (memory_estimate.h): a body's two
// copies of its Body, and each term that derives it (the rigidity, gravity,
// contact with the planes and between bodies, their friction) its own
// RigidBody: 2 KB a body, 120 bytes a surface vertex with its triangles
// (measured: 34 bytes a vertex with four 200,000-vertex cylinders and
// nothing else); once the pattern is built, the rigidity's 4 x 4 blocks.
void body_memory(const Scene& scene, MemoryEstimate& out) {
  const Bodies& bodies = scene.get<Bodies>();
  if (bodies.empty()) return;
  std::size_t vertices = 0;
  for (const Body& b : bodies) vertices += body_surface_vertices(b);
  MemoryPart part;
  part.what = std::to_string(bodies.size()) + " bodies (" + std::to_string(vertices) +
              " surface vertices)";
  part.bytes = 2048.0 * static_cast<double>(bodies.size()) + 120.0 * static_cast<double>(vertices);
  part.pattern_blocks = part.distinct_blocks = 16.0 * static_cast<double>(bodies.size());
  out.parts.push_back(std::move(part));
}

}  // namespace

// A box, strained unless `strained` is false (kAny: A = Q (I + S), S symmetric, some singular values
// below 1; kDefinite: all at or above 1, where the Hessian is semidefinite)
// near the random particles, moving and spinning; placed against the
// scene's first plane when it has one so that some vertices touch it
// (penalty: past it; barrier: within its distance, every gap positive).
void add_random_body_with(Scene& scene, std::mt19937& rng, RandomStates states, bool strained) {
  if (scene.dimension != 3) return;
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Body b;
  b.shape = Body::Shape::kBox;
  b.size = Eigen::Vector3d(1.0 + 0.4 * u(rng), 0.8 + 0.3 * u(rng), 0.6 + 0.2 * u(rng));
  b.density = 1.5 + 0.5 * u(rng);
  b.rigidity = 20.0 + 10.0 * u(rng);
  const Eigen::Quaterniond q =
      Eigen::Quaterniond(u(rng), u(rng), u(rng), 1.0 + std::abs(u(rng))).normalized();
  Eigen::Matrix3d S;
  for (int i = 0; i < 3; ++i) {
    for (int j = i; j < 3; ++j) S(i, j) = S(j, i) = 0.1 * u(rng);
  }
  if (states == RandomStates::kDefinite) {
    S = S * S.transpose() + 0.02 * Eigen::Matrix3d::Identity();  // positive definite: stretched
  }
  if (strained) {
    b.affine = q.toRotationMatrix() * (Eigen::Matrix3d::Identity() + S);
  } else {
    b.orientation = {q.w(), q.x(), q.y(), q.z()};
  }
  b.position = Eigen::Vector3d(2.0 + 0.5 * u(rng), 1.0 + 0.5 * u(rng), 0.5 * u(rng));
  b.v = Eigen::Vector3d(u(rng), u(rng), u(rng));
  b.omega = Eigen::Vector3d(2.0 * u(rng), 2.0 * u(rng), 2.0 * u(rng));
  if (!scene.get<Planes>().empty()) {
    const Plane& plane = scene.get<Planes>().front();
    const Eigen::Vector3d n = plane.normal.normalized();
    RigidBody rb = rigid_body(b);
    double lowest = INFINITY, highest = -INFINITY;
    for (const Eigen::Vector3d& X : rb.X) {
      const double d = n.dot(rb.p0 + rb.A0 * X - plane.point);
      lowest = std::min(lowest, d);
      highest = std::max(highest, d);
    }
    const Contact& c = scene.get<Contact>();
    const double target = c.model == ContactModel::kPenalty ? -0.3 * (highest - lowest)
                                                            : 0.3 * c.distance_or_default();
    *b.position += (target - lowest) * n;
  }
  scene.block<Bodies>().push_back(b);
}

void add_random_body(Scene& scene, std::mt19937& rng, RandomStates states) {
  add_random_body_with(scene, rng, states, true);
}

namespace {

// Its own unknowns (element_kind.h OwnUnknowns): p and A of each free body,
// 4 pseudo-particles of 3, from x0 on.
void bodies_initial_state(const Scene& scene, double* x0, double* v0, double* mass) {
  const BodyLayout layout = body_layout(scene, 0);
  for (std::size_t b = 0; b < layout.bodies.size(); ++b) {
    if (layout.first[b] < 0) continue;
    const std::ptrdiff_t at = static_cast<std::ptrdiff_t>(layout.first[b]) * 3;
    body_initial_state(layout.bodies[b], x0 + at, v0 + at, mass + at);
  }
}

void add_free_bodies_mass(const Scene& scene, double& sum) {
  const BodyLayout layout = body_layout(scene, 0);
  for (std::size_t b = 0; b < layout.bodies.size(); ++b) {
    if (layout.first[b] >= 0) sum += layout.bodies[b].mass.mass;
  }
}

// Every body's vertices x = p0 + A0 X, a fixed body's flagged.
void body_start_points(const Scene& scene, std::vector<StartPoint>& out) {
  for (const Body& body : scene.get<Bodies>()) {
    const RigidBody b = rigid_body(body);
    for (const Eigen::Vector3d& X : b.X) out.push_back({b.p0 + b.A0 * X, b.fixed});
  }
}

}  // namespace

// Its divergence rule: rigidity strain and, unforced, energy (body_verdict.cc).
std::unique_ptr<DivergenceRule> make_body_divergence_rule(const Scene& scene,
                                                          const ParticleOrder& order,
                                                          const VerdictScale& scale);
extern const char kBodyDivergenceSentence[];

const ElementKind& body_kind() {
  static const ElementKind kind = {
      .name = kBodyKind,
      .refers_to_particles = true,
      .keys = {{.name = "bodies", .cap = kMaxSceneBodies, .count = count_bodies}},
      .read = read_bodies,
      .validate = validate_bodies,
      .write = write_bodies,
      .own_unknowns = {.count = body_pseudo_particles,
                       .initial_state = bodies_initial_state,
                       .add_free_mass = add_free_bodies_mass,
                       .start_points = body_start_points,
                       .not_per_particle =
                           "this scene's rigid bodies have no per-particle form (vbd moves one "
                           "particle at a time; a body's 12 unknowns are coupled by its "
                           "rigidity); use implicit-euler"},
      .make = make_rigidity_force,
      .energy = {.name = "rigidity", .counts_with_spring = true},
      .divergence_rule = make_body_divergence_rule,
      .divergence_sentence = kBodyDivergenceSentence,
      .memory = body_memory,
      .add_random = add_random_body,
  };
  return kind;
}

}  // namespace springlab
