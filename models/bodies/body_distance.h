// Distances between the pieces of two surfaces (docs/physics.md "Contact
// between bodies"): a point against a triangle and a segment against a
// segment, the two kinds of pair that IPC's barrier acts on (Li et al.,
// "Incremental Potential Contact", ACM TOG 39(4), 2020, sec. 4), with the
// derivatives the contact forces and their Jacobians need.
//
// Both are the distance between two simplices (a point, a segment, a
// triangle): with barycentric weights alpha on the points u_i of the first
// and beta on the points w_j of the second,
//
//   D^2 / 2 = min over alpha, beta of f,   f = |P|^2 / 2,
//   P = sum_i alpha_i u_i - sum_j beta_j w_j      (alpha, beta >= 0, each summing to 1).
//
// The closest points lie inside two sub-simplices (a vertex, an edge or the
// triangle itself: the active points, found here by the classical
// closest-point constructions of Ericson, "Real-Time Collision Detection",
// 2005, sec. 5.1.5 and 5.1.9). On them the weights are free parameters
// theta (alpha_0 = 1 - sum lambda, alpha_m = lambda_m; beta likewise), so
// that P = sum_v c_v(theta) y_v over the active points y_v, with c = alpha
// on the first simplex's and c = -beta on the second's. Then
//
//   dD/dy_v = c_v n,   n = P / D                  (the closest points' weights),
//
// and by the implicit function theorem applied to df/dtheta = E^T P = 0
// (E_k = dP/dtheta_k = sum_v dc_v/dtheta_k y_v):
//
//   d2f/dy2 = f_yy - f_ytheta G^-1 f_thetay,   G = E^T E,
//   f_yy = c c^T (x) I,   (f_ytheta)_{v,k} = dc_v/dtheta_k P + c_v E_k,
//   dtheta/dy = -G^-1 f_thetay,
//   d2D/dy2 = (d2f/dy2 - dD/dy dD/dy^T) / D.
//
// One formula for every case (point-point, point-edge, point-face,
// edge-edge): the case only decides which points are active.
#pragma once

#include <Eigen/Core>
#include <array>
#include <vector>

#include "models/bodies/mass_properties.h"

namespace springlab {

// The closest points of two simplices (up to 3 points each).
struct SimplexDistance {
  int na = 0, nb = 0;                      // active points of each simplex (1 to 3)
  std::array<int, 3> ia{}, ib{};            // which of its points (0, 1, 2) they are
  std::array<double, 3> alpha{}, beta{};    // their weights (each set sums to 1)
  Eigen::Vector3d P = Eigen::Vector3d::Zero();  // closest point on the first - on the second
  double distance = 0.0;                        // |P|
};

// Point x against the triangle (t0, t1, t2): the first simplex is x.
SimplexDistance point_triangle_distance(const Eigen::Vector3d& x, const Eigen::Vector3d& t0,
                                        const Eigen::Vector3d& t1, const Eigen::Vector3d& t2);
// Segment (p0, p1) against segment (q0, q1).
SimplexDistance segment_segment_distance(const Eigen::Vector3d& p0, const Eigen::Vector3d& p1,
                                         const Eigen::Vector3d& q0, const Eigen::Vector3d& q1);

// The derivatives of D with respect to the active points' positions y
// (the first simplex's active points, then the second's: m = na + nb <= 4
// points, 3 m coordinates), and of theta.
struct DistanceDerivatives {
  int m = 0;  // active points
  int k = 0;  // free parameters theta (na - 1 + nb - 1)
  std::array<double, 4> c{};  // c_v: alpha, then -beta
  // dc_v/dtheta_k (0 or +-1).
  std::array<std::array<double, 2>, 4> dc{};
  Eigen::Matrix<double, 12, 1> gradient = Eigen::Matrix<double, 12, 1>::Zero();   // dD/dy
  Eigen::Matrix<double, 12, 12> hessian = Eigen::Matrix<double, 12, 12>::Zero();  // d2D/dy2
  Eigen::Matrix<double, 2, 12> dtheta = Eigen::Matrix<double, 2, 12>::Zero();     // dtheta/dy
  Eigen::Matrix<double, 3, 2> E = Eigen::Matrix<double, 3, 2>::Zero();            // dP/dtheta
};

// y: the m active positions in that order. D must be positive.
DistanceDerivatives distance_derivatives(const SimplexDistance& s, const Eigen::Vector3d* y);

// Whether the segment (p, q) meets the triangle (t0, t1, t2) (touching
// counts): the sign tests of the signed volumes (the segment's ends on
// opposite sides of, or on, the triangle's plane, and the line through them
// passing inside the triangle's three edges).
bool segment_meets_triangle(const Eigen::Vector3d& p, const Eigen::Vector3d& q,
                            const Eigen::Vector3d& t0, const Eigen::Vector3d& t1,
                            const Eigen::Vector3d& t2);

// The winding number of a closed, outward-oriented surface about x: 1
// inside, 0 outside (the solid angles of its triangles seen from x, summed
// and divided by 4 pi: Van Oosterom and Strackee, "The solid angle of a
// plane triangle", IEEE Trans. Biomed. Eng. 30(2), 1983).
double winding_number(const Eigen::Vector3d& x, const std::vector<Eigen::Vector3d>& points,
                      const std::vector<SurfaceTriangle>& triangles);

}  // namespace springlab
