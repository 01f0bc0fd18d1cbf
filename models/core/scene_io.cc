#include "models/core/scene_io.h"

#include <algorithm>
#include <cmath>

#include "models/core/decimal_text.h"
#include "models/core/registry.h"  // did_you_mean

namespace springlab {
namespace {

std::string join(const std::vector<std::string>& names) {
  std::string out;
  for (const std::string& name : names) out += (out.empty() ? "" : ", ") + name;
  return out;
}

std::string type_of(const Json& j) { return j.type_name(); }

}  // namespace

std::string shortest_text(double value) { return shortest_decimal(value); }

std::string element(const std::string& array, std::size_t index) {
  return array + "[" + std::to_string(index) + "]";
}

std::string field(const std::string& where, const std::string& key) {
  return where.empty() ? key : where + "." + key;
}

void Reporter::fail(const std::string& where, const std::string& problem) const {
  throw SceneError(source_ + ": " + (where.empty() ? "" : where + ": ") + problem);
}

void check_finite(const Reporter& r, const std::string& where, double value) {
  if (!std::isfinite(value)) r.fail(where, "must be a finite number");
}

void check_nonnegative(const Reporter& r, const std::string& where, double value) {
  check_finite(r, where, value);
  if (value < 0) r.fail(where, "must be >= 0 (got " + shortest_text(value) + ")");
}

void check_positive(const Reporter& r, const std::string& where, double value) {
  check_finite(r, where, value);
  if (value <= 0) r.fail(where, "must be > 0 (got " + shortest_text(value) + ")");
}

void check_vector(const Reporter& r, const std::string& where, const Eigen::Vector3d& v,
                  int dimension) {
  for (int k = 0; k < 3; ++k) {
    const std::string at = element(where, static_cast<std::size_t>(k));
    if (k < dimension) {
      check_finite(r, at, v[k]);
    } else if (v[k] != 0) {
      r.fail(at, "must be 0 in a " + std::to_string(dimension) + "-D scene");
    }
  }
}

int check_particle_index(const Reporter& r, const std::string& element, const char* key,
                         double index, std::size_t particle_count) {
  const std::string where = element + "." + key;
  check_finite(r, where, index);
  if (index != std::floor(index)) {
    r.fail(where, "must be a whole number (got " + shortest_text(index) + ")");
  }
  if (index < 0 || index >= static_cast<double>(particle_count)) {
    r.fail(element, "particle " + shortest_text(index) + " does not exist (scene has " +
                        std::to_string(particle_count) +
                        (particle_count == 1 ? " particle)" : " particles)"));
  }
  return static_cast<int>(index);
}

void require_object(const Reporter& r, const std::string& where, const Json& j) {
  if (!j.is_object())
    r.fail(where.empty() ? "top level" : where, "expected an object, got " + type_of(j));
}

void require_array(const Reporter& r, const std::string& where, const Json& j) {
  if (!j.is_array()) r.fail(where, "expected an array, got " + type_of(j));
}

void check_keys(const Reporter& r, const std::string& where, const Json& object,
                const std::vector<std::string>& allowed, const std::vector<std::string>& required) {
  for (const auto& item : object.items()) {
    if (std::find(allowed.begin(), allowed.end(), item.key()) == allowed.end()) {
      r.fail(where, "unknown key '" + printable(item.key()) + "'" +
                        did_you_mean(item.key(), allowed) + " (allowed keys: " + join(allowed) +
                        ")");
    }
  }
  for (const std::string& name : required) {
    if (!object.contains(name)) r.fail(where, "missing required key '" + name + "'");
  }
}

void check_keys(const Reporter& r, const std::string& where, const Json& object,
                std::initializer_list<const char*> allowed,
                std::initializer_list<const char*> required) {
  check_keys(r, where, object, std::vector<std::string>(allowed.begin(), allowed.end()),
             std::vector<std::string>(required.begin(), required.end()));
}

double read_number(const Reporter& r, const std::string& where, const Json& j) {
  if (!j.is_number()) r.fail(where, "expected a number, got " + type_of(j));
  return j.get<double>();
}

bool read_bool(const Reporter& r, const std::string& where, const Json& j) {
  if (!j.is_boolean()) r.fail(where, "expected true or false, got " + type_of(j));
  return j.get<bool>();
}

Eigen::Vector3d read_vector(const Reporter& r, const std::string& where, const Json& j,
                            int dimension) {
  const std::string d = std::to_string(dimension);
  if (!j.is_array()) r.fail(where, "expected an array of " + d + " numbers, got " + type_of(j));
  if (j.size() != static_cast<std::size_t>(dimension)) {
    r.fail(where,
           "expected " + d + " numbers (dimension is " + d + "), got " + std::to_string(j.size()));
  }
  Eigen::Vector3d v = Eigen::Vector3d::Zero();
  for (int k = 0; k < dimension; ++k) {
    const std::string at = element(where, static_cast<std::size_t>(k));
    v[k] = read_number(r, at, j[static_cast<std::size_t>(k)]);
    check_finite(r, at, v[k]);
  }
  return v;
}

std::string json_number(double value) {
  if (!std::isfinite(value)) return "null";
  std::string text = shortest_text(value);
  if (text.find_first_of(".e") == std::string::npos) text += ".0";
  return text;
}

std::string json_vector(const Eigen::Vector3d& v, int dimension) {
  std::string out = "[";
  for (int k = 0; k < dimension; ++k) out += (k ? ", " : "") + json_number(v[k]);
  return out + "]";
}

std::string json_string(const std::string& text) {
  return Json(text).dump(-1, ' ', false, Json::error_handler_t::replace);
}

void JsonLines::add(const std::string& item) {
  text_ += (empty_ ? "\n    " : ",\n    ") + item;
  empty_ = false;
}

}  // namespace springlab
