// The body-body contact and friction kinds' parts of the model's memory
// (memory_estimate.h): their terms each hold every pair of bodies
// BodyPairs makes (body_pairs.h: each body against each box, not two fixed
// ones, not two joined by a body spring) -- n^2 of them for n boxes, 10^8
// for the 10,000 the scene cap allows. Once the pattern is built, a pair
// declares the 8 x 8 blocks of its two bodies' unknowns and keeps their
// slots. When the pairs come from a broad phase instead, this count is the
// one to change.
#include <algorithm>
#include <set>
#include <string>
#include <utility>

#include "models/bodies/bodies.h"
#include "models/bodies/body_pairs.h"
#include "models/bodies/body_springs.h"
#include "models/core/element_kind.h"

namespace springlab {

bool has_body_contacts(const Scene& scene);  // body_body_contact.cc

namespace {

// BodyPairs' count, without making the pairs: n x boxes, less each box
// against itself, the pairs of two fixed bodies and the joined ones.
double body_pair_count(const Scene& scene) {
  const Bodies& bodies = scene.get<Bodies>();
  double boxes = 0.0, fixed = 0.0, fixed_boxes = 0.0;
  for (const Body& b : bodies) {
    const bool box = b.shape == Body::Shape::kBox;
    boxes += box ? 1.0 : 0.0;
    fixed += b.fixed ? 1.0 : 0.0;
    fixed_boxes += box && b.fixed ? 1.0 : 0.0;
  }
  double pairs = static_cast<double>(bodies.size()) * boxes - boxes;
  pairs -= fixed * fixed_boxes - fixed_boxes;  // two fixed bodies
  std::set<std::pair<int, int>> joined;
  for (const BodySpring& s : scene.get<BodySprings>()) {
    if (s.i.is_body() && s.j.is_body() && s.i.body != s.j.body) {
      joined.insert({std::min(s.i.body, s.j.body), std::max(s.i.body, s.j.body)});
    }
  }
  for (const auto& [a, b] : joined) {
    const Body& one = bodies[static_cast<std::size_t>(a)];
    const Body& two = bodies[static_cast<std::size_t>(b)];
    if (one.fixed && two.fixed) continue;  // not counted above either
    pairs -= (two.shape == Body::Shape::kBox ? 1.0 : 0.0) + (one.shape == Body::Shape::kBox ? 1.0 : 0.0);
  }
  return std::max(pairs, 0.0);
}

void add_pairs(const Scene& scene, const char* term, MemoryEstimate& out) {
  const double pairs = body_pair_count(scene);
  const double bodies = static_cast<double>(scene.get<Bodies>().size());
  MemoryPart part;
  part.what = std::to_string(scene.get<Bodies>().size()) + " bodies (" +
              std::to_string(static_cast<long long>(pairs)) + " pairs of bodies for " + term + ")";
  part.bytes = pairs * static_cast<double>(sizeof(BodyPairs::Pair));
  // 64 blocks a pair; the pair (b, a) of two boxes declares the same ones,
  // and a body's own 16 are shared with all its pairs.
  part.pattern_blocks = 64.0 * pairs;
  part.distinct_blocks = 16.0 * pairs + 16.0 * bodies;
  part.slot_bytes = 64.0 * pairs * static_cast<double>(sizeof(BlockSlot));
  out.parts.push_back(std::move(part));
}

}  // namespace

void body_body_contact_memory(const Scene& scene, MemoryEstimate& out) {
  if (has_body_contacts(scene)) add_pairs(scene, "contact", out);
}

// The friction term exists where two bodies or more are rough
// (body_body_friction.cc's has_body_friction).
void body_body_friction_memory(const Scene& scene, MemoryEstimate& out) {
  if (!has_body_contacts(scene)) return;
  const Bodies& bodies = scene.get<Bodies>();
  const auto rough =
      std::count_if(bodies.begin(), bodies.end(), [](const Body& b) { return b.friction > 0.0; });
  if (rough >= 2) add_pairs(scene, "friction", out);
}

}  // namespace springlab
