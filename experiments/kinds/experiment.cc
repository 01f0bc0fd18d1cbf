#include "experiments/kinds/experiment.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "experiments/kinds/definition_methods.h"
#include "experiments/kinds/experiment_support.h"
#include "experiments/io/output_files.h"
#include "models/core/strict_json.h"
#include "models/core/registry.h"

namespace springlab {

Row& Row::add(const std::string& text) {
  separate();
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
  // A value that was not measured (NaN: a run that failed, a column that does
  // not apply) is an empty field, as experiments/README.md says.
  if (std::isnan(value)) return add_empty();
  separate();
  text_ += format_number(value);
  return *this;
}

Row& Row::add(long value) {
  separate();
  text_ += std::to_string(value);
  return *this;
}

Row& Row::raw(const std::string& csv_fields) {
  separate();
  text_ += csv_fields;
  return *this;
}

Row& Row::add_empty() {
  separate();
  return *this;
}

LoadedExperiment parse_experiment(const std::string& json_text, const std::string& source) {
  if (json_text.size() > kMaxDefinitionBytes) {
    throw DefinitionError(source + ": " + std::to_string(json_text.size()) +
                          " bytes, over the cap of " + std::to_string(kMaxDefinitionBytes) +
                          " bytes for an experiment definition");
  }
  if (const std::optional<std::string> problem = json_text_problem(json_text)) {
    throw DefinitionError(source + ": " + *problem);
  }
  // The strict reader refuses a key given twice in one object (the library
  // would keep the last one silently), naming the object: cases[0].scene.
  StrictJsonPolicy policy;
  policy.fail = [&source](const std::string& path, const std::string& message) {
    throw DefinitionError(source + ": " + (path.empty() ? "" : path + ": ") + message);
  };
  // Scenes' nesting cap (issue 46.12: 16 MiB of '[' took 25 s and 1.7 GB
  // to refuse); no definition needs more than a few levels.
  StrictJsonCaps caps;
  caps.max_nesting = kMaxSceneNesting;
  caps.kind = "definition";
  policy.caps = caps;
  const nlohmann::json json = parse_strict_json<nlohmann::json>(json_text, policy);
  // The methods it brings ("plugins", "python") are registered first; the
  // kind reads the rest.
  load_definition_methods(DefinitionObject(json, source, ""));
  nlohmann::json for_kind = json;
  if (for_kind.is_object()) {
    for_kind.erase("plugins");
    for_kind.erase("python");
  }
  const DefinitionObject top(for_kind, source, "");
  const std::string kind = top.string("experiment");
  for (const ExperimentKind* entry : experiment_kinds()) {
    const ExperimentKind& k = *entry;
    if (kind != k.name) continue;
    LoadedExperiment loaded;
    loaded.name = top.string("name", kind);
    // The name becomes file names (<name>-runs.shard-12-of-16.csv and its
    // temporary): a plain, short one, without control characters.
    const bool control = std::any_of(loaded.name.begin(), loaded.name.end(), [](char c) {
      return static_cast<unsigned char>(c) < 0x20 || c == 0x7f;
    });
    if (loaded.name.empty() || loaded.name.find_first_of("/\\") != std::string::npos ||
        loaded.name[0] == '.' || control) {
      top.fail("name", "must be a plain file name (no '/', no leading '.', no control characters)");
    }
    if (loaded.name.size() > kMaxExperimentNameLength) {
      top.fail("name", "longer than " + std::to_string(kMaxExperimentNameLength) +
                           " characters (it names the output files)");
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
  std::vector<std::string> names;
  for (const ExperimentKind* k : experiment_kinds()) {
    kinds += (kinds.empty() ? "" : ", ") + std::string(k->name);
    names.emplace_back(k->name);
  }
  top.fail("experiment", "unknown kind '" + printable(kind) + "'" + did_you_mean(kind, names) +
                             " (kinds: " + kinds + ")");
}

LoadedExperiment load_experiment(const std::string& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) throw DefinitionError(path + ": is a directory, not a file");
  errno = 0;
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    const int error = errno;
    throw DefinitionError(printable(path) + ": cannot open file" +
                          (error != 0 ? std::string(" (") + std::strerror(error) + ")" : std::string()));
  }
  // At most one byte past the cap is read, whatever the file (or pipe) holds.
  std::string text;
  char chunk[1 << 16];
  while (in && text.size() <= kMaxDefinitionBytes) {
    in.read(chunk, sizeof chunk);
    text.append(chunk, static_cast<std::size_t>(in.gcount()));
  }
  if (in.bad()) throw DefinitionError(path + ": cannot read file");
  return parse_experiment(text, path);
}

}  // namespace springlab
