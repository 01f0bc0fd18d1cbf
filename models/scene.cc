// Scene files (SPEC §3): parsing, validation and printing.
//
// parse_scene reads a document element by element and reports the first
// problem it meets. Every semantic rule (finite numbers, mass > 0, index
// exists, ...) lives in one check_* function that both parse_scene and
// validate_scene call, so a built-in scene and a file get the same message.
#include "models/scene.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <nlohmann/json.hpp>
#include <unordered_set>
#include <utility>

namespace springlab {
namespace {

// ordered_json keeps the document's key order, so "the first unknown key" is
// the first one the user wrote.
using Json = nlohmann::ordered_json;

// Shortest text that reads back to the same double (for messages and files).
std::string format_number(double value) {
  char buffer[64];
  const auto result = std::to_chars(buffer, buffer + sizeof buffer, value);
  return std::string(buffer, result.ptr);
}

std::string element(const std::string& array, std::size_t index) {
  return array + "[" + std::to_string(index) + "]";
}

std::string field(const std::string& where, const std::string& key) {
  return where.empty() ? key : where + "." + key;
}

std::string join(std::initializer_list<const char*> names) {
  std::string out;
  for (const char* name : names) out += (out.empty() ? "" : ", ") + std::string(name);
  return out;
}

class Reporter {
 public:
  explicit Reporter(const std::string& source) : source_(source) {}

  [[noreturn]] void fail(const std::string& where, const std::string& problem) const {
    throw SceneError(source_ + ": " + (where.empty() ? "" : where + ": ") + problem);
  }

