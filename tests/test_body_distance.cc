// Distances between pieces of two surfaces (models/body_distance.h): the
// point-triangle and segment-segment distances against a brute-force
// minimum over a fine grid of barycentric weights, every case of closest
// points (vertex, edge, face; end, interior) met; the distance's gradient
// and Hessian against central differences in each case; the segment-
// triangle test and the winding number on cases with known answers.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <map>
#include <random>
#include <vector>

#include "models/bodies/body_distance.h"
#include "models/bodies/mass_properties.h"

namespace springlab::test_body_distance {
namespace {

using Points = std::vector<Eigen::Vector3d>;

Eigen::Vector3d random_point(std::mt19937& rng, double scale) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  return scale * Eigen::Vector3d(u(rng), u(rng), u(rng));
}

// Points 0.. of the first simplex (1 or 2), then of the second (3 or 2).
SimplexDistance distance_of(const Points& y, bool point_triangle) {
  return point_triangle ? point_triangle_distance(y[0], y[1], y[2], y[3])
                        : segment_segment_distance(y[0], y[1], y[2], y[3]);
}

// The brute-force minimum over weights on a grid of 1/400.
double brute_force(const Points& y, bool point_triangle) {
  const int n = 400;
  double best = INFINITY;
  if (point_triangle) {
    for (int i = 0; i <= n; ++i) {
      for (int j = 0; i + j <= n; ++j) {
        const double b = double(i) / n, c = double(j) / n;
        best = std::min(best, (y[0] - ((1 - b - c) * y[1] + b * y[2] + c * y[3])).norm());
      }
    }
  } else {
    for (int i = 0; i <= n; ++i) {
      for (int j = 0; j <= n; ++j) {
        const double s = double(i) / n, t = double(j) / n;
        best = std::min(best, ((y[0] + s * (y[1] - y[0])) - (y[2] + t * (y[3] - y[2]))).norm());
      }
    }
  }
  return best;
}

// The gradient of D over all four input points (zero on inactive ones).
Eigen::Matrix<double, 12, 1> full_gradient(const Points& y, bool point_triangle) {
  const SimplexDistance s = distance_of(y, point_triangle);
  const int first = point_triangle ? 1 : 2;  // where the second simplex's points start
  Eigen::Vector3d active[4];
  int slot[4];
  int m = 0;
  for (int v = 0; v < s.na; ++v) slot[m] = s.ia[v], active[m++] = y[s.ia[v]];
  for (int v = 0; v < s.nb; ++v) slot[m] = first + s.ib[v], active[m++] = y[first + s.ib[v]];
  const DistanceDerivatives d = distance_derivatives(s, active);
  Eigen::Matrix<double, 12, 1> g = Eigen::Matrix<double, 12, 1>::Zero();
  for (int v = 0; v < m; ++v) g.segment<3>(3 * slot[v]) = d.gradient.segment<3>(3 * v);
  return g;
}

Eigen::Matrix<double, 12, 12> full_hessian(const Points& y, bool point_triangle) {
  const SimplexDistance s = distance_of(y, point_triangle);
  const int first = point_triangle ? 1 : 2;
  Eigen::Vector3d active[4];
  int slot[4];
  int m = 0;
  for (int v = 0; v < s.na; ++v) slot[m] = s.ia[v], active[m++] = y[s.ia[v]];
  for (int v = 0; v < s.nb; ++v) slot[m] = first + s.ib[v], active[m++] = y[first + s.ib[v]];
  const DistanceDerivatives d = distance_derivatives(s, active);
  Eigen::Matrix<double, 12, 12> H = Eigen::Matrix<double, 12, 12>::Zero();
  for (int v = 0; v < m; ++v) {
    for (int w = 0; w < m; ++w) {
      H.block<3, 3>(3 * slot[v], 3 * slot[w]) = d.hessian.block<3, 3>(3 * v, 3 * w);
    }
  }
  return H;
}

// The case of a pair: how many points of each simplex are active.
int case_of(const SimplexDistance& s) { return 10 * s.na + s.nb; }

// Random configurations, until every case has been met 5 times: the
// distance agrees with the brute force (to the grid's resolution), the
// closest points' weights reproduce P, the gradient matches central
// differences of D, the Hessian central differences of the gradient.
void check_every_case(bool point_triangle, const std::vector<int>& cases) {
  std::mt19937 rng(point_triangle ? 11 : 12);
  std::map<int, int> met;
  int tries = 0;
  auto done = [&] {
    for (int c : cases) {
      if (met[c] < 5) return false;
    }
    return true;
  };
  while (!done() && ++tries < 20000) {
    Points y(4);
    for (auto& p : y) p = random_point(rng, 1.0);
    if (!point_triangle) {
      // Segments of many directions, some nearly parallel.
      if (tries % 7 == 0) y[3] = y[2] + (y[1] - y[0]) * 0.8 + random_point(rng, 0.05);
    } else {
      // Points near the triangle's plane as well as far.
      if (tries % 3 == 0) y[0] = (y[1] + y[2] + y[3]) / 3.0 + random_point(rng, 0.6);
    }
    const SimplexDistance s = distance_of(y, point_triangle);
    const int c = case_of(s);
    if (met[c] >= 5 || s.distance < 1e-3) continue;
    ++met[c];
    SCOPED_TRACE("case " + std::to_string(c) + ", try " + std::to_string(tries));
    // The brute force samples the weights every 1/400: within that of the truth.
    const double coarse = brute_force(y, point_triangle);
    EXPECT_LE(s.distance, coarse + 1e-12);
    EXPECT_GT(s.distance, coarse - 1e-2);
    const double eps = 1e-6;
    const Eigen::Matrix<double, 12, 1> g = full_gradient(y, point_triangle);
    const Eigen::Matrix<double, 12, 12> H = full_hessian(y, point_triangle);
    for (int j = 0; j < 12; ++j) {
      Points yp = y, ym = y;
      yp[j / 3][j % 3] += eps;
      ym[j / 3][j % 3] -= eps;
      const double dD = (distance_of(yp, point_triangle).distance -
                         distance_of(ym, point_triangle).distance) / (2 * eps);
      EXPECT_NEAR(g[j], dD, 1e-7) << "gradient " << j;
      const Eigen::Matrix<double, 12, 1> dg =
          (full_gradient(yp, point_triangle) - full_gradient(ym, point_triangle)) / (2 * eps);
      EXPECT_LT((H.col(j) - dg).norm(), 1e-5 * (1.0 + dg.norm())) << "Hessian column " << j;
    }
    EXPECT_LT((H - H.transpose()).norm(), 1e-9 * (1.0 + H.norm()));
  }
  for (int c : cases) EXPECT_GE(met[c], 5) << "case " << c << " met " << met[c] << " times";
}

// Vertex (1 active point), edge (2), face (3) of the triangle.
TEST(BodyDistance, PointTriangleInEveryCaseMatchesBruteForceAndDifferences) {
  check_every_case(true, {11, 12, 13});
}

// End or interior of either segment.
TEST(BodyDistance, SegmentSegmentInEveryCaseMatchesBruteForceAndDifferences) {
  check_every_case(false, {11, 12, 21, 22});
}

// Closed forms: a point 0.3 above the middle of a unit right triangle's
// face is 0.3 from it along its normal; beyond its hypotenuse by 0.5 along
// the in-plane normal, 0.5 from the edge's midpoint; two crossing segments
// 0.2 apart along z are 0.2 apart, closest at their middles; parallel
// segments overlapping by half are as far apart as their lines.
TEST(BodyDistance, ClosedFormCases) {
  const Eigen::Vector3d a(0, 0, 0), b(1, 0, 0), c(0, 1, 0);
  SimplexDistance s = point_triangle_distance(Eigen::Vector3d(0.25, 0.25, 0.3), a, b, c);
  EXPECT_EQ(s.nb, 3);
  EXPECT_NEAR(s.distance, 0.3, 1e-15);
  EXPECT_NEAR((s.P - Eigen::Vector3d(0, 0, 0.3)).norm(), 0.0, 1e-15);
  const Eigen::Vector3d out = Eigen::Vector3d(0.5, 0.5, 0) + 0.5 * Eigen::Vector3d(1, 1, 0).normalized();
  s = point_triangle_distance(out, a, b, c);
  EXPECT_EQ(s.nb, 2);
  EXPECT_NEAR(s.distance, 0.5, 1e-15);
  EXPECT_NEAR(s.beta[0], 0.5, 1e-15);
  s = segment_segment_distance({-1, 0, 0.2}, {1, 0, 0.2}, {0, -1, 0}, {0, 1, 0});
  EXPECT_EQ(s.na, 2);
  EXPECT_EQ(s.nb, 2);
  EXPECT_NEAR(s.distance, 0.2, 1e-15);
  EXPECT_NEAR(s.alpha[0], 0.5, 1e-15);
  s = segment_segment_distance({0, 0, 0.1}, {1, 0, 0.1}, {0.5, 0, 0}, {1.5, 0, 0});
  EXPECT_NEAR(s.distance, 0.1, 1e-15);
}

TEST(BodyDistance, SegmentMeetsTriangleAndWindingNumber) {
  const Eigen::Vector3d a(0, 0, 0), b(1, 0, 0), c(0, 1, 0);
  EXPECT_TRUE(segment_meets_triangle({0.2, 0.2, -1}, {0.2, 0.2, 1}, a, b, c));
  EXPECT_FALSE(segment_meets_triangle({0.2, 0.2, 0.1}, {0.2, 0.2, 1}, a, b, c));
  EXPECT_FALSE(segment_meets_triangle({0.8, 0.8, -1}, {0.8, 0.8, 1}, a, b, c));
  EXPECT_TRUE(segment_meets_triangle({-1, 0.3, 0.5}, {1, 0.3, -0.5}, a, b, c));
  Points box;
  std::vector<SurfaceTriangle> triangles;
  box_surface(Eigen::Vector3d(1.0, 2.0, 3.0), box, triangles);
  EXPECT_NEAR(winding_number({0.1, 0.2, 0.3}, box, triangles), 1.0, 1e-12);
  EXPECT_NEAR(winding_number({0.45, -0.9, 1.4}, box, triangles), 1.0, 1e-12);
  EXPECT_NEAR(winding_number({0.6, 0.0, 0.0}, box, triangles), 0.0, 1e-12);
  EXPECT_NEAR(winding_number({5.0, 7.0, -3.0}, box, triangles), 0.0, 1e-12);
}

}  // namespace
}  // namespace springlab::test_body_distance
