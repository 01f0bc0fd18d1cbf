#include "experiments/experiment.h"

#include <fstream>
#include <sstream>

#include "experiments/experiment_support.h"
#include "experiments/output_files.h"

namespace springlab {

Row& Row::add(const std::string& text) {
  if (!text_.empty()) text_ += ',';
  // Names here never contain commas or quotes, but a scene file's name might.
  if (text.find_first_of(",\"\n") != std::string::npos) {
    text_ += '"';
    for (char c : text) text_ += c == '"' ? std::string("\"\"") : std::string(1, c);
    text_ += '"';
  } else {
    text_ += text;
  }
  return *this;
}

Row& Row::add(double value) {
  if (!text_.empty()) text_ += ',';
  text_ += format_number(value);
  return *this;
}

Row& Row::add(long value) {
  if (!text_.empty()) text_ += ',';
  text_ += std::to_string(value);
  return *this;
}

Row& Row::raw(const std::string& csv_fields) {
  if (!text_.empty()) text_ += ',';
  text_ += csv_fields;
  return *this;
}

Row& Row::add_empty() {
  text_ += ',';
  return *this;
}

LoadedExperiment parse_experiment(const std::string& json_text, const std::string& source) {
  nlohmann::json json;
  try {
    json = nlohmann::json::parse(json_text);
  } catch (const nlohmann::json::exception& e) {
    // parse_error, or out_of_range 406 for a number beyond a double (1e999).
    std::string what = e.what();
    const auto bracket = what.find("] ");
    if (bracket != std::string::npos) what = what.substr(bracket + 2);
    throw DefinitionError(source + ": malformed JSON: " + what);
  }
  const DefinitionObject top(json, source, "");
  const std::string kind = top.string("experiment");
  for (const ExperimentKind& k : experiment_kinds()) {
    if (kind != k.name) continue;
    LoadedExperiment loaded;
    loaded.name = top.string("name", kind);
    if (loaded.name.empty() || loaded.name.find_first_of("/\\") != std::string::npos ||
        loaded.name[0] == '.') {
      top.fail("name", "must be a plain file name");
    }
    top.string("title", "");  // both optional, but text when given
    top.string("description", "");
    loaded.experiment = k.make(top);
    // Each kind refuses its own large sweeps while reading; this is the net.
    if (loaded.experiment->task_count() > kMaxExperimentTasks) {
      throw DefinitionError(source + ": the experiment would have " +
                            std::to_string(loaded.experiment->task_count()) +
                            " tasks, over the cap of " + std::to_string(kMaxExperimentTasks));
    }
    loaded.definition = json;
    return loaded;
  }
  std::string kinds;
  for (const ExperimentKind& k : experiment_kinds()) kinds += (kinds.empty() ? "" : ", ") + std::string(k.name);
  top.fail("experiment", "unknown kind '" + kind + "' (kinds: " + kinds + ")");
}

LoadedExperiment load_experiment(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw DefinitionError(path + ": cannot open file");
  std::stringstream text;
  text << in.rdbuf();
  return parse_experiment(text.str(), path);
}

}  // namespace springlab
