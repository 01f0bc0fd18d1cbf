// Neighbour search on a uniform grid (docs/physics.md "Fluids"): every pair
// of points closer than a radius R, in time linear in the number of points.
// The points are binned into cubic cells of side R, so the partners of a
// point lie in its own cell and the 3^d - 1 around it. Cells are found by
// spatial hashing (Teschner et al. 2003, "Optimized spatial hashing for
// collision detection of deformable objects", VMV): the integer cell
// coordinates hash into a table of about twice as many buckets as points,
// so memory stays linear however far apart the points are; a bucket shared
// by two cells is filtered by each point's own cell. The buckets are filled
// by a counting sort (stable), so the pairs come out in one deterministic
// order: by first point, then cell by cell.
#pragma once

#include <cstdint>
#include <utility>
#include <vector>

namespace springlab {

class NeighbourGrid {
 public:
  // Finds every pair (i, j), i < j, with |x_i - x_j| < radius among the
  // `count` points x (point p at x[p * dim .. p * dim + dim)). A point that
  // is not finite has no partners.
  void build(const double* x, int count, int dim, double radius);

  // The pairs found, i < j: the partners of i are pairs()[first(i) ..
  // first(i + 1)).
  const std::vector<std::pair<int, int>>& pairs() const { return pairs_; }
  int first(int i) const { return first_[static_cast<std::size_t>(i)]; }

 private:
  std::size_t bucket(std::int64_t cx, std::int64_t cy, std::int64_t cz) const;

  std::vector<std::pair<int, int>> pairs_;
  std::vector<int> first_;
  std::vector<std::int64_t> cell_;       // 3 per point
  std::vector<int> bucket_start_, order_;  // counting sort: points by bucket
  // Scratch kept between builds (a fluid searches at every evaluation).
  std::vector<char> binned_;
  std::vector<std::size_t> of_;
  std::vector<int> fill_;
  std::size_t mask_ = 0;
};

// The same pairs by comparing every pair of points (O(N^2)): the tests'
// reference.
std::vector<std::pair<int, int>> all_pairs_within(const double* x, int count, int dim,
                                                  double radius);

}  // namespace springlab
