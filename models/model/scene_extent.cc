#include "models/model/scene_extent.h"

#include <cmath>
#include <vector>

#include "models/contact/contact.h"
#include "models/springs/gravity.h"

namespace springlab {

double extent_of_motion(const Scene& scene, const std::vector<StartPoint>& points) {
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(INFINITY), hi = -lo;
  std::vector<Eigen::Vector3d> free;  // the points that can fall
  for (const Particle& p : scene.particles) {
    lo = lo.cwiseMin(p.x);
    hi = hi.cwiseMax(p.x);
    if (!p.fixed) free.push_back(p.x);
  }
  for (const StartPoint& point : points) {
    lo = lo.cwiseMin(point.x);
    hi = hi.cwiseMax(point.x);
    if (!point.fixed) free.push_back(point.x);
  }
  const Eigen::Vector3d g = scene.get<Gravity>().acceleration;
  const Planes* planes = scene.find<Planes>();
  if (planes != nullptr && g.norm() > 0.0) {
    const Eigen::Vector3d down = g.normalized();
    // The planes that stop a fall: their normal has a part against g.
    std::vector<Plane> floors;
    for (Plane p : *planes) {
      p.normal.stableNormalize();
      if (p.normal.dot(down) < 0.0) floors.push_back(p);
    }
    for (const Eigen::Vector3d& x : free) {
      // Along x + s down the gap n.(x - point) falls at the rate -n.down:
      // it closes at s = gap / -n.down, on the nearest floor above which x is.
      double fall = INFINITY;
      for (const Plane& p : floors) {
        const double gap = p.normal.dot(x - p.point);
        if (gap > 0.0) fall = std::min(fall, gap / -p.normal.dot(down));
      }
      if (!std::isfinite(fall)) continue;
      const Eigen::Vector3d foot = x + fall * down;
      lo = lo.cwiseMin(foot);
      hi = hi.cwiseMax(foot);
    }
  }
  if (!(hi.x() >= lo.x())) return 0.0;  // nothing in the scene
  if (!points.empty()) return (hi - lo).norm();  // a kind's own points are 3-D
  double d2 = 0.0;
  for (int r = 0; r < scene.dimension; ++r) d2 += (hi[r] - lo[r]) * (hi[r] - lo[r]);
  return std::sqrt(d2);
}

}  // namespace springlab
