#include "models/core/force_term.h"

#include <algorithm>
#include <stdexcept>

namespace springlab {

BlockSlot find_block_slot(const SparseMatrix& pattern, int dim, int a, int b) {
  BlockSlot slot;
  const int* outer = pattern.outerIndexPtr();
  const int* inner = pattern.innerIndexPtr();
  // A pattern of whole blocks (Model::build_pattern) has the same
  // rows in every column of a block column: the first column's search
  // places the block in the others too, where one comparison confirms it
  // (and a search runs only where it does not).
  int rank = -1;  // the block's first row's place within its column
  for (int c = 0; c < dim; ++c) {
    const int col = b * dim + c;
    const int* begin = inner + outer[col];
    const int* end = inner + outer[col + 1];
    const int* hit = rank >= 0 && rank < end - begin && begin[rank] == a * dim
                         ? begin + rank
                         : std::lower_bound(begin, end, a * dim);
    if (hit == end || *hit != a * dim) {
      throw std::logic_error("find_block_slot: block not in the Jacobian pattern");
    }
    rank = static_cast<int>(hit - begin);
    slot.offset[c] = static_cast<int>(hit - inner);
  }
  return slot;
}

void declare_pair_blocks(JacobianPatternBuilder& builder, int a, int b, int free_particles) {
  if (a < free_particles && b < free_particles) {
    builder.add_block(a, b);
    builder.add_block(b, a);
  }
}

PairSlots find_pair_slots(const SparseMatrix& pattern, int dim, int a, int b, int free_particles) {
  PairSlots slots;
  if (a < free_particles) slots.aa = find_block_slot(pattern, dim, a, a);
  if (b < free_particles) slots.bb = find_block_slot(pattern, dim, b, b);
  if (a < free_particles && b < free_particles) {
    slots.ab = find_block_slot(pattern, dim, a, b);
    slots.ba = find_block_slot(pattern, dim, b, a);
  }
  return slots;
}

std::vector<int> diagonal_slots(const SparseMatrix& pattern) {
  std::vector<int> slots(static_cast<std::size_t>(pattern.rows()));
  for (int k = 0; k < pattern.rows(); ++k) {
    const int* begin = pattern.innerIndexPtr() + pattern.outerIndexPtr()[k];
    const int* end = pattern.innerIndexPtr() + pattern.outerIndexPtr()[k + 1];
    const int* hit = std::lower_bound(begin, end, k);
    if (hit == end || *hit != k) throw std::logic_error("diagonal_slots: missing diagonal entry");
    slots[static_cast<std::size_t>(k)] = static_cast<int>(hit - pattern.innerIndexPtr());
  }
  return slots;
}

}  // namespace springlab
