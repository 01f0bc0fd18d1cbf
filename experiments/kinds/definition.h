// Reading experiment definition files (experiments/*.json) with messages
// that name the file and the element, like scene files: unknown keys are
// errors, so a typo cannot silently fall back to a default.
#pragma once

#include <initializer_list>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <vector>

#include "models/core/scene.h"

namespace springlab {

class DefinitionError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// One JSON object of a definition, with its path for messages.
class DefinitionObject {
 public:
  DefinitionObject(const nlohmann::json& json, std::string file, std::string path);

  bool has(const char* key) const { return json_.contains(key); }
  double number(const char* key) const;
  double number(const char* key, double fallback) const;
  double positive(const char* key) const;
  double positive(const char* key, double fallback) const;
  int count(const char* key, int fallback, int min, int max) const;
  std::string string(const char* key) const;
  std::string string(const char* key, const std::string& fallback) const;
  std::vector<double> positives(const char* key) const;  // non-empty array of numbers > 0
  DefinitionObject object(const char* key) const;
  std::vector<DefinitionObject> objects(const char* key) const;  // non-empty array of objects
  const nlohmann::json& raw(const char* key) const { return json_.at(key); }
  const nlohmann::json& json() const { return json_; }

  // Refuses any key not listed.
  void allow_only(std::initializer_list<const char*> keys) const;
  [[noreturn]] void fail(const std::string& key, const std::string& problem) const;

  const std::string& file() const { return file_; }

 private:
  std::string where(const std::string& key) const;
  const nlohmann::json& json_;
  std::string file_, path_;
};

// A scene named in a definition: {"scene": NAME or PATH, "parameters": {...}}
// (a path is relative to the definition's folder). `overrides` are extra
// built-in parameters (e.g. a stiffness sweep's k).
Scene definition_scene(const DefinitionObject& o,
                       const std::vector<std::pair<std::string, std::string>>& overrides = {});
// The built-in parameters of a case, as `-p` pairs.
std::vector<std::pair<std::string, std::string>> definition_parameters(const DefinitionObject& o);

// One registered integrator's name at `key` (refused: "unknown integrator").
std::string definition_integrator(const DefinitionObject& o, const char* key);

// "all", "fixed-step", "adaptive" or a list of registry names.
std::vector<std::string> definition_integrators(const DefinitionObject& o, const char* key,
                                                const std::string& fallback);

}  // namespace springlab
