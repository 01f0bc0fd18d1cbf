// Why a model cannot give a method the form it asks for, as data (issue 47
// item 4): the sentence for the user and, where one exists, the scene
// setting that would make the pairing work. The command line, Python and the
// browser lab print from these fields; none of them reads the sentence's
// words to decide anything.
#pragma once

#include <string>

namespace springlab {

// A scene setting and the value that would make a refused pairing work:
// {"model", "corotated"} (a material's model), {"contact", "0", "penalty"}. A built-in scene with a parameter of that
// name is told `-p field=value`.
struct SceneRemedy {
  std::string field;
  std::string value;
  std::string meaning;  // shown after the value ("penalty"), or ""
  bool empty() const { return field.empty(); }
};

struct Refusal {
  std::string text;  // one sentence for the user, saying what to use instead
  SceneRemedy remedy;
};

}  // namespace springlab
