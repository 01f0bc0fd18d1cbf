#pragma once

#include <string>
#include <utility>
#include <vector>

#include "experiments/kinds/definition.h"

namespace springlab {

// A measured reference a definition names under "reference": a CSV file
// next to the definition whose '#' lines say where the data come from.
struct ReferenceLines {
  std::string file;    // as the definition names it
  std::string source;  // the '#' lines, joined by spaces
  // The other non-empty lines with their line numbers (1-based), for the
  // caller's own header and rows.
  std::vector<std::pair<int, std::string>> lines;
};

// Reads d's "reference" file; a file that cannot be read fails d.
ReferenceLines read_reference_lines(const DefinitionObject& d);

}  // namespace springlab