 private:
  const std::string& source_;
};

// ---- Semantic checks, shared by parse_scene and validate_scene. ----

void check_finite(const Reporter& r, const std::string& where, double value) {
  if (!std::isfinite(value)) r.fail(where, "must be a finite number");
}

void check_nonnegative(const Reporter& r, const std::string& where, double value) {
  check_finite(r, where, value);
  if (value < 0) r.fail(where, "must be >= 0 (got " + format_number(value) + ")");
}

void check_positive(const Reporter& r, const std::string& where, double value) {
  check_finite(r, where, value);
  if (value <= 0) r.fail(where, "must be > 0 (got " + format_number(value) + ")");
}

int check_dimension(const Reporter& r, double value) {
  if (value != 2 && value != 3)
    r.fail("dimension", "must be 2 or 3 (got " + format_number(value) + ")");
  return static_cast<int>(value);
}

// Components past `dimension` are not in the file; a built Scene keeps them 0.
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

void check_wind(const Reporter& r, const Wind& wind, int dimension) {
  check_vector(r, "wind.velocity", wind.velocity, dimension);
  check_nonnegative(r, "wind.coefficient", wind.coefficient);
  check_nonnegative(r, "wind.gust", wind.gust);
  check_nonnegative(r, "wind.frequency", wind.frequency);
}

// The resource caps of scene.h, on counts already known.
void check_counts(const Reporter& r, std::size_t particles, std::size_t springs) {
  if (particles > kMaxSceneParticles) {
    r.fail("particles", std::to_string(particles) + " particles, over the cap of " +
                            std::to_string(kMaxSceneParticles) + " per scene");
  }
  if (springs > kMaxSceneSprings) {
    r.fail("springs", std::to_string(springs) + " springs, over the cap of " +
                          std::to_string(kMaxSceneSprings) + " per scene");
  }
}

void check_has_free_particle(const Reporter& r, const std::vector<Particle>& particles) {
  const bool any_free =
      std::any_of(particles.begin(), particles.end(), [](const Particle& p) { return !p.fixed; });
  if (!any_free) r.fail("particles", "scene has no free particle");
}

// An end index as a double, so that a fractional or huge value from a file is
// reported instead of being truncated to int.
int check_index(const Reporter& r, const std::string& spring, const char* end, double index,
                std::size_t particle_count) {
  const std::string where = spring + "." + end;
  check_finite(r, where, index);
  if (index != std::floor(index)) {
    r.fail(where, "must be a whole number (got " + format_number(index) + ")");
  }
  if (index < 0 || index >= static_cast<double>(particle_count)) {
    r.fail(spring, "particle " + format_number(index) + " does not exist (scene has " +
                       std::to_string(particle_count) +
                       (particle_count == 1 ? " particle)" : " particles)"));
  }
  return static_cast<int>(index);
}

void check_not_self(const Reporter& r, const std::string& where, const Spring& s) {
  if (s.i == s.j) r.fail(where, "joins particle " + std::to_string(s.i) + " to itself");
}

// Coinciding ends have no spring direction; only a zero-rest-length spring
// (a linear force, SPEC §2) is defined there. Returns the initial distance.
double check_spring_ends(const Reporter& r, const std::string& where, const Spring& s,
                         const std::vector<Particle>& particles, bool rest_given) {
  const double distance = (particles[s.i].x - particles[s.j].x).norm();
  const std::string ends = std::to_string(s.i) + " and " + std::to_string(s.j);
  if (distance == 0 && !(rest_given && s.rest == 0)) {
    r.fail(where,
           "particles " + ends + " coincide " +
               (rest_given ? "but the rest length is positive" : "and no rest length is given"));
  }
  if (!rest_given && !std::isfinite(distance)) {
    r.fail(where, "particles " + ends + " are too far apart to take their distance as rest length");
  }
  return distance;
}

// The first spring (in order) among springs[0, count) that joins the same
// unordered pair as an earlier one: {later, earlier}. Bucketing by the lower
// end keeps time and memory O(N + M) for the largest built-ins.
std::optional<std::pair<std::size_t, std::size_t>> first_duplicate(
    const std::vector<Spring>& springs, std::size_t count, std::size_t particle_count) {
  auto low = [&](std::size_t s) {
    return static_cast<std::size_t>(std::min(springs[s].i, springs[s].j));
  };
  auto high = [&](std::size_t s) { return std::max(springs[s].i, springs[s].j); };
  std::vector<std::size_t> start(particle_count + 1, 0);
  for (std::size_t s = 0; s < count; ++s) ++start[low(s) + 1];
  for (std::size_t p = 0; p < particle_count; ++p) start[p + 1] += start[p];
  std::vector<std::size_t> order(count);
  std::vector<std::size_t> next(start.begin(), start.end() - 1);
  for (std::size_t s = 0; s < count; ++s) order[next[low(s)]++] = s;

  std::optional<std::pair<std::size_t, std::size_t>> found;
  for (std::size_t p = 0; p < particle_count; ++p) {
    const auto first = order.begin() + static_cast<std::ptrdiff_t>(start[p]);
    const auto last = order.begin() + static_cast<std::ptrdiff_t>(start[p + 1]);
    std::sort(first, last, [&](std::size_t a, std::size_t b) {
      return std::pair(high(a), a) < std::pair(high(b), b);
    });
    for (auto it = first; it != last; ++it) {
      const auto head = it;  // earliest spring of a run with the same pair
      while (it + 1 != last && high(*(it + 1)) == high(*head)) {
        ++it;
        if (!found || *it < found->first) found = std::pair(*it, *head);
      }
    }
  }
  return found;
}

void check_no_duplicate(const Reporter& r, const std::vector<Spring>& springs, std::size_t count,
                        std::size_t particle_count) {
  if (const auto dup = first_duplicate(springs, count, particle_count)) {
    const Spring& s = springs[dup->first];
    r.fail(element("springs", dup->first), "duplicates " + element("springs", dup->second) +
                                               " (both join particles " +
                                               std::to_string(std::min(s.i, s.j)) + " and " +
                                               std::to_string(std::max(s.i, s.j)) + ")");
  }
}

// Runs check(s) for every spring in order. Duplicates are found only in bulk,
// so before a failing spring's message, any duplicate among the springs before
// it is reported: the user always sees the first problem in the file.
template <typename CheckOne>
void check_springs_in_order(const Reporter& r, const std::vector<Spring>& springs,
                            std::size_t spring_count, std::size_t particle_count, CheckOne check) {
  for (std::size_t s = 0; s < spring_count; ++s) {
    try {
      check(s);
    } catch (const SceneError&) {
      check_no_duplicate(r, springs, std::min(s, springs.size()), particle_count);
      throw;
    }
  }
  check_no_duplicate(r, springs, springs.size(), particle_count);
}

// ---- Reading the JSON document. ----

// Builds the document through nlohmann's SAX interface while tracking where
// it is, to refuse duplicate keys (the library would keep the last silently)
// and to name the element of a number too large for a double (the library
// refuses 1e999 before we see it). nlohmann's callback parser would do this
// too, but it rescans the parent array after every object: quadratic.
//
// The resource caps of scene.h are enforced here, as the document grows, so
// that memory stays bounded whatever the file holds: nesting depth (each open
// container keeps its path), the number of values, and the length of the
// particles and springs arrays. Keys are looked up in a hash set and appended
// without a search: an ordered_json object searches linearly, which made an
// object of 10^5 keys take a minute.
class DocumentBuilder {
 public:
  DocumentBuilder(Json& root, const Reporter& r) : root_(root), r_(r) {}

