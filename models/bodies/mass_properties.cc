// Polyhedral mass properties (mass_properties.h), Eberly 2002.
#include "models/bodies/mass_properties.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>
#include <sstream>
#include <utility>

namespace springlab {
namespace {

// Eberly's subexpressions of one coordinate w0, w1, w2 of a triangle:
// f1 = sum w, f2 = sum of the quadratic monomials, f3 = of the cubic ones,
// g_i = f2 + w_i (f1 + w_i).
struct Sub {
  double f1, f2, f3, g0, g1, g2;
};
Sub subexpressions(double w0, double w1, double w2) {
  Sub s;
  const double t0 = w0 + w1, t1 = w0 * w0, t2 = t1 + w1 * t0;
  s.f1 = t0 + w2;
  s.f2 = t2 + w2 * s.f1;
  s.f3 = w0 * t1 + w1 * t2 + w2 * s.f2;
  s.g0 = s.f2 + w0 * (s.f1 + w0);
  s.g1 = s.f2 + w1 * (s.f1 + w1);
  s.g2 = s.f2 + w2 * (s.f1 + w2);
  return s;
}

}  // namespace

void principal_frame(const Eigen::Matrix3d& C, Eigen::Matrix3d& R, Eigen::Vector3d& J) {
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(C);
  const Eigen::Matrix3d E = eigen.eigenvectors();
  const Eigen::Vector3d values = eigen.eigenvalues();
  // Of the 6 orders of the eigenvectors, the one whose columns are most
  // aligned with the axes (largest sum of |diagonal|), each column signed
  // to a non-negative diagonal entry; then det +1 by flipping the column
  // with the smallest diagonal (a mirror image is not a rotation).
  std::array<int, 3> order{0, 1, 2}, best = order;
  double best_score = -1.0;
  do {
    double score = 0.0;
    for (int i = 0; i < 3; ++i) score += std::abs(E(i, order[static_cast<std::size_t>(i)]));
    if (score > best_score + 1e-12) {
      best_score = score;
      best = order;
    }
  } while (std::next_permutation(order.begin(), order.end()));
  for (int i = 0; i < 3; ++i) {
    const int k = best[static_cast<std::size_t>(i)];
    R.col(i) = E.col(k) * (E(i, k) < 0.0 ? -1.0 : 1.0);
    J[i] = values[k];
  }
  if (R.determinant() < 0.0) {
    int smallest = 0;
    for (int i = 1; i < 3; ++i) {
      if (R(i, i) < R(smallest, smallest)) smallest = i;
    }
    R.col(smallest) = -R.col(smallest);
  }
}

MassProperties mass_properties(const std::vector<Eigen::Vector3d>& vertices,
                               const std::vector<SurfaceTriangle>& triangles, double density) {
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3d& v : vertices) origin += v;
  if (!vertices.empty()) origin /= static_cast<double>(vertices.size());
  // integral of 1, x, y, z, x^2, y^2, z^2, xy, yz, zx (about `origin`)
  double in[10] = {};
  for (const SurfaceTriangle& t : triangles) {
    const Eigen::Vector3d p0 = vertices[static_cast<std::size_t>(t[0])] - origin;
    const Eigen::Vector3d p1 = vertices[static_cast<std::size_t>(t[1])] - origin;
    const Eigen::Vector3d p2 = vertices[static_cast<std::size_t>(t[2])] - origin;
    const Eigen::Vector3d d = (p1 - p0).cross(p2 - p0);  // twice the area times the normal
    const Sub x = subexpressions(p0.x(), p1.x(), p2.x());
    const Sub y = subexpressions(p0.y(), p1.y(), p2.y());
    const Sub z = subexpressions(p0.z(), p1.z(), p2.z());
    in[0] += d.x() * x.f1;
    in[1] += d.x() * x.f2;
    in[2] += d.y() * y.f2;
    in[3] += d.z() * z.f2;
    in[4] += d.x() * x.f3;
    in[5] += d.y() * y.f3;
    in[6] += d.z() * z.f3;
    in[7] += d.x() * (p0.y() * x.g0 + p1.y() * x.g1 + p2.y() * x.g2);
    in[8] += d.y() * (p0.z() * y.g0 + p1.z() * y.g1 + p2.z() * y.g2);
    in[9] += d.z() * (p0.x() * z.g0 + p1.x() * z.g1 + p2.x() * z.g2);
  }
  const double scale[10] = {1.0 / 6,  1.0 / 24, 1.0 / 24, 1.0 / 24,  1.0 / 60,
                            1.0 / 60, 1.0 / 60, 1.0 / 120, 1.0 / 120, 1.0 / 120};
  for (int k = 0; k < 10; ++k) in[k] *= scale[k];

  MassProperties mp;
  mp.volume = in[0];
  mp.mass = density * in[0];
  const Eigen::Vector3d first(in[1], in[2], in[3]);  // integral of (x - origin)
  const Eigen::Vector3d offset = first / in[0];      // c - origin
  mp.centre = origin + offset;
  Eigen::Matrix3d S;  // integral (x - origin)(x - origin)^T
  S << in[4], in[7], in[9], in[7], in[5], in[8], in[9], in[8], in[6];
  // About the centre: S - V o o^T (parallel axes), times rho.
  mp.second_moment = density * (S - in[0] * offset * offset.transpose());
  principal_frame(mp.second_moment, mp.frame, mp.J);
  return mp;
}

