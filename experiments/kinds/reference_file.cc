#include "experiments/kinds/reference_file.h"

#include <filesystem>
#include <fstream>

namespace springlab {

ReferenceLines read_reference_lines(const DefinitionObject& d) {
  ReferenceLines r;
  r.file = d.string("reference");
  const std::filesystem::path path = std::filesystem::path(d.file()).parent_path() / r.file;
  std::ifstream in(path);
  if (!in) d.fail("reference", "cannot read '" + r.file + "' next to the definition");
  std::string line;
  int number = 0;
  while (std::getline(in, line)) {
    ++number;
    if (line.empty()) continue;
    if (line[0] == '#') {
      const std::size_t start = line.find_first_not_of("# ");
      if (start != std::string::npos) {
        if (!r.source.empty()) r.source.push_back(' ');
        r.source.append(line, start, std::string::npos);
      }
      continue;
    }
    r.lines.emplace_back(number, line);
  }
  return r;
}

}  // namespace springlab