  bool null() { return add(nullptr); }
  bool boolean(bool value) { return add(value); }
  bool number_integer(Json::number_integer_t value) { return add(value); }
  bool number_unsigned(Json::number_unsigned_t value) { return add(value); }
  bool number_float(Json::number_float_t value, const Json::string_t&) { return add(value); }
  bool string(Json::string_t& value) { return add(std::move(value)); }
  bool binary(Json::binary_t& value) { return add(Json::binary(std::move(value))); }

  bool start_object(std::size_t) { return open(Json::object()); }
  bool start_array(std::size_t) { return open(Json::array()); }
  bool end_object() { return close(); }
  bool end_array() { return close(); }

  bool key(Json::string_t& key) {
    Frame& top = frames_.back();
    if (!top.keys.insert(key).second) r_.fail(top.path, "duplicate key '" + printable(key) + "'");
    top.key = std::move(key);
    return true;
  }

  bool parse_error(std::size_t, const std::string&, const Json::exception& e) {
    if (e.id == 406)
      r_.fail(next_path().empty() ? "top level" : next_path(), "must be a finite number");
    std::string message = e.what();
    const auto bracket = message.find("] ");  // drop "[json.exception.parse_error.101] "
    if (message.rfind("[json.exception.", 0) == 0 && bracket != std::string::npos) {
      message.erase(0, bracket + 2);
    }
    std::replace(message.begin(), message.end(), '\n', ' ');
    r_.fail("", "malformed JSON: " + message);
  }

 private:
  struct Frame {
    Json* container;
    std::string path;
    std::string key;                       // objects: the key of the value being read
    std::unordered_set<std::string> keys;  // objects: the keys read so far
  };

  // The path of the value being read now.
  std::string next_path() const {
    if (frames_.empty()) return "";
    const Frame& top = frames_.back();
    return top.container->is_array() ? element(top.path, top.container->size())
                                     : field(top.path, top.key);
  }

  // Only the innermost open container grows, so pointers to the open ones
  // (each the last element of its parent) stay valid.
  Json* insert(Json&& value) {
    if (++values_ > kMaxSceneJsonValues) {
      r_.fail(next_path().empty() ? "top level" : next_path(),
              "the file holds more than " + std::to_string(kMaxSceneJsonValues) +
                  " JSON values, over the cap for a scene file");
    }
    if (frames_.empty()) {
      root_ = std::move(value);
      return &root_;
    }
    Frame& frame = frames_.back();
    Json& top = *frame.container;
    if (top.is_array()) {
      if (frames_.size() == 2 && (frame.path == "particles" || frame.path == "springs")) {
        const bool particles = frame.path == "particles";
        const std::size_t cap = particles ? kMaxSceneParticles : kMaxSceneSprings;
        if (top.size() >= cap) {
          r_.fail(frame.path, "more than " + std::to_string(cap) + " " + frame.path +
                                  ", over the cap of " + std::to_string(cap) + " per scene");
        }
      }
      top.push_back(std::move(value));
      return &top.back();
    }
    // key() has refused a duplicate, so the key is new: append, no search.
    Json::object_t& object = top.get_ref<Json::object_t&>();
    object.emplace_back(std::move(frame.key), std::move(value));
    return &object.back().second;
  }

  bool add(Json&& value) {
    insert(std::move(value));
    return true;
  }

