#include "experiments/kinds/definition.h"

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "experiments/driver/memory_check.h"
#include "experiments/io/output_files.h"
#include "integrators/registry/registry.h"
#include "models/scenes/builtin_scenes.h"
#include "models/model/scene_file.h"

namespace springlab {

DefinitionObject::DefinitionObject(const nlohmann::json& json, std::string file, std::string path)
    : json_(json), file_(std::move(file)), path_(std::move(path)) {
  if (!json_.is_object()) {
    throw DefinitionError(file_ + ": " + (path_.empty() ? "top level" : path_) +
                          ": expected an object");
  }
}

std::string DefinitionObject::where(const std::string& key) const {
  return file_ + ": " + (path_.empty() ? key : path_ + "." + key);
}

void DefinitionObject::fail(const std::string& key, const std::string& problem) const {
  throw DefinitionError(where(key) + ": " + problem);
}

void DefinitionObject::allow_only(std::initializer_list<const char*> keys) const {
  for (const auto& [key, value] : json_.items()) {
    bool known = false;
    for (const char* k : keys) known = known || key == k;
    if (!known) {
      std::string list;
      for (const char* k : keys) list += (list.empty() ? "" : ", ") + std::string(k);
      throw DefinitionError(file_ + ": " + (path_.empty() ? "" : path_ + ": ") + "unknown key '" +
                            printable(key) + "' (allowed: " + list + ")");
    }
  }
}

double DefinitionObject::number(const char* key) const {
  if (!has(key)) fail(key, "missing");
  const nlohmann::json& v = json_.at(key);
  if (!v.is_number()) fail(key, std::string("expected a number, got ") + v.type_name());
  const double x = v.get<double>();
  if (!std::isfinite(x)) fail(key, "must be a finite number");
  return x;
}

double DefinitionObject::number(const char* key, double fallback) const {
  return has(key) ? number(key) : fallback;
}

double DefinitionObject::positive(const char* key) const {
  const double x = number(key);
  if (!(x > 0.0)) fail(key, "must be > 0 (got " + format_number(x) + ")");
  return x;
}

double DefinitionObject::positive(const char* key, double fallback) const {
  return has(key) ? positive(key) : fallback;
}

int DefinitionObject::count(const char* key, int fallback, int min, int max) const {
  if (!has(key)) return fallback;
  const double x = number(key);
  if (x != std::floor(x) || x < min || x > max) {
    fail(key, "must be a whole number in [" + std::to_string(min) + ", " + std::to_string(max) +
                  "] (got " + format_number(x) + ")");
  }
  return static_cast<int>(x);
}

std::string DefinitionObject::string(const char* key) const {
  if (!has(key)) fail(key, "missing");
  const nlohmann::json& v = json_.at(key);
  if (!v.is_string()) fail(key, std::string("expected a string, got ") + v.type_name());
  return v.get<std::string>();
}

std::string DefinitionObject::string(const char* key, const std::string& fallback) const {
  return has(key) ? string(key) : fallback;
}

std::vector<double> DefinitionObject::positives(const char* key) const {
  if (!has(key)) fail(key, "missing");
  const nlohmann::json& v = json_.at(key);
  if (!v.is_array() || v.empty()) fail(key, "expected a non-empty array of numbers");
  if (v.size() > 10000) fail(key, "more than 10000 values");
  std::vector<double> out;
  for (std::size_t k = 0; k < v.size(); ++k) {
    const std::string item = std::string(key) + "[" + std::to_string(k) + "]";
    if (!v[k].is_number()) fail(item, std::string("expected a number, got ") + v[k].type_name());
    const double x = v[k].get<double>();
    if (!std::isfinite(x) || !(x > 0.0)) fail(item, "must be a finite number > 0");
    out.push_back(x);
  }
  return out;
}

DefinitionObject DefinitionObject::object(const char* key) const {
  if (!has(key)) fail(key, "missing");
  if (!json_.at(key).is_object()) fail(key, "expected an object");
  return DefinitionObject(json_.at(key), file_, path_.empty() ? key : path_ + "." + key);
}

std::vector<DefinitionObject> DefinitionObject::objects(const char* key) const {
  if (!has(key)) fail(key, "missing");
  const nlohmann::json& v = json_.at(key);
  if (!v.is_array() || v.empty()) fail(key, "expected a non-empty array of objects");
  std::vector<DefinitionObject> out;
  for (std::size_t k = 0; k < v.size(); ++k) {
    const std::string item = (path_.empty() ? "" : path_ + ".") + key + "[" + std::to_string(k) + "]";
    out.emplace_back(v[k], file_, item);
  }
  return out;
}

std::vector<std::pair<std::string, std::string>> definition_parameters(const DefinitionObject& o) {
  std::vector<std::pair<std::string, std::string>> pairs;
  if (!o.has("parameters")) return pairs;
  const DefinitionObject p = o.object("parameters");
  for (const auto& [key, value] : p.json().items()) {
    if (value.is_number()) {
      pairs.emplace_back(key, format_number(value.get<double>()));
    } else if (value.is_string()) {
      pairs.emplace_back(key, value.get<std::string>());
    } else {
      p.fail(key, "expected a number or a string");
    }
  }
  return pairs;
}

Scene definition_scene(const DefinitionObject& o,
                       const std::vector<std::pair<std::string, std::string>>& overrides) {
  const std::string name = o.string("scene");
  auto parameters = definition_parameters(o);
  for (const auto& [key, value] : overrides) {
    for (const auto& given : parameters) {
      if (given.first == key) {
        o.fail("parameters", std::string("'").append(printable(key)).append("' is the parameter the sweep sets: leave it out"));
      }
    }
  }
  parameters.insert(parameters.end(), overrides.begin(), overrides.end());
  // A scene whose model would not fit is refused at load (memory_check.h).
  auto fitting = [&](Scene scene, const char* key) {
    try {
      check_scene_memory(scene, "scene '" + printable(name) + "'");
    } catch (const MemoryRefused& e) {
      o.fail(key, e.what());
    }
    return scene;
  };
  if (is_builtin_scene(name)) {
    Scene scene;
    try {
      scene = make_builtin_scene(name, parameters);
    } catch (const SceneError& e) {
      o.fail("parameters", e.what());
    }
    return fitting(std::move(scene), "parameters");
  }
  if (!parameters.empty()) o.fail("parameters", "apply to built-in scenes only");
  const std::filesystem::path base = std::filesystem::path(o.file()).parent_path();
  const std::filesystem::path path = base / name;
  std::error_code ec;  // a name too long for the file system is "not a file", not an exception
  if (!std::filesystem::is_regular_file(path, ec)) {
    o.fail("scene", std::string("'").append(printable(name)).append(
                        "' is neither a built-in scene nor a file next to the definition"));
  }
  Scene scene;
  try {
    scene = load_scene_file(path.string());
  } catch (const SceneError& e) {
    o.fail("scene", e.what());  // the definition's file and key, then the scene's
  }
  return fitting(std::move(scene), "scene");
}

std::string definition_integrator(const DefinitionObject& o, const char* key) {
  const std::string name = o.string(key);
  if (!is_integrator(name)) o.fail(key, integrator_registry().unknown("integrator", printable(name)));
  return name;
}

std::vector<std::string> definition_integrators(const DefinitionObject& o, const char* key,
                                                const std::string& fallback) {
  std::vector<std::string> names;
  const nlohmann::json choice = o.has(key) ? o.raw(key) : nlohmann::json(fallback);
  if (choice.is_string()) {
    const std::string which = choice.get<std::string>();
    if (which != "all" && which != "fixed-step" && which != "adaptive") {
      o.fail(key, "expected \"all\", \"fixed-step\", \"adaptive\" or a list of names");
    }
    for (const std::string& name : integrator_names()) {
      const bool adaptive = make_integrator(name)->info().adaptive;
      if (which == "all" || adaptive == (which == "adaptive")) names.push_back(name);
    }
    return names;
  }
  if (!choice.is_array() || choice.empty()) o.fail(key, "expected a name group or a list of names");
  for (const auto& item : choice) {
    if (!item.is_string()) o.fail(key, "expected integrator names");
    const std::string name = item.get<std::string>();
    if (!is_integrator(name)) {
      o.fail(key, integrator_registry().unknown("integrator", printable(name)));
    }
    if (std::find(names.begin(), names.end(), name) != names.end()) {
      o.fail(key, "'" + name + "' is listed twice");
    }
    names.push_back(name);
  }
  return names;
}

}  // namespace springlab
