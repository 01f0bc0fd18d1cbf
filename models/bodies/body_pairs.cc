// The pairs of bodies that meet (body_pairs.h).
#include "models/bodies/body_pairs.h"

#include <set>
#include <utility>

#include "models/bodies/body_springs.h"
#include "models/core/scene.h"

namespace springlab {

BodyPairs::BodyPairs(const Scene& scene, const BodyLayout& layout) {
  const Bodies& bodies = scene.get<Bodies>();
  for (std::size_t b = 0; b < layout.bodies.size(); ++b) {
    const RigidBody& rb = layout.bodies[b];
    Member m;
    m.first = layout.first[b];
    m.p0 = rb.p0;
    m.A0 = rb.A0;
    m.X = rb.X;
    m.box = bodies[b].shape == Body::Shape::kBox;
    m.friction = bodies[b].friction;
    for (const Eigen::Vector3d& X : rb.X) {
      m.half = m.half.cwiseMax(X.cwiseAbs());
      m.radius = std::max(m.radius, X.norm());
    }
    members_.push_back(std::move(m));
  }
  // Bodies joined by a spring (a joint) do not meet: a hinge's boxes touch
  // at the joint, where contact would fight the spring.
  std::set<std::pair<int, int>> joined;
  for (const BodySpring& s : scene.get<BodySprings>()) {
    if (s.i.is_body() && s.j.is_body()) {
      joined.insert({std::min(s.i.body, s.j.body), std::max(s.i.body, s.j.body)});
    }
  }
  const int n = static_cast<int>(members_.size());
  for (int a = 0; a < n; ++a) {
    for (int b = 0; b < n; ++b) {
      if (a == b || !member(b).box) continue;
      if (joined.count({std::min(a, b), std::max(a, b)}) != 0) continue;
      if (member(a).first < 0 && member(b).first < 0) continue;
      Pair pair;
      pair.a = a;
      pair.b = b;
      const int ends[2] = {member(a).first, member(b).first};
      for (int e = 0; e < 2; ++e) {
        for (int u = 0; u < 4; ++u) {
          pair.index[static_cast<std::size_t>(4 * e + u)] = ends[e] < 0 ? -1 : ends[e] + u;
        }
      }
      pair.friction = std::sqrt(member(a).friction * member(b).friction);
      pairs_.push_back(pair);
    }
  }
}

void BodyPairs::declare_blocks(JacobianPatternBuilder& builder) const {
  for (const Pair& pair : pairs_) {
    for (int u : pair.index) {
      for (int w : pair.index) {
        if (u >= 0 && w >= 0) builder.add_block(u, w);
      }
    }
  }
}

std::vector<BlockSlot> BodyPairs::find_slots(const SparseMatrix& pattern) const {
  std::vector<BlockSlot> slots(pairs_.size() * 64);
  for (std::size_t k = 0; k < pairs_.size(); ++k) {
    for (std::size_t u = 0; u < 8; ++u) {
      for (std::size_t w = 0; w < 8; ++w) {
        const int iu = pairs_[k].index[u], iw = pairs_[k].index[w];
        if (iu >= 0 && iw >= 0) slots[k * 64 + 8 * u + w] = find_block_slot(pattern, 3, iu, iw);
      }
    }
  }
  return slots;
}

}  // namespace springlab
