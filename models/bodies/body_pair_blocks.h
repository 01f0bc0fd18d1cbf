// The Jacobian blocks of bodies in contact (body_body_contact.cc,
// body_body_friction.cc): a contact between bodies a and b couples their 8
// pseudo-particles (p, a_1, a_2, a_3 of each), so its Jacobian is 8 x 8
// blocks of 3 x 3. Up to kAllPairsBodies bodies every pair that may meet
// is declared once (a fixed pattern, which every solver can keep: 120
// pairs at most). Beyond, which pairs touch follows the state, and so do
// the declared pairs (ForceTerm::pattern_varies): the pairs near each
// other (body_contacts.h's broad phase), never all pairs of the scene's
// bodies. Either way a sorted list of pairs, with their 64 block slots
// each once the pattern is bound: memory linear in the pairs declared.
#pragma once

#include <Eigen/Core>
#include <array>
#include <utility>
#include <vector>

#include "models/bodies/body_contacts.h"
#include "models/core/force_term.h"

namespace springlab {

inline constexpr int kAllPairsBodies = 16;

class BodyPairBlocks {
 public:
  // Every pair that may meet (BodyContactFinder::may_meet), when the scene
  // has at most kAllPairsBodies bodies; else none, and `fixed` is false.
  static std::vector<std::pair<int, int>> every_pair(const BodyContactFinder& finder, bool& fixed);
  // The pairs to declare at the finder's placed state beyond
  // kAllPairsBodies: those given, and those whose boxes come within the
  // contact distance r and a quarter of the larger bounding radius (room
  // to move before the pattern must follow).
  static std::vector<std::pair<int, int>> near_pairs(const BodyContactFinder& finder, double r,
                                                     std::vector<std::pair<int, int>> also);
  // The pairs a contact or friction term declares at its start (placed):
  // every pair, or the near ones (memory_estimate counts these).
  static std::vector<std::pair<int, int>> first_pairs(const BodyContactFinder& finder, double r,
                                                      bool& fixed);

  // The pair's 8 unknowns in the order (a's p, a_1, a_2, a_3, then b's):
  // internal pseudo-particle indices, -1 where the body is fixed.
  static std::array<int, 8> unknowns(const BodyContactFinder& finder, int a, int b);

  // The pairs to declare (each (lo, hi), lo < hi; sorted and made unique here).
  void set(std::vector<std::pair<int, int>> pairs);
  const std::vector<std::pair<int, int>>& pairs() const { return pairs_; }
  bool covers(int a, int b) const;

  void declare(const BodyContactFinder& finder, JacobianPatternBuilder& builder) const;
  void bind(const BodyContactFinder& finder, const SparseMatrix& pattern);

  // Adds s K to the block (u, w) of pair (a, b), u and w in the pair's
  // order above (a's first, whichever of a, b is lower); nothing where
  // either unknown is fixed. The pair must be covered.
  void add(double* values, int a, int b, int u, int w, const Eigen::Matrix3d& K, double s) const;

 private:
  std::vector<std::pair<int, int>> pairs_;
  std::vector<BlockSlot> slots_;  // 64 per pair: (u, w) at 8 u + w in (lo's, hi's) order
};

}  // namespace springlab