  bool open(Json&& container) {
    std::string path = next_path();
    if (frames_.size() >= kMaxSceneNesting) {
      r_.fail(path, "nested deeper than " + std::to_string(kMaxSceneNesting) +
                        " levels, over the cap for a scene file");
    }
    Json* inserted = insert(std::move(container));
    frames_.push_back({inserted, std::move(path), {}, {}});
    return true;
  }

  bool close() {
    frames_.pop_back();
    return true;
  }

  Json& root_;
  const Reporter& r_;
  std::vector<Frame> frames_;
  std::size_t values_ = 0;
};

Json parse_document(const std::string& text, const Reporter& r) {
  Json document;
  DocumentBuilder builder(document, r);
  Json::sax_parse(text, &builder);  // every failure throws from the builder
  return document;
}

std::string type_of(const Json& j) { return j.type_name(); }

void require_object(const Reporter& r, const std::string& where, const Json& j) {
  if (!j.is_object())
    r.fail(where.empty() ? "top level" : where, "expected an object, got " + type_of(j));
}

void check_keys(const Reporter& r, const std::string& where, const Json& object,
                std::initializer_list<const char*> allowed,
                std::initializer_list<const char*> required) {
  for (const auto& item : object.items()) {
    const bool known = std::any_of(allowed.begin(), allowed.end(),
                                   [&](const char* name) { return item.key() == name; });
    if (!known) {
      r.fail(where,
             "unknown key '" + printable(item.key()) + "' (allowed keys: " + join(allowed) + ")");
    }
  }
  for (const char* name : required) {
    if (!object.contains(name)) r.fail(where, std::string("missing required key '") + name + "'");
  }
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

Wind read_wind(const Reporter& r, const Json& j, int dimension) {
  require_object(r, "wind", j);
  check_keys(r, "wind", j, {"velocity", "coefficient", "gust", "frequency"}, {"velocity"});
  Wind wind;
  wind.velocity = read_vector(r, "wind.velocity", j.at("velocity"), dimension);
  auto optional_rate = [&](const char* key, double& out) {
    if (!j.contains(key)) return;
    out = read_number(r, field("wind", key), j.at(key));
    check_nonnegative(r, field("wind", key), out);
  };
  optional_rate("coefficient", wind.coefficient);
  optional_rate("gust", wind.gust);
  optional_rate("frequency", wind.frequency);
  return wind;
}

Particle read_particle(const Reporter& r, const std::string& where, const Json& j, int dimension) {
  require_object(r, where, j);
  check_keys(r, where, j, {"x", "v", "mass", "fixed"}, {"x"});
  Particle p;
  p.x = read_vector(r, field(where, "x"), j.at("x"), dimension);
  if (j.contains("v")) p.v = read_vector(r, field(where, "v"), j.at("v"), dimension);
  if (j.contains("mass")) {
    p.mass = read_number(r, field(where, "mass"), j.at("mass"));
    check_positive(r, field(where, "mass"), p.mass);
  }
  if (j.contains("fixed")) p.fixed = read_bool(r, field(where, "fixed"), j.at("fixed"));
  return p;
}

Spring read_spring(const Reporter& r, const std::string& where, const Json& j,
                   const std::vector<Particle>& particles) {
  require_object(r, where, j);
  check_keys(r, where, j, {"i", "j", "k", "rest", "damping"}, {"i", "j", "k"});
  Spring s;
  s.i = check_index(r, where, "i", read_number(r, field(where, "i"), j.at("i")), particles.size());
  s.j = check_index(r, where, "j", read_number(r, field(where, "j"), j.at("j")), particles.size());
  check_not_self(r, where, s);
  s.k = read_number(r, field(where, "k"), j.at("k"));
  check_nonnegative(r, field(where, "k"), s.k);
  const bool rest_given = j.contains("rest");
  if (rest_given) {
    s.rest = read_number(r, field(where, "rest"), j.at("rest"));
    check_nonnegative(r, field(where, "rest"), s.rest);
  }
  if (j.contains("damping")) {
    s.damping = read_number(r, field(where, "damping"), j.at("damping"));
    check_nonnegative(r, field(where, "damping"), s.damping);
  }
  const double distance = check_spring_ends(r, where, s, particles, rest_given);
  if (!rest_given) s.rest = distance;
  return s;
}

std::string file_size_error(const std::string& bytes) {
  return bytes + " bytes, over the cap of " + std::to_string(kMaxSceneFileBytes) +
         " bytes for a scene file";
}

// ---- Writing. ----

// Like nlohmann's output: shortest round-trip text, ".0" on whole numbers.
std::string json_number(double value) {
  if (!std::isfinite(value)) return "null";
  std::string text = format_number(value);
  if (text.find_first_of(".e") == std::string::npos) text += ".0";
  return text;
}

std::string json_vector(const Eigen::Vector3d& v, int dimension) {
  std::string out = "[";
  for (int k = 0; k < dimension; ++k) out += (k ? ", " : "") + json_number(v[k]);
  return out + "]";
}

}  // namespace

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

Scene parse_scene(const std::string& json_text, const std::string& source) {
  const Reporter r(source);
  if (json_text.size() > kMaxSceneFileBytes) {
    r.fail("", file_size_error(std::to_string(json_text.size())));
  }
  if (const std::optional<std::string> problem = json_text_problem(json_text)) r.fail("", *problem);
  const Json doc = parse_document(json_text, r);
  require_object(r, "", doc);
  check_keys(r, "", doc, {"name", "dimension", "gravity", "drag", "wind", "particles", "springs"},
             {"dimension", "particles", "springs"});

  // Everything below depends on the dimension, and springs on the particles,
  // so the top-level keys are read in this fixed order.
  Scene scene;
  scene.dimension = check_dimension(r, read_number(r, "dimension", doc.at("dimension")));
  if (doc.contains("name")) {
    if (!doc.at("name").is_string())
      r.fail("name", "expected a string, got " + type_of(doc.at("name")));
    scene.name = doc.at("name").get<std::string>();
  }
  if (doc.contains("gravity"))
    scene.gravity = read_vector(r, "gravity", doc.at("gravity"), scene.dimension);
  if (doc.contains("drag")) {
    scene.drag = read_number(r, "drag", doc.at("drag"));
    check_nonnegative(r, "drag", scene.drag);
  }
  if (doc.contains("wind")) scene.wind = read_wind(r, doc.at("wind"), scene.dimension);

  const Json& particles = doc.at("particles");
  if (!particles.is_array()) r.fail("particles", "expected an array, got " + type_of(particles));
  scene.particles.reserve(particles.size());
  for (std::size_t p = 0; p < particles.size(); ++p) {
    scene.particles.push_back(
        read_particle(r, element("particles", p), particles[p], scene.dimension));
  }
  check_has_free_particle(r, scene.particles);

  const Json& springs = doc.at("springs");
  if (!springs.is_array()) r.fail("springs", "expected an array, got " + type_of(springs));
  scene.springs.reserve(springs.size());
  check_springs_in_order(
      r, scene.springs, springs.size(), scene.particles.size(), [&](std::size_t s) {
        scene.springs.push_back(read_spring(r, element("springs", s), springs[s], scene.particles));
      });
  return scene;
}

void validate_scene(const Scene& scene, const std::string& source) {
  const Reporter r(source);
  check_counts(r, scene.particles.size(), scene.springs.size());
  const int dimension = check_dimension(r, scene.dimension);
  check_vector(r, "gravity", scene.gravity, dimension);
  check_nonnegative(r, "drag", scene.drag);
  if (scene.wind) check_wind(r, *scene.wind, dimension);

  for (std::size_t p = 0; p < scene.particles.size(); ++p) {
    const std::string where = element("particles", p);
    const Particle& particle = scene.particles[p];
    check_vector(r, field(where, "x"), particle.x, dimension);
    check_vector(r, field(where, "v"), particle.v, dimension);
    check_positive(r, field(where, "mass"), particle.mass);
  }
  check_has_free_particle(r, scene.particles);

  const std::size_t n = scene.particles.size();
  check_springs_in_order(r, scene.springs, scene.springs.size(), n, [&](std::size_t s) {
    const std::string where = element("springs", s);
    const Spring& spring = scene.springs[s];
    check_index(r, where, "i", spring.i, n);
    check_index(r, where, "j", spring.j, n);
    check_not_self(r, where, spring);
    check_nonnegative(r, field(where, "k"), spring.k);
    check_nonnegative(r, field(where, "rest"), spring.rest);
    check_nonnegative(r, field(where, "damping"), spring.damping);
    check_spring_ends(r, where, spring, scene.particles, /*rest_given=*/true);
  });
}

Scene load_scene_file(const std::string& path, const std::string& source) {
  const std::string& name = source.empty() ? path : source;
  std::error_code ignored;
  std::ifstream in(path, std::ios::binary);
  // A directory opens as a stream on Linux but cannot be read.
  if (!in || std::filesystem::is_directory(path, ignored))
    throw SceneError(name + ": cannot open file");
  // The size cap is checked before reading: a huge file is refused, not loaded.
  std::error_code size_error;
  const std::uintmax_t size = std::filesystem::file_size(path, size_error);
  if (!size_error && size > kMaxSceneFileBytes) {
    throw SceneError(name + ": " + file_size_error(std::to_string(size)));
  }
  // Read in chunks up to one byte past the cap: a file whose size is not
  // known in advance (a pipe, /proc) cannot grow without bound either.
  std::string text;
  if (!size_error) text.reserve(static_cast<std::size_t>(size) + 1);  // no doubling
  char chunk[1 << 16];
  while (in && text.size() <= kMaxSceneFileBytes) {
    in.read(chunk, sizeof chunk);
    text.append(chunk, static_cast<std::size_t>(in.gcount()));
  }
  if (in.bad()) throw SceneError(name + ": cannot open file");
  if (text.size() > kMaxSceneFileBytes) {
    throw SceneError(name + ": " +
                     file_size_error("more than " + std::to_string(kMaxSceneFileBytes)));
  }
  return parse_scene(text, name);  // an empty file is left to the parser ("malformed JSON")
}

// One particle or spring per line: a scene file stays readable (and diffable)
// at thousands of elements, and no JSON tree of the whole scene is built.
std::string scene_to_json(const Scene& scene) {
  const int d = std::clamp(scene.dimension, 0, 3);  // an invalid scene is written, not crashed on
  std::string out = "{\n";
  out += "  \"name\": " + Json(scene.name).dump(-1, ' ', false, Json::error_handler_t::replace) +
         ",\n";
  out += "  \"dimension\": " + std::to_string(scene.dimension) + ",\n";
  out += "  \"gravity\": " + json_vector(scene.gravity, d) + ",\n";
  out += "  \"drag\": " + json_number(scene.drag) + ",\n";
  if (scene.wind) {
    const Wind& w = *scene.wind;
    out += "  \"wind\": {\"velocity\": " + json_vector(w.velocity, d) +
           ", \"coefficient\": " + json_number(w.coefficient) +
           ", \"gust\": " + json_number(w.gust) + ", \"frequency\": " + json_number(w.frequency) +
           "},\n";
  }
  out += "  \"particles\": [";
  for (std::size_t p = 0; p < scene.particles.size(); ++p) {
    const Particle& particle = scene.particles[p];
    out += (p ? ",\n    " : "\n    ");
    out += "{\"x\": " + json_vector(particle.x, d);
    if ((particle.v.head(d).array() != 0).any()) out += ", \"v\": " + json_vector(particle.v, d);
    out += ", \"mass\": " + json_number(particle.mass);
    if (particle.fixed) out += ", \"fixed\": true";
    out += "}";
  }
  out += scene.particles.empty() ? "],\n" : "\n  ],\n";
  out += "  \"springs\": [";
  for (std::size_t s = 0; s < scene.springs.size(); ++s) {
    const Spring& spring = scene.springs[s];
    out += (s ? ",\n    " : "\n    ");
    out += "{\"i\": " + std::to_string(spring.i) + ", \"j\": " + std::to_string(spring.j) +
           ", \"k\": " + json_number(spring.k) + ", \"rest\": " + json_number(spring.rest);
    if (spring.damping != 0) out += ", \"damping\": " + json_number(spring.damping);
    out += "}";
  }
  out += scene.springs.empty() ? "]\n" : "\n  ]\n";
  return out + "}\n";
}

}  // namespace springlab
