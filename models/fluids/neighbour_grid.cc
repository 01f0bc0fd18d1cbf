#include "models/fluids/neighbour_grid.h"

#include <cmath>

namespace springlab {

std::size_t NeighbourGrid::bucket(std::int64_t cx, std::int64_t cy, std::int64_t cz) const {
  // Teschner et al. (2003): three large primes, XOR-ed.
  const std::uint64_t h = (static_cast<std::uint64_t>(cx) * 73856093u) ^
                          (static_cast<std::uint64_t>(cy) * 19349663u) ^
                          (static_cast<std::uint64_t>(cz) * 83492791u);
  return static_cast<std::size_t>(h) & mask_;
}

void NeighbourGrid::build(const double* x, int count, int dim, double radius) {
  const std::size_t n = static_cast<std::size_t>(count);
  const std::size_t pairs_before = pairs_.size();
  pairs_.clear();
  pairs_.reserve(pairs_before);
  first_.assign(n + 1, 0);
  cell_.assign(3 * n, 0);
  std::size_t table = 16;
  while (table < 2 * n) table *= 2;
  mask_ = table - 1;
  // A point that is not finite, or so far out that its cell does not fit
  // in 62 bits, gets no cell (no partners).
  constexpr double kFar = 4e18;
  std::vector<char>& binned = binned_;
  binned.assign(n, 1);
  for (std::size_t p = 0; p < n; ++p) {
    for (int r = 0; r < dim; ++r) {
      const double c = std::floor(x[p * dim + r] / radius);
      if (!(std::abs(c) < kFar)) {
        binned[p] = 0;
        break;
      }
      cell_[3 * p + r] = static_cast<std::int64_t>(c);
    }
  }
  // Counting sort of the points by bucket.
  bucket_start_.assign(table + 1, 0);
  std::vector<std::size_t>& of = of_;
  of.assign(n, 0);
  for (std::size_t p = 0; p < n; ++p) {
    if (!binned[p]) continue;
    of[p] = bucket(cell_[3 * p], cell_[3 * p + 1], cell_[3 * p + 2]);
    ++bucket_start_[of[p] + 1];
  }
  for (std::size_t b = 0; b < table; ++b) bucket_start_[b + 1] += bucket_start_[b];
  order_.assign(static_cast<std::size_t>(bucket_start_[table]), 0);
  std::vector<int>& fill = fill_;
  fill.assign(bucket_start_.begin(), bucket_start_.end() - 1);
  for (std::size_t p = 0; p < n; ++p) {
    if (binned[p]) order_[static_cast<std::size_t>(fill[of[p]]++)] = static_cast<int>(p);
  }

  const double r2 = radius * radius;
  const int reach_z = dim == 3 ? 1 : 0;
  for (std::size_t i = 0; i < n; ++i) {
    first_[i] = static_cast<int>(pairs_.size());
    if (!binned[i]) continue;
    const std::int64_t* ci = &cell_[3 * i];
    for (int dz = -reach_z; dz <= reach_z; ++dz) {
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
          const std::int64_t cx = ci[0] + dx, cy = ci[1] + dy, cz = ci[2] + dz;
          const std::size_t b = bucket(cx, cy, cz);
          for (int k = bucket_start_[b]; k < bucket_start_[b + 1]; ++k) {
            const std::size_t j = static_cast<std::size_t>(order_[static_cast<std::size_t>(k)]);
            if (j <= i) continue;
            const std::int64_t* cj = &cell_[3 * j];
            if (cj[0] != cx || cj[1] != cy || cj[2] != cz) continue;  // another cell's bucket
            double d2 = 0.0;
            for (int r = 0; r < dim; ++r) {
              const double d = x[i * dim + r] - x[j * dim + r];
              d2 += d * d;
            }
            if (d2 < r2) pairs_.emplace_back(static_cast<int>(i), static_cast<int>(j));
          }
        }
      }
    }
  }
  first_[n] = static_cast<int>(pairs_.size());
}

std::vector<std::pair<int, int>> all_pairs_within(const double* x, int count, int dim,
                                                  double radius) {
  std::vector<std::pair<int, int>> pairs;
  for (int i = 0; i < count; ++i) {
    for (int j = i + 1; j < count; ++j) {
      double d2 = 0.0;
      for (int r = 0; r < dim; ++r) {
        const double d = x[i * dim + r] - x[j * dim + r];
        d2 += d * d;
      }
      if (d2 < radius * radius) pairs.emplace_back(i, j);
    }
  }
  return pairs;
}

}  // namespace springlab
