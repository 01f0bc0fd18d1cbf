// Where rigid bodies meet (body_contacts.h).
#include "models/bodies/body_contacts.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <tuple>

#include "models/bodies/body_springs.h"
#include "models/core/scene.h"

namespace springlab {
namespace {

// Coplanar neighbours: their unit normals agree to this.
constexpr double kFlat = 1e-10;

// The squared distance from x to the box [lo, hi].
double box_distance2(const Eigen::Vector3d& x, const Eigen::Vector3d& lo,
                     const Eigen::Vector3d& hi) {
  const Eigen::Vector3d below = (lo - x).cwiseMax(0.0), above = (x - hi).cwiseMax(0.0);
  return (below + above).squaredNorm();
}

bool boxes_meet(const Eigen::Vector3d& lo1, const Eigen::Vector3d& hi1, const Eigen::Vector3d& lo2,
                const Eigen::Vector3d& hi2, double grow) {
  for (int r = 0; r < 3; ++r) {
    if (lo1[r] - grow > hi2[r] || lo2[r] - grow > hi1[r]) return false;
  }
  return true;
}

}  // namespace

std::string BodyOverlap::text() const {
  std::ostringstream out;
  if (triangle >= 0) {
    out << "edge (" << edge_from << ", " << edge_to << ") of body " << a
        << " passes through triangle " << triangle << " of body " << b;
  } else {
    out << "body " << a << " lies inside body " << b;
  }
  return out.str();
}

Eigen::Vector3d BodyContactFinder::Surface::p(const double* x) const {
  return first < 0 || x == nullptr ? p0 : Eigen::Vector3d(x[3 * first], x[3 * first + 1], x[3 * first + 2]);
}

Eigen::Matrix3d BodyContactFinder::Surface::A(const double* x) const {
  if (first < 0 || x == nullptr) return A0;
  Eigen::Matrix3d A;
  for (int i = 0; i < 3; ++i) {
    for (int r = 0; r < 3; ++r) A(r, i) = x[3 * (first + 1 + i) + r];
  }
  return A;
}

BodyContactFinder::BodyContactFinder(const Scene& scene, const BodyLayout& layout) {
  const Bodies& bodies = scene.get<Bodies>();
  for (std::size_t k = 0; k < layout.bodies.size(); ++k) {
    const RigidBody& rb = layout.bodies[k];
    Surface s;
    s.first = layout.first[k];
    s.p0 = rb.p0;
    s.A0 = rb.A0;
    s.X = rb.X;
    s.triangles = rb.triangles;
    s.friction = bodies[k].friction;
    s.contact_damping = bodies[k].contact_damping;
    for (const Eigen::Vector3d& X : s.X) s.radius = std::max(s.radius, X.norm());
    // Each edge with the triangles on its two sides (a closed surface).
    std::vector<std::tuple<int, int, int>> sides;  // (lower vertex, upper vertex, triangle)
    for (std::size_t t = 0; t < s.triangles.size(); ++t) {
      for (int e = 0; e < 3; ++e) {
        const int i = s.triangles[t][e], j = s.triangles[t][(e + 1) % 3];
        sides.emplace_back(std::min(i, j), std::max(i, j), static_cast<int>(t));
      }
    }
    std::sort(sides.begin(), sides.end());
    auto normal = [&](int t) {
      const SurfaceTriangle& tri = s.triangles[static_cast<std::size_t>(t)];
      return (s.X[tri[1]] - s.X[tri[0]]).cross(s.X[tri[2]] - s.X[tri[0]]).normalized();
    };
    for (std::size_t e = 0; e + 1 < sides.size(); e += 2) {
      const auto& [i, j, t1] = sides[e];
      const int t2 = std::get<2>(sides[e + 1]);
      s.edges.push_back({i, j});
      if (normal(t1).dot(normal(t2)) < 1.0 - kFlat) s.feature_edges.push_back({i, j});
    }
    surfaces_.push_back(std::move(s));
  }
  for (const BodySpring& spring : scene.get<BodySprings>()) {
    if (spring.i.is_body() && spring.j.is_body()) {
      joined_.emplace_back(std::min(spring.i.body, spring.j.body),
                           std::max(spring.i.body, spring.j.body));
    }
  }
  std::sort(joined_.begin(), joined_.end());
  world_.resize(surfaces_.size());
  lo_.resize(surfaces_.size());
  hi_.resize(surfaces_.size());
  // Fixed bodies are placed once.
  for (std::size_t k = 0; k < surfaces_.size(); ++k) {
    const Surface& s = surfaces_[k];
    if (s.first >= 0) continue;
    for (const Eigen::Vector3d& X : s.X) world_[k].push_back(s.p0 + s.A0 * X);
    lo_[k] = hi_[k] = world_[k].front();
    for (const Eigen::Vector3d& x : world_[k]) {
      lo_[k] = lo_[k].cwiseMin(x);
      hi_[k] = hi_[k].cwiseMax(x);
    }
  }
}

bool BodyContactFinder::may_meet(int a, int b) const {
  if (a == b) return false;
  if (surface(a).first < 0 && surface(b).first < 0) return false;
  return !std::binary_search(joined_.begin(), joined_.end(),
                             std::make_pair(std::min(a, b), std::max(a, b)));
}

void BodyContactFinder::place(const double* x) {
  for (std::size_t k = 0; k < surfaces_.size(); ++k) {
    const Surface& s = surfaces_[k];
    if (s.first < 0) continue;
    const Eigen::Vector3d p = s.p(x);
    const Eigen::Matrix3d A = s.A(x);
    std::vector<Eigen::Vector3d>& w = world_[k];
    w.resize(s.X.size());
    for (std::size_t v = 0; v < s.X.size(); ++v) w[v] = p + A * s.X[v];
    lo_[k] = hi_[k] = w.front();
    for (const Eigen::Vector3d& y : w) {
      lo_[k] = lo_[k].cwiseMin(y);
      hi_[k] = hi_[k].cwiseMax(y);
    }
  }
}

void BodyContactFinder::near_pairs(const std::vector<double>& grow,
                                   std::vector<std::pair<int, int>>& out) const {
  out.clear();
  const int n = size();
  if (n < 2) return;
  // The axis along which the boxes' centres spread most.
  Eigen::Vector3d mean = Eigen::Vector3d::Zero(), square = Eigen::Vector3d::Zero();
  for (int k = 0; k < n; ++k) {
    const Eigen::Vector3d c = 0.5 * (lo_[k] + hi_[k]);
    mean += c;
    square += c.cwiseProduct(c);
  }
  int axis = 0;
  (square / n - (mean / n).cwiseProduct(mean / n)).maxCoeff(&axis);
  std::vector<int> order(static_cast<std::size_t>(n));
  for (int k = 0; k < n; ++k) order[static_cast<std::size_t>(k)] = k;
  auto lower = [&](int k) { return lo_[k][axis] - grow[static_cast<std::size_t>(k)]; };
  auto upper = [&](int k) { return hi_[k][axis] + grow[static_cast<std::size_t>(k)]; };
  std::sort(order.begin(), order.end(), [&](int i, int j) {
    return lower(i) < lower(j) || (lower(i) == lower(j) && i < j);
  });
  std::vector<int> active;
  for (int i : order) {
    const double start = lower(i);
    active.erase(std::remove_if(active.begin(), active.end(),
                                [&](int j) { return upper(j) < start; }),
                 active.end());
    for (int j : active) {
      const double g = grow[static_cast<std::size_t>(i)] + grow[static_cast<std::size_t>(j)];
      if (boxes_meet(lo_[i], hi_[i], lo_[j], hi_[j], g) && may_meet(i, j)) {
        out.emplace_back(std::min(i, j), std::max(i, j));
      }
    }
    active.push_back(i);
  }
  std::sort(out.begin(), out.end());
}

void BodyContactFinder::vertices_against(int a, int b, double r,
                                         std::vector<BodyContact>& out) const {
  const std::vector<Eigen::Vector3d>& xa = world(a);
  const std::vector<Eigen::Vector3d>& xb = world(b);
  const Surface& sa = surface(a);
  const Surface& sb = surface(b);
  const Eigen::Vector3d lo = lo_[b] - Eigen::Vector3d::Constant(r);
  const Eigen::Vector3d hi = hi_[b] + Eigen::Vector3d::Constant(r);
  for (std::size_t v = 0; v < xa.size(); ++v) {
    const Eigen::Vector3d& x = xa[v];
    if ((x.array() < lo.array()).any() || (x.array() > hi.array()).any()) continue;
    double best = r;
    int best_t = -1;
    SimplexDistance nearest;
    for (std::size_t t = 0; t < sb.triangles.size(); ++t) {
      const SurfaceTriangle& tri = sb.triangles[t];
      const Eigen::Vector3d& t0 = xb[tri[0]];
      const Eigen::Vector3d& t1 = xb[tri[1]];
      const Eigen::Vector3d& t2 = xb[tri[2]];
      if (box_distance2(x, t0.cwiseMin(t1).cwiseMin(t2), t0.cwiseMax(t1).cwiseMax(t2)) >=
          best * best) {
        continue;
      }
      const SimplexDistance s = point_triangle_distance(x, t0, t1, t2);
      if (s.distance < best) {
        best = s.distance;
        best_t = static_cast<int>(t);
        nearest = s;
      }
    }
    if (best_t < 0) continue;
    const SurfaceTriangle& tri = sb.triangles[static_cast<std::size_t>(best_t)];
    BodyContact c;
    c.a = a;
    c.b = b;
    c.va = {static_cast<int>(v), -1, -1};
    c.vb = {tri[0], tri[1], tri[2]};
    c.simplex = nearest;
    c.Xa = sa.X[v];
    for (int j = 0; j < nearest.nb; ++j) c.Xb += nearest.beta[j] * sb.X[tri[nearest.ib[j]]];
    c.d = nearest.distance;
    // At zero distance (touching) the direction is the triangle's normal.
    c.n = c.d > 0.0 ? Eigen::Vector3d(nearest.P / c.d)
                    : (xb[tri[1]] - xb[tri[0]]).cross(xb[tri[2]] - xb[tri[0]]).normalized();
    out.push_back(c);
  }
}

void BodyContactFinder::edges_against(int a, int b, double r,
                                      std::vector<BodyContact>& out) const {
  const std::vector<Eigen::Vector3d>& xa = world(a);
  const std::vector<Eigen::Vector3d>& xb = world(b);
  const Surface& sa = surface(a);
  const Surface& sb = surface(b);
  // The region both boxes, grown by r, cover.
  const Eigen::Vector3d lo = lo_[a].cwiseMax(lo_[b]) - Eigen::Vector3d::Constant(r);
  const Eigen::Vector3d hi = hi_[a].cwiseMin(hi_[b]) + Eigen::Vector3d::Constant(r);
  auto inside = [&](const Eigen::Vector3d& p, const Eigen::Vector3d& q) {
    return boxes_meet(p.cwiseMin(q), p.cwiseMax(q), lo, hi, 0.0);
  };
  std::vector<std::size_t> near_a, near_b;
  for (std::size_t e = 0; e < sa.feature_edges.size(); ++e) {
    if (inside(xa[sa.feature_edges[e][0]], xa[sa.feature_edges[e][1]])) near_a.push_back(e);
  }
  for (std::size_t e = 0; e < sb.feature_edges.size(); ++e) {
    if (inside(xb[sb.feature_edges[e][0]], xb[sb.feature_edges[e][1]])) near_b.push_back(e);
  }
  for (std::size_t i : near_a) {
    const auto& ea = sa.feature_edges[i];
    const Eigen::Vector3d& p0 = xa[ea[0]];
    const Eigen::Vector3d& p1 = xa[ea[1]];
    for (std::size_t j : near_b) {
      const auto& eb = sb.feature_edges[j];
      const Eigen::Vector3d& q0 = xb[eb[0]];
      const Eigen::Vector3d& q1 = xb[eb[1]];
      if (!boxes_meet(p0.cwiseMin(p1), p0.cwiseMax(p1), q0.cwiseMin(q1), q0.cwiseMax(q1), r)) {
        continue;
      }
      const SimplexDistance s = segment_segment_distance(p0, p1, q0, q1);
      if (!(s.distance < r)) continue;
      BodyContact c;
      c.a = a;
      c.b = b;
      c.va = {ea[0], ea[1], -1};
      c.vb = {eb[0], eb[1], -1};
      c.simplex = s;
      for (int k = 0; k < s.na; ++k) c.Xa += s.alpha[k] * sa.X[c.va[s.ia[k]]];
      for (int k = 0; k < s.nb; ++k) c.Xb += s.beta[k] * sb.X[c.vb[s.ib[k]]];
      c.d = s.distance;
      if (c.d > 0.0) {
        c.n = s.P / c.d;
      } else {
        // Touching: across both edges, pointing away from b's centre.
        c.n = (p1 - p0).cross(q1 - q0).normalized();
        const Eigen::Vector3d centre_b = 0.5 * (lo_[b] + hi_[b]);
        if (c.n.dot(p0 - centre_b) < 0.0) c.n = -c.n;
      }
      out.push_back(c);
    }
  }
}

void BodyContactFinder::contacts(int a, int b, double r, std::vector<BodyContact>& out) const {
  vertices_against(a, b, r, out);
  vertices_against(b, a, r, out);
  edges_against(a, b, r, out);
}

void BodyContactFinder::all_contacts(double r, std::vector<BodyContact>& out) const {
  out.clear();
  grow_.assign(surfaces_.size(), 0.5 * r);
  std::vector<std::pair<int, int>> pairs;
  near_pairs(grow_, pairs);
  for (const auto& [a, b] : pairs) contacts(a, b, r, out);
}

void BodyContactFinder::step_contacts(double r, const double* v, double h, double g,
                                      std::vector<BodyContact>& out) const {
  out.clear();
  const bool moving = v != nullptr && h > 0.0;
  std::vector<double> reach(surfaces_.size(), 0.0);
  for (std::size_t k = 0; k < surfaces_.size() && moving; ++k) {
    const Surface& s = surfaces_[k];
    if (s.first < 0) continue;
    const double speed = s.p(v).norm() + s.A(v).norm() * s.radius;
    reach[k] = 2.0 * h * speed + 2.0 * g * h * h;
  }
  grow_.resize(surfaces_.size());
  for (std::size_t k = 0; k < surfaces_.size(); ++k) grow_[k] = 0.5 * r + reach[k];
  std::vector<std::pair<int, int>> pairs;
  near_pairs(grow_, pairs);
  for (const auto& [a, b] : pairs) {
    contacts(a, b, r + reach[static_cast<std::size_t>(a)] + reach[static_cast<std::size_t>(b)],
             out);
  }
}

BodyOverlap BodyContactFinder::crossing(int a, int b) const {
  const std::vector<Eigen::Vector3d>& xa = world(a);
  const std::vector<Eigen::Vector3d>& xb = world(b);
  const Surface& sa = surface(a);
  const Surface& sb = surface(b);
  const Eigen::Vector3d lo = lo_[a].cwiseMax(lo_[b]), hi = hi_[a].cwiseMin(hi_[b]);
  std::vector<std::size_t> triangles;
  for (std::size_t t = 0; t < sb.triangles.size(); ++t) {
    const SurfaceTriangle& tri = sb.triangles[t];
    const Eigen::Vector3d tlo = xb[tri[0]].cwiseMin(xb[tri[1]]).cwiseMin(xb[tri[2]]);
    const Eigen::Vector3d thi = xb[tri[0]].cwiseMax(xb[tri[1]]).cwiseMax(xb[tri[2]]);
    if (boxes_meet(tlo, thi, lo, hi, 0.0)) triangles.push_back(t);
  }
  BodyOverlap found;
  if (triangles.empty()) return found;
  for (const auto& e : sa.edges) {
    const Eigen::Vector3d& p = xa[e[0]];
    const Eigen::Vector3d& q = xa[e[1]];
    const Eigen::Vector3d elo = p.cwiseMin(q), ehi = p.cwiseMax(q);
    if (!boxes_meet(elo, ehi, lo, hi, 0.0)) continue;
    for (std::size_t t : triangles) {
      const SurfaceTriangle& tri = sb.triangles[t];
      if (segment_meets_triangle(p, q, xb[tri[0]], xb[tri[1]], xb[tri[2]])) {
        found.a = a;
        found.b = b;
        found.edge_from = e[0];
        found.edge_to = e[1];
        found.triangle = static_cast<int>(t);
        return found;
      }
    }
  }
  return found;
}

BodyOverlap BodyContactFinder::overlap() const {
  grow_.assign(surfaces_.size(), 0.0);
  std::vector<std::pair<int, int>> pairs;
  near_pairs(grow_, pairs);
  for (const auto& [a, b] : pairs) {
    BodyOverlap o = crossing(a, b);
    if (!o.found()) o = crossing(b, a);
    if (o.found()) return o;
    // No surface crosses the other: one inside the other, or apart.
    for (const auto& [inner, outer] : {std::make_pair(a, b), std::make_pair(b, a)}) {
      if (winding_number(world(inner).front(), world(outer), surface(outer).triangles) > 0.5) {
        o.a = inner;
        o.b = outer;
        return o;
      }
    }
  }
  return {};
}

BodyContactFinder::Derivatives BodyContactFinder::derivatives(const BodyContact& c) const {
  const SimplexDistance& s = c.simplex;
  // The active points: their positions y, rest coordinates Y, and which
  // body (0: a, 1: b).
  Eigen::Vector3d y[4], Y[4];
  int side[4];
  int m = 0;
  for (int v = 0; v < s.na; ++v, ++m) {
    const int vertex = c.va[s.ia[v]];
    y[m] = world(c.a)[vertex];
    Y[m] = surface(c.a).X[vertex];
    side[m] = 0;
  }
  for (int v = 0; v < s.nb; ++v, ++m) {
    const int vertex = c.vb[s.ib[v]];
    y[m] = world(c.b)[vertex];
    Y[m] = surface(c.b).X[vertex];
    side[m] = 1;
  }
  const DistanceDerivatives d = distance_derivatives(s, y);
  // W: dy/dq, 3 m x 24; row block v has (1, Y_v) (x) I in its body's columns.
  Eigen::Matrix<double, 12, 24> W = Eigen::Matrix<double, 12, 24>::Zero();
  for (int v = 0; v < m; ++v) {
    const double w[4] = {1.0, Y[v].x(), Y[v].y(), Y[v].z()};
    for (int u = 0; u < 4; ++u) {
      W.block<3, 3>(3 * v, 3 * (4 * side[v] + u)) = w[u] * Eigen::Matrix3d::Identity();
    }
  }
  const auto Wm = W.topRows(3 * m);
  Derivatives out;
  out.gradient = Wm.transpose() * d.gradient.head(3 * m);
  out.hessian = Wm.transpose() * d.hessian.topLeftCorner(3 * m, 3 * m) * Wm;
  const int K = d.k;
  Eigen::Matrix<double, 2, 24> dtheta = Eigen::Matrix<double, 2, 24>::Zero();
  dtheta.topRows(K) = d.dtheta.topLeftCorner(K, 3 * m) * Wm;
  // dP/dq = sum_v c_v dy_v/dq + E dtheta/dq.
  Eigen::Matrix<double, 3, 24> dP = d.E.leftCols(K) * dtheta.topRows(K);
  for (int v = 0; v < m; ++v) dP += d.c[v] * W.block<3, 24>(3 * v, 0);
  const double D = s.distance;
  const Eigen::Vector3d n = s.P / D;
  out.dn = (Eigen::Matrix3d::Identity() - n * n.transpose()) / D * dP;
  // X_a = sum over a's points c_v Y_v, X_b = -sum over b's points c_v Y_v.
  out.dXa.setZero();
  out.dXb.setZero();
  for (int k = 0; k < K; ++k) {
    Eigen::Vector3d along_a = Eigen::Vector3d::Zero(), along_b = Eigen::Vector3d::Zero();
    for (int v = 0; v < m; ++v) (side[v] == 0 ? along_a : along_b) += d.dc[v][k] * Y[v];
    out.dXa += along_a * dtheta.row(k);
    out.dXb -= along_b * dtheta.row(k);
  }
  return out;
}

}  // namespace springlab
