// The Jacobian blocks of bodies in contact (body_pair_blocks.h).
#include "models/bodies/body_pair_blocks.h"

#include <algorithm>

namespace springlab {

std::array<int, 8> BodyPairBlocks::unknowns(const BodyContactFinder& finder, int a, int b) {
  std::array<int, 8> index{};
  const int ends[2] = {finder.surface(a).first, finder.surface(b).first};
  for (int e = 0; e < 2; ++e) {
    for (int u = 0; u < 4; ++u) index[static_cast<std::size_t>(4 * e + u)] = ends[e] < 0 ? -1 : ends[e] + u;
  }
  return index;
}

std::vector<std::pair<int, int>> BodyPairBlocks::every_pair(const BodyContactFinder& finder,
                                                            bool& fixed) {
  std::vector<std::pair<int, int>> pairs;
  fixed = finder.size() <= kAllPairsBodies;
  if (!fixed) return pairs;
  for (int a = 0; a < finder.size(); ++a) {
    for (int b = a + 1; b < finder.size(); ++b) {
      if (finder.may_meet(a, b)) pairs.emplace_back(a, b);
    }
  }
  return pairs;
}

std::vector<std::pair<int, int>> BodyPairBlocks::near_pairs(const BodyContactFinder& finder,
                                                            double r,
                                                            std::vector<std::pair<int, int>> also) {
  std::vector<double> grow(static_cast<std::size_t>(finder.size()));
  for (int k = 0; k < finder.size(); ++k) {
    grow[static_cast<std::size_t>(k)] = 0.5 * r + 0.25 * finder.surface(k).radius;
  }
  std::vector<std::pair<int, int>> near;
  finder.near_pairs(grow, near);
  also.insert(also.end(), near.begin(), near.end());
  std::sort(also.begin(), also.end());
  also.erase(std::unique(also.begin(), also.end()), also.end());
  return also;
}

std::vector<std::pair<int, int>> BodyPairBlocks::first_pairs(const BodyContactFinder& finder,
                                                             double r, bool& fixed) {
  std::vector<std::pair<int, int>> every = every_pair(finder, fixed);
  return fixed ? every : near_pairs(finder, r, {});
}

void BodyPairBlocks::set(std::vector<std::pair<int, int>> pairs) {
  std::sort(pairs.begin(), pairs.end());
  pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
  pairs_ = std::move(pairs);
  slots_.clear();
}

bool BodyPairBlocks::covers(int a, int b) const {
  return std::binary_search(pairs_.begin(), pairs_.end(),
                            std::make_pair(std::min(a, b), std::max(a, b)));
}

void BodyPairBlocks::declare(const BodyContactFinder& finder,
                             JacobianPatternBuilder& builder) const {
  for (const auto& [a, b] : pairs_) {
    const std::array<int, 8> index = unknowns(finder, a, b);
    for (int u : index) {
      for (int w : index) {
        if (u >= 0 && w >= 0) builder.add_block(u, w);
      }
    }
  }
}

void BodyPairBlocks::bind(const BodyContactFinder& finder, const SparseMatrix& pattern) {
  slots_.assign(pairs_.size() * 64, BlockSlot{});
  for (std::size_t k = 0; k < pairs_.size(); ++k) {
    const std::array<int, 8> index = unknowns(finder, pairs_[k].first, pairs_[k].second);
    for (std::size_t u = 0; u < 8; ++u) {
      for (std::size_t w = 0; w < 8; ++w) {
        if (index[u] >= 0 && index[w] >= 0) {
          slots_[k * 64 + 8 * u + w] = find_block_slot(pattern, 3, index[u], index[w]);
        }
      }
    }
  }
}

void BodyPairBlocks::add(double* values, int a, int b, int u, int w, const Eigen::Matrix3d& K,
                         double s) const {
  const std::pair<int, int> pair(std::min(a, b), std::max(a, b));
  const auto at = std::lower_bound(pairs_.begin(), pairs_.end(), pair);
  if (at == pairs_.end() || *at != pair) return;  // (not covered: the model follows first)
  const std::size_t k = static_cast<std::size_t>(at - pairs_.begin());
  if (a > b) {  // the pair's slots are in (b's, a's) order
    u = (u + 4) % 8;
    w = (w + 4) % 8;
  }
  const BlockSlot& slot = slots_[k * 64 + static_cast<std::size_t>(8 * u + w)];
  if (!slot.valid()) return;
  double block[3][3];
  for (int r = 0; r < 3; ++r) {
    for (int q = 0; q < 3; ++q) block[r][q] = K(r, q);
  }
  add_block<3>(values, slot, block, s);
}

}  // namespace springlab