std::string surface_problem(const std::vector<Eigen::Vector3d>& vertices,
                            const std::vector<SurfaceTriangle>& triangles) {
  std::ostringstream why;
  const int n = static_cast<int>(vertices.size());
  if (triangles.size() < 4) {
    why << "a closed surface needs at least 4 triangles (got " << triangles.size() << ")";
    return why.str();
  }
  // Each directed edge (a, b) once, and its reverse once: closed, manifold,
  // consistently oriented.
  std::map<std::pair<int, int>, int> directed;
  for (std::size_t k = 0; k < triangles.size(); ++k) {
    const SurfaceTriangle& t = triangles[k];
    for (int c = 0; c < 3; ++c) {
      if (t[static_cast<std::size_t>(c)] < 0 || t[static_cast<std::size_t>(c)] >= n) {
        why << "triangles[" << k << "]: vertex " << t[static_cast<std::size_t>(c)]
            << " does not exist (body has " << n << " vertices)";
        return why.str();
      }
    }
    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) {
      why << "triangles[" << k << "]: a vertex is repeated";
      return why.str();
    }
    const Eigen::Vector3d& a = vertices[static_cast<std::size_t>(t[0])];
    const Eigen::Vector3d& b = vertices[static_cast<std::size_t>(t[1])];
    const Eigen::Vector3d& c = vertices[static_cast<std::size_t>(t[2])];
    const double edge2 = std::max({(b - a).squaredNorm(), (c - b).squaredNorm(),
                                   (a - c).squaredNorm()});
    if (!((b - a).cross(c - a).norm() > 1e-12 * edge2)) {
      why << "triangles[" << k << "]: degenerate (zero area)";
      return why.str();
    }
    for (int e = 0; e < 3; ++e) {
      const std::pair<int, int> edge{t[static_cast<std::size_t>(e)],
                                     t[static_cast<std::size_t>((e + 1) % 3)]};
      if (++directed[edge] > 1) {
        why << "edge (" << edge.first << ", " << edge.second
            << ") is used twice in the same direction (triangles[" << k
            << "]): the surface is not manifold or not consistently oriented";
        return why.str();
      }
    }
  }
  for (const auto& [edge, count] : directed) {
    if (directed.find({edge.second, edge.first}) == directed.end()) {
      why << "the surface is not closed: edge (" << edge.first << ", " << edge.second
          << ") belongs to one triangle only";
      return why.str();
    }
  }
  Eigen::Vector3d lo = vertices[0], hi = vertices[0];
  for (const Eigen::Vector3d& v : vertices) {
    lo = lo.cwiseMin(v);
    hi = hi.cwiseMax(v);
  }
  const double diameter = (hi - lo).norm();
  const double volume = mass_properties(vertices, triangles, 1.0).volume;
  if (!(std::abs(volume) > 1e-12 * diameter * diameter * diameter)) {
    why << "zero volume (" << volume << " m^3): the surface encloses no solid";
    return why.str();
  }
  if (volume < 0.0) {
    why << "negative volume (" << volume
        << " m^3): the triangles are oriented inward; list each triangle's vertices "
           "counter-clockwise seen from outside";
    return why.str();
  }
  return {};
}

void box_surface(const Eigen::Vector3d& size, std::vector<Eigen::Vector3d>& vertices,
                 std::vector<SurfaceTriangle>& triangles) {
  vertices.clear();
  for (int k = 0; k < 8; ++k) {
    vertices.emplace_back((k & 1 ? 0.5 : -0.5) * size.x(), (k & 2 ? 0.5 : -0.5) * size.y(),
                          (k & 4 ? 0.5 : -0.5) * size.z());
  }
  // Two triangles per face, counter-clockwise seen from outside.
  triangles = {{0, 2, 3}, {0, 3, 1}, {4, 5, 7}, {4, 7, 6},   // -z, +z
               {0, 1, 5}, {0, 5, 4}, {2, 6, 7}, {2, 7, 3},   // -y, +y
               {0, 4, 6}, {0, 6, 2}, {1, 3, 7}, {1, 7, 5}};  // -x, +x
}

void cylinder_surface(double radius, double height, int segments,
                      std::vector<Eigen::Vector3d>& vertices, std::vector<SurfaceTriangle>& triangles) {
  vertices.clear();
  triangles.clear();
  const double h = 0.5 * height;
  for (int k = 0; k < segments; ++k) {
    const double phi = 2.0 * std::numbers::pi * k / segments;
    vertices.emplace_back(radius * std::cos(phi), radius * std::sin(phi), -h);
    vertices.emplace_back(radius * std::cos(phi), radius * std::sin(phi), h);
  }
  const int bottom = 2 * segments, top = bottom + 1;
  vertices.emplace_back(0.0, 0.0, -h);
  vertices.emplace_back(0.0, 0.0, h);
  for (int k = 0; k < segments; ++k) {
    const int b0 = 2 * k, t0 = b0 + 1, b1 = 2 * ((k + 1) % segments), t1 = b1 + 1;
    triangles.push_back({b0, b1, t1});
    triangles.push_back({b0, t1, t0});
    triangles.push_back({bottom, b1, b0});
    triangles.push_back({top, t0, t1});
  }
}

}  // namespace springlab
