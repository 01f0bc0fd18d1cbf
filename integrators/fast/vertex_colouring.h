// The graph colouring of vertex block descent (vbd.h; Chen, Macklin et al.
// 2024, sec. 3.9): particles that share no element (no block of the
// system's Jacobian pattern couples them) get the same colour, so the
// particles of one colour can be updated at once, each from the others'
// positions, and a Gauss-Seidel sweep goes colour by colour.
//
// Greedy, in particle order: each particle takes the smallest colour none
// of its already coloured neighbours has (Welsh and Powell 1967 without the
// sort by degree). At most one colour more than the largest number of
// neighbours; a grid cloth with bend springs (neighbours two apart) takes
// 9 or 10.
#pragma once

#include <vector>

#include "models/core/mechanical_system.h"

namespace springlab {

struct VertexColouring {
  std::vector<int> colour;                // per particle
  std::vector<std::vector<int>> members;  // per colour, its particles in increasing order
};

// The colouring of `particles` particles of `dim` unknowns each from the
// pattern's blocks (its first `particles * dim` rows and columns).
VertexColouring colour_vertices(const SparseMatrix& pattern, int dim, int particles);

}  // namespace springlab
