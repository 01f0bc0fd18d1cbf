// What a model of a scene will hold, estimated from the scene alone, before
// anything large is built (issue 46.5-7; docs/reliability.md "Memory known
// before it is spent"). Each element kind adds its own parts
// (ElementKind::memory): the bytes its term holds whatever the method, and
// the Jacobian blocks it declares, which only a method that assembles
// Jacobians pays for (Model builds its pattern only when asked). The
// model adds its own arrays; estimate_model_memory (models/model/
// model_memory.h) sums them all. The
// constants are peak resident bytes measured on built-in scenes (the .cc).
#pragma once

#include <string>
#include <vector>

namespace springlab {

struct MemoryPart {
  // The scene's words for what costs it: "400 bodies (159600 body pairs)".
  std::string what;
  double bytes = 0.0;  // held whatever the method
  // The dim x dim Jacobian blocks it declares, repeats counted (the pattern
  // builder holds each), and how many of them are distinct (the pattern's).
  double pattern_blocks = 0.0;
  double distinct_blocks = 0.0;
  double slot_bytes = 0.0;  // what its term keeps of the pattern, once built
};

struct MemoryEstimate {
  int dim = 3;
  std::vector<MemoryPart> parts;

  // Peak bytes of the model and a run's state, without or with the
  // Jacobian pattern (its build, and the copies a Newton method keeps).
  double bytes(bool jacobians) const;
  // The bytes of one part, likewise.
  double part_bytes(const MemoryPart& part, bool jacobians) const;
  // The part that weighs most (nullptr when there is none).
  const MemoryPart* largest(bool jacobians) const;
};

}  // namespace springlab
