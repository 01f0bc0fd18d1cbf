#include "experiments/experiment.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "experiments/experiment_support.h"
#include "experiments/output_files.h"

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

namespace {

// Builds a definition's JSON through nlohmann's SAX interface, refusing a
// key given twice in one object (the library would keep the last one
// silently), with the element's path in the message. Paths are built only
// for a message, so deep nesting costs memory in proportion to the depth.
class DefinitionBuilder {
 public:
  DefinitionBuilder(nlohmann::json& root, const std::string& source) : root_(root), source_(source) {}

  bool null() { return add(nullptr); }
  bool boolean(bool value) { return add(value); }
  bool number_integer(nlohmann::json::number_integer_t value) { return add(value); }
  bool number_unsigned(nlohmann::json::number_unsigned_t value) { return add(value); }
  bool number_float(nlohmann::json::number_float_t value, const std::string&) { return add(value); }
  bool string(std::string& value) { return add(std::move(value)); }
  bool binary(nlohmann::json::binary_t& value) { return add(nlohmann::json::binary(std::move(value))); }
  bool start_object(std::size_t) { return open(nlohmann::json::object()); }
  bool start_array(std::size_t) { return open(nlohmann::json::array()); }
  bool end_object() { return close(); }
  bool end_array() { return close(); }

  bool key(std::string& key) {
    Frame& top = frames_.back();
    if (top.container->contains(key)) {
      const std::string where = path();
      throw DefinitionError(source_ + ": " + (where.empty() ? "" : where + ": ") + "duplicate key '" +
                            printable(key) + "'");
    }
    top.key = std::move(key);
    return true;
  }

  bool parse_error(std::size_t, const std::string&, const nlohmann::json::exception& e) {
    // parse_error, or out_of_range 406 for a number beyond a double (1e999).
    std::string what = e.what();
    const auto bracket = what.find("] ");
    if (bracket != std::string::npos) what = what.substr(bracket + 2);
    std::replace(what.begin(), what.end(), '\n', ' ');
    throw DefinitionError(source_ + ": malformed JSON: " + what);
  }

 private:
  struct Frame {
    nlohmann::json* container;
    std::string key;  // objects: the key of the value being read
  };

  // The path of the open container, as DefinitionObject writes it: cases[0].scene
  std::string path() const {
    std::string out;
    for (std::size_t k = 1; k < frames_.size(); ++k) {
      const Frame& parent = frames_[k - 1];
      if (parent.container->is_array()) {
        out += '[';
        out += std::to_string(parent.container->size() - 1);
        out += ']';
      } else {
        if (!out.empty()) out += '.';
        out += parent.key;
      }
    }
    return out;
  }

  nlohmann::json* insert(nlohmann::json&& value) {
    if (frames_.empty()) {
      root_ = std::move(value);
      return &root_;
    }
    Frame& top = frames_.back();
    if (top.container->is_array()) {
      top.container->push_back(std::move(value));
      return &top.container->back();
    }
    return &((*top.container)[top.key] = std::move(value));
  }
  bool add(nlohmann::json&& value) {
    insert(std::move(value));
    return true;
  }
  bool open(nlohmann::json&& container) {
    frames_.push_back({insert(std::move(container)), {}});
    return true;
  }
  bool close() {
    frames_.pop_back();
    return true;
  }

  nlohmann::json& root_;
  const std::string& source_;
  std::vector<Frame> frames_;
};

}  // namespace

LoadedExperiment parse_experiment(const std::string& json_text, const std::string& source) {
  if (json_text.size() > kMaxDefinitionBytes) {
    throw DefinitionError(source + ": " + std::to_string(json_text.size()) +
                          " bytes, over the cap of " + std::to_string(kMaxDefinitionBytes) +
                          " bytes for an experiment definition");
  }
  if (const std::optional<std::string> problem = json_text_problem(json_text)) {
    throw DefinitionError(source + ": " + *problem);
  }
  nlohmann::json json;
  DefinitionBuilder builder(json, source);
  nlohmann::json::sax_parse(json_text, &builder);  // every failure throws from the builder
  const DefinitionObject top(json, source, "");
  const std::string kind = top.string("experiment");
  for (const ExperimentKind& k : experiment_kinds()) {
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
  for (const ExperimentKind& k : experiment_kinds()) kinds += (kinds.empty() ? "" : ", ") + std::string(k.name);
  top.fail("experiment", "unknown kind '" + printable(kind) + "' (kinds: " + kinds + ")");
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
