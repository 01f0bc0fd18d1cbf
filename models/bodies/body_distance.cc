// Distances between pieces of two surfaces, and their derivatives
// (body_distance.h).
#include "models/bodies/body_distance.h"

#include <Eigen/Geometry>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <numbers>

namespace springlab {
namespace {

// The first simplex a single point (weight 1), the second the points
// `which` of a triangle with weights `weight`.
SimplexDistance point_against(std::initializer_list<int> which,
                              std::initializer_list<double> weight) {
  SimplexDistance s;
  s.na = 1;
  s.ia[0] = 0;
  s.alpha[0] = 1.0;
  s.nb = static_cast<int>(which.size());
  std::copy(which.begin(), which.end(), s.ib.begin());
  std::copy(weight.begin(), weight.end(), s.beta.begin());
  return s;
}

}  // namespace

// Ericson (2005), sec. 5.1.5: the Voronoi regions of the triangle's
// vertices, then of its edges, then the face, tested with the dot products
// d1..d6 of the edges ab, ac with x's offsets from a, b, c.
SimplexDistance point_triangle_distance(const Eigen::Vector3d& x, const Eigen::Vector3d& a,
                                        const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  const Eigen::Vector3d ab = b - a, ac = c - a;
  const Eigen::Vector3d ap = x - a, bp = x - b, cp = x - c;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  // (d1 - d3 = |ab|^2, d2 - d6 = |ac|^2, (d4 - d3) + (d5 - d6) = |bc|^2 and
  // va + vb + vc = |ab x ac|^2: no division by zero on a triangle of area.)
  const double vc = d1 * d4 - d3 * d2, vb = d5 * d2 - d1 * d6, va = d3 * d6 - d5 * d4;
  SimplexDistance s;
  if (d1 <= 0.0 && d2 <= 0.0) {
    s = point_against({0}, {1.0});
  } else if (d3 >= 0.0 && d4 <= d3) {
    s = point_against({1}, {1.0});
  } else if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) {
    const double v = d1 / (d1 - d3);
    s = point_against({0, 1}, {1.0 - v, v});
  } else if (d6 >= 0.0 && d5 <= d6) {
    s = point_against({2}, {1.0});
  } else if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) {
    const double w = d2 / (d2 - d6);
    s = point_against({0, 2}, {1.0 - w, w});
  } else if (va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0) {
    const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    s = point_against({1, 2}, {1.0 - w, w});
  } else {
    const double v = vb / (va + vb + vc), w = vc / (va + vb + vc);
    s = point_against({0, 1, 2}, {1.0 - v - w, v, w});
  }
  const Eigen::Vector3d* t[3] = {&a, &b, &c};
  Eigen::Vector3d closest = Eigen::Vector3d::Zero();
  for (int j = 0; j < s.nb; ++j) closest += s.beta[j] * *t[s.ib[j]];
  s.P = x - closest;
  s.distance = s.P.norm();
  return s;
}

// Ericson (2005), sec. 5.1.9: the closest points of the two lines,
// p0 + s d1 and q0 + t d2, then clamped to the segments (s first, t from it,
// s again where t had to be clamped). Nearly parallel segments (the lines'
// normal equations singular to round-off) take s = 0: their distance is
// then that of an end, to the last bits.
SimplexDistance segment_segment_distance(const Eigen::Vector3d& p0, const Eigen::Vector3d& p1,
                                         const Eigen::Vector3d& q0, const Eigen::Vector3d& q1) {
  const Eigen::Vector3d d1 = p1 - p0, d2 = q1 - q0, r = p0 - q0;
  const double a = d1.squaredNorm(), e = d2.squaredNorm();
  const double b = d1.dot(d2), c = d1.dot(r), f = d2.dot(r);
  const double denominator = a * e - b * b;
  auto clamp = [](double u) { return std::clamp(u, 0.0, 1.0); };
  double s = denominator > 1e-14 * a * e ? clamp((b * f - c * e) / denominator) : 0.0;
  double t = (b * s + f) / e;
  if (t <= 0.0) {
    t = 0.0;
    s = clamp(-c / a);
  } else if (t >= 1.0) {
    t = 1.0;
    s = clamp((b - c) / a);
  }
  SimplexDistance out;
  auto side = [](double u, int& n, std::array<int, 3>& index, std::array<double, 3>& weight) {
    if (u == 0.0) {
      n = 1;
      index[0] = 0;
      weight[0] = 1.0;
    } else if (u == 1.0) {
      n = 1;
      index[0] = 1;
      weight[0] = 1.0;
    } else {
      n = 2;
      index[0] = 0;
      index[1] = 1;
      weight[0] = 1.0 - u;
      weight[1] = u;
    }
  };
  side(s, out.na, out.ia, out.alpha);
  side(t, out.nb, out.ib, out.beta);
  out.P = (p0 + s * d1) - (q0 + t * d2);
  out.distance = out.P.norm();
  return out;
}

