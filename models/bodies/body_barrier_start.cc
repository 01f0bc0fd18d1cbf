// With contact model "barrier" every body must start outside every plane,
// as every free particle must (check_barrier_start, planes.cc): the
// barrier's energy b(d) is infinite at a gap d <= 0, and a body that starts
// on or inside a plane got "the initial energy is not finite", which names
// no body and no plane (issue 46). Checked where the body-plane contact
// kind reads or validates a scene (after the planes and the bodies).
#include <string>
#include <vector>

#include "models/bodies/bodies.h"
#include "models/contact/contact.h"
#include "models/core/scene_io.h"

namespace springlab {

void check_body_barrier_start(const Scene& scene, const Reporter& r) {
  const Contact* contact = scene.find<Contact>();
  const Planes* planes = scene.find<Planes>();
  const Bodies* bodies = scene.find<Bodies>();
  if (contact == nullptr || planes == nullptr || bodies == nullptr ||
      contact->model != ContactModel::kBarrier) {
    return;
  }
  for (std::size_t b = 0; b < bodies->size(); ++b) {
    if ((*bodies)[b].fixed) continue;
    const RigidBody body = rigid_body((*bodies)[b]);
    for (std::size_t k = 0; k < planes->size(); ++k) {
      const Plane& p = (*planes)[k];
      const Eigen::Vector3d n = p.normal.stableNormalized();
      for (std::size_t v = 0; v < body.X.size(); ++v) {
        // x = p + A X (bodies.h), at the start.
        const double d = n.dot(body.p0 + body.A0 * body.X[v] - p.point);
        if (!(d > 0.0)) {
          r.fail(element("bodies", b),
                 "surface vertex " + std::to_string(v) + " starts " + (d == 0.0 ? "on" : "inside") +
                     " plane " + std::to_string(k) + " (gap " + shortest_text(d) +
                     " m), where the barrier's energy is infinite: with contact model "
                     "\"barrier\" every body must start outside every plane");
        }
      }
    }
  }
}

}  // namespace springlab
