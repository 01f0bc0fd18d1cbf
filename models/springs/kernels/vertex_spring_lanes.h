// Vertex block descent's exact blocks of 3-D springs (vertex_spring.h,
// add_vertex_spring, is the formula, one spring at a time), two springs at
// once in the lanes of a two-double vector.
#pragma once

#include "models/core/vertex_blocks.h"
#include "models/springs/vertex_spring.h"

namespace springlab {

// The blocks of particles[0 .. count-1] (3-D): particle p's springs are
// springs[vertex_first[p] .. vertex_first[p + 1] - 1].
void add_vertex_blocks_lanes3(const double* x, const int* particles, int count,
                              const int* vertex_first, const VertexSpring* springs,
                              const VertexBlocks& out);

}  // namespace springlab