DistanceDerivatives distance_derivatives(const SimplexDistance& s, const Eigen::Vector3d* y) {
  DistanceDerivatives out;
  out.m = s.na + s.nb;
  out.k = (s.na - 1) + (s.nb - 1);
  const int m = out.m, K = out.k;
  for (int v = 0; v < s.na; ++v) out.c[v] = s.alpha[v];
  for (int v = 0; v < s.nb; ++v) out.c[s.na + v] = -s.beta[v];
  for (auto& row : out.dc) row = {0.0, 0.0};
  // alpha_0 = 1 - sum lambda, alpha_j = lambda_j; beta likewise (c = -beta).
  for (int j = 1; j < s.na; ++j) {
    out.dc[0][j - 1] = -1.0;
    out.dc[j][j - 1] = 1.0;
  }
  for (int j = 1; j < s.nb; ++j) {
    const int k = s.na - 1 + j - 1;
    out.dc[s.na][k] = 1.0;
    out.dc[s.na + j][k] = -1.0;
  }
  for (int k = 0; k < K; ++k) {
    out.E.col(k).setZero();
    for (int v = 0; v < m; ++v) out.E.col(k) += out.dc[v][k] * y[v];
  }
  const double D = s.distance;
  const Eigen::Vector3d n = s.P / D;
  for (int v = 0; v < m; ++v) out.gradient.segment<3>(3 * v) = out.c[v] * n;

  // d2f/dy2 = c c^T (x) I - F G^-1 F^T, F = f_ytheta.
  Eigen::Matrix<double, 12, 12> Hf = Eigen::Matrix<double, 12, 12>::Zero();
  for (int v = 0; v < m; ++v) {
    for (int w = 0; w < m; ++w) {
      Hf.block<3, 3>(3 * v, 3 * w) = out.c[v] * out.c[w] * Eigen::Matrix3d::Identity();
    }
  }
  if (K > 0) {
    Eigen::Matrix<double, 12, 2> F = Eigen::Matrix<double, 12, 2>::Zero();
    for (int v = 0; v < m; ++v) {
      for (int k = 0; k < K; ++k) {
        F.block<3, 1>(3 * v, k) = out.dc[v][k] * s.P + out.c[v] * out.E.col(k);
      }
    }
    Eigen::Matrix2d G = Eigen::Matrix2d::Identity();  // (the unused part stays I)
    G.topLeftCorner(K, K) = out.E.leftCols(K).transpose() * out.E.leftCols(K);
    const Eigen::Matrix2d G_inverse = G.inverse();
    out.dtheta.topRows(K) = -(G_inverse.topLeftCorner(K, K) * F.leftCols(K).transpose());
    Hf.topLeftCorner(3 * m, 3 * m) +=
        F.topLeftCorner(3 * m, K) * out.dtheta.topLeftCorner(K, 3 * m);
  }
  out.hessian.topLeftCorner(3 * m, 3 * m) =
      (Hf.topLeftCorner(3 * m, 3 * m) -
       out.gradient.head(3 * m) * out.gradient.head(3 * m).transpose()) / D;
  return out;
}

namespace {
// 6 times the signed volume of (a, b, c, d): positive when d is on the side
// of the plane (a, b, c) that its counter-clockwise normal points to.
double volume(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
              const Eigen::Vector3d& d) {
  return (b - a).cross(c - a).dot(d - a);
}
}  // namespace

bool segment_meets_triangle(const Eigen::Vector3d& p, const Eigen::Vector3d& q,
                            const Eigen::Vector3d& t0, const Eigen::Vector3d& t1,
                            const Eigen::Vector3d& t2) {
  const double sp = volume(t0, t1, t2, p), sq = volume(t0, t1, t2, q);
  if ((sp > 0.0 && sq > 0.0) || (sp < 0.0 && sq < 0.0)) return false;
  if (sp == 0.0 && sq == 0.0) return false;  // in the plane: touching at most
  const double e0 = volume(p, q, t0, t1), e1 = volume(p, q, t1, t2), e2 = volume(p, q, t2, t0);
  return (e0 >= 0.0 && e1 >= 0.0 && e2 >= 0.0) || (e0 <= 0.0 && e1 <= 0.0 && e2 <= 0.0);
}

double winding_number(const Eigen::Vector3d& x, const std::vector<Eigen::Vector3d>& points,
                      const std::vector<SurfaceTriangle>& triangles) {
  double sum = 0.0;
  for (const SurfaceTriangle& t : triangles) {
    const Eigen::Vector3d a = points[t[0]] - x, b = points[t[1]] - x, c = points[t[2]] - x;
    const double la = a.norm(), lb = b.norm(), lc = c.norm();
    const double numerator = a.dot(b.cross(c));
    const double denominator = la * lb * lc + a.dot(b) * lc + a.dot(c) * lb + b.dot(c) * la;
    sum += 2.0 * std::atan2(numerator, denominator);
  }
  return sum / (4.0 * std::numbers::pi);
}

}  // namespace springlab
