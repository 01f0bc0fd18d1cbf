// The toolbox for reading, checking and writing scene files (docs/physics.md "Scene files"), shared
// by models/model/scene_file.cc (the document, the particles) and every element kind's file
// (springs.cc, gravity_force.cc, ...): one wording for every message, so a
// problem reads the same whichever part of the scene it is in.
//
// Messages name the element as a path: "springs[3]", "wind.velocity[2]",
// "particles[1].mass". A check that fails throws SceneError with the whole
// line ("scene.json: springs[3]: particle 17 does not exist ...").
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <initializer_list>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "models/core/scene.h"

namespace springlab {

// ordered_json keeps the document's key order, so "the first unknown key" is
// the first one the user wrote.
using Json = nlohmann::ordered_json;

// Shortest text that reads back to the same double (for messages and files).
std::string shortest_text(double value);

// "springs" + 3 -> "springs[3]"; "wind" + "gust" -> "wind.gust".
std::string element(const std::string& array, std::size_t index);
std::string field(const std::string& where, const std::string& key);

// Throws the one-line SceneError "source: where: problem".
class Reporter {
 public:
  explicit Reporter(const std::string& source) : source_(source) {}
  [[noreturn]] void fail(const std::string& where, const std::string& problem) const;

 private:
  const std::string& source_;
};

// ---- Semantic checks, shared by reading and validate_scene. ----

void check_finite(const Reporter& r, const std::string& where, double value);
void check_nonnegative(const Reporter& r, const std::string& where, double value);
void check_positive(const Reporter& r, const std::string& where, double value);
// Components past `dimension` are not in the file; a built Scene keeps them 0.
void check_vector(const Reporter& r, const std::string& where, const Eigen::Vector3d& v,
                  int dimension);
// A particle index read as a double (so that a fractional or huge value from
// a file is reported, not truncated): whole and in [0, particle_count).
// `element` names the element ("springs[3]"), `key` its index key ("i").
int check_particle_index(const Reporter& r, const std::string& element, const char* key,
                         double index, std::size_t particle_count);

// ---- Reading JSON values. ----

// "expected an object, got array" (the top level is named "top level").
void require_object(const Reporter& r, const std::string& where, const Json& j);
void require_array(const Reporter& r, const std::string& where, const Json& j);
// Refuses the first key of `object` not in `allowed` (in the document's
// order), then the first key of `required` that is missing.
void check_keys(const Reporter& r, const std::string& where, const Json& object,
                const std::vector<std::string>& allowed, const std::vector<std::string>& required);
void check_keys(const Reporter& r, const std::string& where, const Json& object,
                std::initializer_list<const char*> allowed,
                std::initializer_list<const char*> required);
double read_number(const Reporter& r, const std::string& where, const Json& j);
bool read_bool(const Reporter& r, const std::string& where, const Json& j);
// `dimension` finite numbers; the components past it stay 0.
Eigen::Vector3d read_vector(const Reporter& r, const std::string& where, const Json& j,
                            int dimension);

// ---- Writing (scene_to_json): deterministic, shortest round-trip numbers. ----

// Like nlohmann's output: shortest round-trip text, ".0" on whole numbers.
std::string json_number(double value);
std::string json_vector(const Eigen::Vector3d& v, int dimension);
std::string json_string(const std::string& text);
// A JSON array with one item per line, indented under a top-level key:
// "[\n    item,\n    item\n  ]", or "[]" when empty. A scene file stays
// readable (and diffable) at thousands of elements.
class JsonLines {
 public:
  void add(const std::string& item);
  std::string str() const { return empty_ ? "[]" : text_ + "\n  ]"; }

 private:
  std::string text_ = "[";
  bool empty_ = true;
};

}  // namespace springlab
