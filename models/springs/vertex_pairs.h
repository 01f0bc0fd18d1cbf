// The pairs (springs, dampers) around each free particle, for vertex block
// descent's per-particle forces (models/vertex_blocks.h): a compressed
// adjacency, particle p's entries at [first[p], first[p + 1]), each the
// pair's index and its other end (an internal particle index, free or
// fixed). The pairs are listed in the order given, so a particle sums its
// pairs' forces in that order.
#pragma once

#include <utility>
#include <vector>

namespace springlab {

struct VertexPairs {
  struct Entry {
    int pair;   // index into the pairs given
    int other;  // the pair's other end
  };
  std::vector<int> first;  // free particles + 1 offsets
  std::vector<Entry> entries;
};

// ends[n] = (a, b) of pair n, internal indices; only free ends get entries.
inline VertexPairs vertex_pairs(const std::vector<std::pair<int, int>>& ends,
                                int free_particles) {
  VertexPairs out;
  out.first.assign(static_cast<std::size_t>(free_particles) + 1, 0);
  for (const auto& [a, b] : ends) {
    if (a < free_particles) ++out.first[static_cast<std::size_t>(a) + 1];
    if (b < free_particles) ++out.first[static_cast<std::size_t>(b) + 1];
  }
  for (std::size_t p = 0; p < static_cast<std::size_t>(free_particles); ++p) {
    out.first[p + 1] += out.first[p];
  }
  out.entries.resize(static_cast<std::size_t>(out.first.back()));
  std::vector<int> next(out.first.begin(), out.first.end() - 1);
  for (std::size_t n = 0; n < ends.size(); ++n) {
    const auto [a, b] = ends[n];
    if (a < free_particles) {
      out.entries[static_cast<std::size_t>(next[static_cast<std::size_t>(a)]++)] = {static_cast<int>(n), b};
    }
    if (b < free_particles) {
      out.entries[static_cast<std::size_t>(next[static_cast<std::size_t>(b)]++)] = {static_cast<int>(n), a};
    }
  }
  return out;
}

}  // namespace springlab
