// What the scene's data needs of the JSON text it is read from
// (scene.h): the checks before parsing, and names as the user typed them.
// Reading, checking and writing whole scene files is the registry's
// (models/model/scene_file.h), since it walks every element kind.
#include "models/core/scene.h"

#include "models/core/scene_io.h"

namespace springlab {

std::optional<std::string> json_text_problem(const std::string& text) {
  auto white = [](char c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r'; };
  bool in_string = false, escaped = false;
  std::size_t line = 1, column = 0, run = 0;
  auto at = [&] { return " at line " + std::to_string(line) + ", column " + std::to_string(column); };
  for (const char c : text) {
    ++column;
    if (c == '\0') return "malformed JSON: a NUL byte" + at() + " (JSON text cannot hold one)";
    if (c == '\n') {
      ++line;
      column = 0;
    }
    if (in_string) {
      if (escaped) {
        escaped = false;
      } else if (c == '\\') {
        escaped = true;
      } else if (c == '"') {
        in_string = false;
      }
    } else if (white(c)) {
      if (++run > kMaxJsonWhitespaceRun) {
        return "more than " + std::to_string(kMaxJsonWhitespaceRun) +
               " whitespace characters in a row, up to line " + std::to_string(line) +
               ", over the cap for a JSON file";
      }
    } else {
      run = 0;
      in_string = c == '"';
    }
  }
  return std::nullopt;
}

std::string printable(const std::string& text) {
  constexpr std::size_t kShown = 100;
  const std::string shown = text.size() > kShown ? text.substr(0, kShown) : text;
  const std::string quoted = Json(shown).dump(-1, ' ', false, Json::error_handler_t::replace);
  std::string out = quoted.substr(1, quoted.size() - 2);
  if (text.size() > kShown) out += "... (" + std::to_string(text.size()) + " bytes)";
  return out;
}

}  // namespace springlab
