#include "integrators/fast/vertex_colouring.h"

#include <algorithm>

namespace springlab {

VertexColouring colour_vertices(const SparseMatrix& pattern, int dim, int particles) {
  VertexColouring out;
  out.colour.assign(static_cast<std::size_t>(particles), -1);
  std::vector<int> taken;  // taken[c] == p: colour c is a neighbour's of particle p
  for (int p = 0; p < particles; ++p) {
    // The neighbours are the rows of particle p's first column.
    const Eigen::Index column = static_cast<Eigen::Index>(p) * dim;
    for (SparseMatrix::InnerIterator it(pattern, column); it; ++it) {
      const Eigen::Index q = it.row() / dim;
      if (q == p || q >= particles) continue;
      const int c = out.colour[static_cast<std::size_t>(q)];
      if (c < 0) continue;
      if (static_cast<std::size_t>(c) >= taken.size()) taken.resize(static_cast<std::size_t>(c) + 1, -1);
      taken[static_cast<std::size_t>(c)] = p;
    }
    int c = 0;
    while (static_cast<std::size_t>(c) < taken.size() && taken[static_cast<std::size_t>(c)] == p) ++c;
    out.colour[static_cast<std::size_t>(p)] = c;
    if (static_cast<std::size_t>(c) >= out.members.size()) out.members.resize(static_cast<std::size_t>(c) + 1);
    out.members[static_cast<std::size_t>(c)].push_back(p);
  }
  return out;
}

}  // namespace springlab
