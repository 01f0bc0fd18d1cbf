// Scene files (docs/physics.md "Scene files"): the document, the particles, and the order in which
// the element kinds (element_kind.h) read, check and write their own keys.
//
// parse_scene reads a document element by element and reports the first
// problem it meets. Every semantic rule (finite numbers, mass > 0, index
// exists, ...) lives in one check function that both parse_scene and
// validate_scene call, so a built-in scene and a file get the same message.
#include "models/model/scene_file.h"

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <utility>

#include "models/bodies/bodies.h"
#include "models/core/element_kind.h"
#include "models/model/element_registry.h"
#include "models/core/scene_io.h"
#include "models/core/strict_json.h"

namespace springlab {
namespace {

int check_dimension(const Reporter& r, double value) {
  if (value != 2 && value != 3)
    r.fail("dimension", "must be 2 or 3 (got " + shortest_text(value) + ")");
  return static_cast<int>(value);
}

// A scene with rigid bodies may have no free particle: the "body" kind
// (bodies.cc) then checks that some body is free.
void check_has_free_particle(const Reporter& r, const std::vector<Particle>& particles,
                             bool has_bodies) {
  const bool any_free =
      std::any_of(particles.begin(), particles.end(), [](const Particle& p) { return !p.fixed; });
  if (!any_free && !has_bodies) r.fail("particles", "scene has no free particle");
}

// The kinds read before "particles" (scene-wide: gravity, drag, wind) or
// after it (elements that name particles: springs), in registry order.
std::vector<const ElementKind*> kinds_in_phase(bool refers_to_particles) {
  std::vector<const ElementKind*> out;
  for (const ElementKind* kind : element_kinds()) {
    if (kind->refers_to_particles == refers_to_particles) out.push_back(kind);
  }
  return out;
}

// The top-level keys in the order messages list them and files hold them.
std::vector<std::string> top_level_keys(bool required_only) {
  std::vector<std::string> keys;
  auto add_kinds = [&](bool refers_to_particles) {
    for (const ElementKind* kind : kinds_in_phase(refers_to_particles)) {
      for (const SceneKey& key : kind->keys) {
        if (!required_only || key.required) keys.emplace_back(key.name);
      }
    }
  };
  if (!required_only) keys.push_back("name");
  keys.push_back("dimension");
  add_kinds(false);
  keys.push_back("particles");
  add_kinds(true);
  return keys;
}

// The caps on element arrays, checked while the document grows: the
// particles, and each kind's arrays (springs, ...).
std::size_t array_cap(const std::string& key) {
  if (key == "particles") return kMaxSceneParticles;
  for (const ElementKind* kind : element_kinds()) {
    for (const SceneKey& k : kind->keys) {
      if (k.cap > 0 && k.name == key) return k.cap;
    }
  }
  return std::numeric_limits<std::size_t>::max();
}

// ---- Reading the JSON document. ----

// The strict reader (strict_json.h) refuses duplicate keys and names the
// element of a number too large for a double (the library refuses 1e999
// before we see it). The resource caps of scene.h are enforced as the
// document grows, so that memory stays bounded whatever the file holds:
// nesting depth, the number of values, and the length of the particles array
// and of every element kind's arrays.
Json parse_document(const std::string& text, const Reporter& r) {
  StrictJsonPolicy policy;
  policy.fail = [&r](const std::string& path, const std::string& message) { r.fail(path, message); };
  policy.name_overflowing_number = true;
  policy.caps = StrictJsonCaps{kMaxSceneNesting, kMaxSceneJsonValues, array_cap, "scene"};
  return parse_strict_json<Json>(text, policy);
}

// ---- Particles (docs/physics.md "Scene files"). ----

Particle read_particle(const Reporter& r, const std::string& where, const Json& j, int dimension) {
  require_object(r, where, j);
  check_keys(r, where, j, {"x", "X", "v", "mass", "fixed"}, {"x"});
  Particle p;
  p.x = read_vector(r, field(where, "x"), j.at("x"), dimension);
  if (j.contains("X")) p.X = read_vector(r, field(where, "X"), j.at("X"), dimension);
  if (j.contains("v")) p.v = read_vector(r, field(where, "v"), j.at("v"), dimension);
  if (j.contains("mass")) {
    p.mass = read_number(r, field(where, "mass"), j.at("mass"));
    check_positive(r, field(where, "mass"), p.mass);
  }
  if (j.contains("fixed")) p.fixed = read_bool(r, field(where, "fixed"), j.at("fixed"));
  return p;
}

void check_particle(const Reporter& r, const std::string& where, const Particle& particle,
                    int dimension) {
  check_vector(r, field(where, "x"), particle.x, dimension);
  if (particle.X) check_vector(r, field(where, "X"), *particle.X, dimension);
  check_vector(r, field(where, "v"), particle.v, dimension);
  check_positive(r, field(where, "mass"), particle.mass);
}

std::string particle_json(const Particle& particle, int d) {
  std::string out = "{\"x\": " + json_vector(particle.x, d);
  if (particle.X) out += ", \"X\": " + json_vector(*particle.X, d);
  if ((particle.v.head(d).array() != 0).any()) out += ", \"v\": " + json_vector(particle.v, d);
  out += ", \"mass\": " + json_number(particle.mass);
  if (particle.fixed) out += ", \"fixed\": true";
  return out + "}";
}

std::string file_size_error(const std::string& bytes) {
  return bytes + " bytes, over the cap of " + std::to_string(kMaxSceneFileBytes) +
         " bytes for a scene file";
}

}  // namespace

Scene parse_scene(const std::string& json_text, const std::string& source) {
  const Reporter r(source);
  if (json_text.size() > kMaxSceneFileBytes) {
    r.fail("", file_size_error(std::to_string(json_text.size())));
  }
  if (const std::optional<std::string> problem = json_text_problem(json_text)) r.fail("", *problem);
  const Json doc = parse_document(json_text, r);
  require_object(r, "", doc);
  check_keys(r, "", doc, top_level_keys(false), top_level_keys(true));

  // Everything below depends on the dimension, and the elements on the
  // particles, so the top-level keys are read in this fixed order.
  Scene scene;
  scene.dimension = check_dimension(r, read_number(r, "dimension", doc.at("dimension")));
  if (doc.contains("name")) {
    if (!doc.at("name").is_string())
      r.fail("name", "expected a string, got " + std::string(doc.at("name").type_name()));
    scene.name = doc.at("name").get<std::string>();
  }
  for (const ElementKind* kind : kinds_in_phase(false)) {
    if (kind->read != nullptr) kind->read(doc, r, scene);
  }

  const Json& particles = doc.at("particles");
  require_array(r, "particles", particles);
  scene.particles.reserve(particles.size());
  for (std::size_t p = 0; p < particles.size(); ++p) {
    scene.particles.push_back(
        read_particle(r, element("particles", p), particles[p], scene.dimension));
  }
  // (A fluid's "box" makes free particles of its own: fluid_kind.cc.)
  const auto makes_particles = [&](const char* key, const char* inner) {
    if (!doc.contains(key) || !doc.at(key).is_array()) return false;
    for (const Json& e : doc.at(key)) {
      if (inner == nullptr || (e.is_object() && e.contains(inner))) return true;
    }
    return false;
  };
  check_has_free_particle(r, scene.particles,
                          makes_particles("bodies", nullptr) || makes_particles("fluids", "box"));

  for (const ElementKind* kind : kinds_in_phase(true)) {
    if (kind->read != nullptr) kind->read(doc, r, scene);
  }
  return scene;
}

void validate_scene(const Scene& scene, const std::string& source) {
  const Reporter r(source);
  // The caps first: a scene over them is refused before anything is checked.
  if (scene.particles.size() > kMaxSceneParticles) {
    r.fail("particles", std::to_string(scene.particles.size()) + " particles, over the cap of " +
                            std::to_string(kMaxSceneParticles) + " per scene");
  }
  for (const ElementCount& c : element_counts(scene)) {
    if (c.count > c.cap) {
      const std::string key(c.key);
      r.fail(key, std::to_string(c.count) + " " + key + ", over the cap of " +
                      std::to_string(c.cap) + " per scene");
    }
  }
  const int dimension = check_dimension(r, scene.dimension);
  for (const ElementKind* kind : kinds_in_phase(false)) {
    if (kind->validate != nullptr) kind->validate(scene, r);
  }
  for (std::size_t p = 0; p < scene.particles.size(); ++p) {
    check_particle(r, element("particles", p), scene.particles[p], dimension);
  }
  check_has_free_particle(r, scene.particles, !scene.get<Bodies>().empty());
  for (const ElementKind* kind : kinds_in_phase(true)) {
    if (kind->validate != nullptr) kind->validate(scene, r);
  }
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
    const std::size_t got = static_cast<std::size_t>(in.gcount());
    text.append(chunk, got);
    // A NUL byte is refused where it is read (`run /dev/zero`: in the first
    // chunk, not after the 512 MiB cap).
    if (std::memchr(chunk, '\0', got) != nullptr) {
      if (const std::optional<std::string> problem = json_text_problem(text)) {
        throw SceneError(name + ": " + *problem);
      }
    }
  }
  if (in.bad()) throw SceneError(name + ": cannot open file");
  if (text.size() > kMaxSceneFileBytes) {
    throw SceneError(name + ": " +
                     file_size_error("more than " + std::to_string(kMaxSceneFileBytes)));
  }
  return parse_scene(text, name);  // an empty file is left to the parser ("malformed JSON")
}

// One particle or element per line: a scene file stays readable (and
// diffable) at thousands of elements, and no JSON tree of the whole scene is
// built. The keys come in the order parse_scene reads them.
std::string scene_to_json(const Scene& scene) {
  const int d = std::clamp(scene.dimension, 0, 3);  // an invalid scene is written, not crashed on
  std::vector<std::pair<std::string, std::string>> entries;
  entries.emplace_back("name", json_string(scene.name));
  entries.emplace_back("dimension", std::to_string(scene.dimension));
  for (const ElementKind* kind : kinds_in_phase(false)) {
    if (kind->write != nullptr) kind->write(scene, entries);
  }
  JsonLines particles;
  for (const Particle& particle : scene.particles) particles.add(particle_json(particle, d));
  entries.emplace_back("particles", particles.str());
  for (const ElementKind* kind : kinds_in_phase(true)) {
    if (kind->write != nullptr) kind->write(scene, entries);
  }
  std::string out = "{\n";
  for (std::size_t k = 0; k < entries.size(); ++k) {
    out += (k ? ",\n  \"" : "  \"") + entries[k].first + "\": " + entries[k].second;
  }
  return out + "\n}\n";
}

}  // namespace springlab
