// The body-body contact and friction kinds' parts of the model's memory
// (memory_estimate.h): each term declares the pairs of bodies
// BodyPairBlocks::first_pairs gives at the scene's start (body_pair_blocks.h:
// every pair that may meet up to kAllPairsBodies bodies, beyond that the
// pairs the broad phase finds near each other), 64 blocks of 3 x 3 each
// with their slots, and keeps the contacts it finds (a few per pair). The
// pairs grow as bodies come near others (a pile settling); this counts the
// start's, which for bodies spread apart is linear in the bodies.
#include <algorithm>
#include <string>
#include <utility>

#include "models/bodies/bodies.h"
#include "models/bodies/body_contacts.h"
#include "models/bodies/body_pair_blocks.h"
#include "models/contact/contact.h"
#include "models/core/element_kind.h"

namespace springlab {

bool has_body_contacts(const Scene& scene);  // body_body_contact.cc

namespace {

double body_pair_count(const Scene& scene) {
  BodyContactFinder finder(scene, body_layout(scene, 0));
  finder.place(nullptr);
  bool fixed = false;
  return static_cast<double>(
      BodyPairBlocks::first_pairs(finder, scene.get<Contact>().distance_or_default(), fixed)
          .size());
}

void add_pairs(const Scene& scene, const char* term, MemoryEstimate& out) {
  const double pairs = body_pair_count(scene);
  const double bodies = static_cast<double>(scene.get<Bodies>().size());
  MemoryPart part;
  part.what = std::to_string(scene.get<Bodies>().size()) + " bodies (" +
              std::to_string(static_cast<long long>(pairs)) + " pairs of bodies for " + term + ")";
  // The pair list, and each body's surface placed in the world.
  part.bytes = pairs * static_cast<double>(sizeof(std::pair<int, int>)) +
               bodies * static_cast<double>(sizeof(BodyContactFinder::Surface));
  for (const Body& b : scene.get<Bodies>()) {
    part.bytes += 2.0 * static_cast<double>(rigid_body(b).X.size() * 3 * sizeof(double));
  }
  // 64 blocks a pair, of which a body's own 16 are shared with all its pairs.
  part.pattern_blocks = 64.0 * pairs;
  part.distinct_blocks = 32.0 * pairs + 16.0 * bodies;
  part.slot_bytes = 64.0 * pairs * static_cast<double>(sizeof(BlockSlot));
  out.parts.push_back(std::move(part));
}

}  // namespace

void body_body_contact_memory(const Scene& scene, MemoryEstimate& out) {
  if (has_body_contacts(scene)) add_pairs(scene, "contact", out);
}

// The friction term exists where two bodies or more are rough, or one has
// contact damping (body_body_friction.cc's has_body_friction).
bool has_body_friction(const Scene& scene);  // body_body_friction.cc
void body_body_friction_memory(const Scene& scene, MemoryEstimate& out) {
  if (has_body_friction(scene)) add_pairs(scene, "friction", out);
}

}  // namespace springlab
