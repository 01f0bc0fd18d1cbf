// The "body-spring" element kind (body_springs.h, docs/physics.md "Springs
// to body points"): the springs of a scene's "springs" with a body point at
// an end -- reading, checks, writing, a random instance -- and its
// registration. The force is body_spring_force.cc.
//
// "springs" belongs to the spring kind, which reads it first and leaves out
// every entry with an object end (springs.cc, is_body_spring); this kind
// reads those entries afterwards, once "bodies" is read, so an end can be
// checked against its body. (A problem in a body spring is therefore reported
// after every problem of the particle springs and bodies.)
#include "models/bodies/body_springs.h"

#include <Eigen/Geometry>
#include <cmath>
#include <memory>
#include <random>
#include <string>

#include "models/bodies/bodies.h"
#include "models/contact/contact.h"
#include "models/core/element_kind.h"
#include "models/springs/spring_reading.h"
#include "models/springs/springs.h"

namespace springlab {

// body_spring_force.cc
std::unique_ptr<ForceTerm> make_body_spring_force(const Scene&, const ParticleOrder&);
const ElementKind& spring_kind();  // springs.cc
// bodies.cc: a random box; strained (A not a rotation) or not.
void add_random_body_with(Scene& scene, std::mt19937& rng, RandomStates states, bool strained);

Eigen::Vector3d spring_end_rest_point(const Scene& scene, const SpringEnd& end) {
  if (!end.is_body()) return scene.particles[static_cast<std::size_t>(end.particle)].rest_position();
  const RigidBody body = rigid_body(scene.get<Bodies>()[static_cast<std::size_t>(end.body)]);
  return body.p0 + body.A0 * (body.mass.frame.transpose() * (end.X - body.mass.centre));
}

namespace {

std::string plural(std::size_t n, const char* one, const char* many) {
  return std::to_string(n) + " " + (n == 1 ? one : many);
}

std::string end_name(const SpringEnd& e) {
  return e.is_body() ? "a point of body " + std::to_string(e.body)
                     : "particle " + std::to_string(e.particle);
}

// Every check of one end, for files and built scenes alike. `key` is "i" or "j".
void check_end(const Reporter& r, const std::string& where, const char* key, const SpringEnd& e,
               const Scene& scene) {
  if (!e.is_body()) {
    check_particle_index(r, where, key, e.particle, scene.particles.size());
    return;
  }
  const std::size_t bodies = scene.get<Bodies>().size();
  if (static_cast<std::size_t>(e.body) >= bodies) {
    r.fail(field(where, key), "body " + std::to_string(e.body) + " does not exist (scene has " +
                                  plural(bodies, "body)", "bodies)"));
  }
  check_vector(r, field(field(where, key), "X"), e.X, 3);
}

// The checks after both ends are known; returns the ends' distance at rest.
double check_ends(const Reporter& r, const std::string& where, const BodySpring& s,
                  const Scene& scene, bool rest_given) {
  if (s.i.is_body() && s.j.is_body() && s.i.body == s.j.body) {
    r.fail(where, "joins body " + std::to_string(s.i.body) +
                      " to itself (a spring inside one rigid body does nothing)");
  }
  const double distance =
      (spring_end_rest_point(scene, s.i) - spring_end_rest_point(scene, s.j)).norm();
  if (distance == 0.0 && !(rest_given && s.rest == 0.0)) {
    r.fail(where, end_name(s.i) + " and " + end_name(s.j) + " coincide " +
                      (rest_given ? "but the rest length is positive" : "and no rest length is given"));
  }
  if (!rest_given && !std::isfinite(distance)) {
    r.fail(where, "its ends are too far apart to take their distance as rest length");
  }
  return distance;
}

// An end as the file gives it: a particle index, or {"body": b, "X": [x, y, z]}.
SpringEnd read_end(const Reporter& r, const std::string& where, const char* key, const Json& j,
                   const Scene& scene) {
  SpringEnd e;
  const std::string at = field(where, key);
  if (!j.is_object()) {
    e.particle = check_particle_index(r, where, key, read_number(r, at, j), scene.particles.size());
    return e;
  }
  check_keys(r, at, j, {"body", "X"}, {"body", "X"});
  const double b = read_number(r, field(at, "body"), j.at("body"));
  if (!std::isfinite(b) || b != std::floor(b) || b < 0) {
    r.fail(field(at, "body"), "expected a whole body index >= 0 (got " + shortest_text(b) + ")");
  }
  const std::size_t bodies = scene.get<Bodies>().size();
  if (b >= static_cast<double>(bodies)) {
    r.fail(at, "body " + shortest_text(b) + " does not exist (scene has " +
                   plural(bodies, "body)", "bodies)"));
  }
  e.body = static_cast<int>(b);
  const Json& X = j.at("X");
  if (!X.is_array() || X.size() != 3) {
    r.fail(field(at, "X"), "expected 3 numbers, a point in the body's own frame [x, y, z], got " +
                               (X.is_array() ? plural(X.size(), "number", "numbers")
                                             : std::string(X.type_name())));
  }
  e.X = read_vector(r, field(at, "X"), X, 3);
  return e;
}

BodySpring read_body_spring(const Reporter& r, const std::string& where, const Json& j,
                            const Scene& scene) {
  check_keys(r, where, j, {"i", "j", "k", "rest", "damping"}, {"i", "j", "k"});
  if (j.contains("damping")) {
    r.fail(field(where, "damping"),
           "a spring with a body end has no damping (only particle springs have)");
  }
  BodySpring s;
  s.i = read_end(r, where, "i", j.at("i"), scene);
  s.j = read_end(r, where, "j", j.at("j"), scene);
  const bool rest_given = read_stiffness_and_rest(r, where, j, s.k, s.rest);
  const double distance = check_ends(r, where, s, scene, rest_given);
  if (!rest_given) s.rest = distance;
  return s;
}

void read_body_springs(const Json& document, const Reporter& r, Scene& scene) {
  const Json& springs = document.at("springs");  // an array: the spring kind read it
  for (std::size_t s = 0; s < springs.size(); ++s) {
    if (!is_body_spring(springs[s])) continue;
    if (scene.dimension != 3) r.fail(element("springs", s), "body points need a 3-D scene");
    scene.block<BodySprings>().push_back(
        read_body_spring(r, element("springs", s), springs[s], scene));
  }
}

// A built scene's body springs are named by the place scene_to_json gives
// them: after the particle springs.
void validate_body_springs(const Scene& scene, const Reporter& r) {
  const BodySprings& springs = scene.get<BodySprings>();
  const std::size_t first = scene.get<Springs>().size();
  for (std::size_t s = 0; s < springs.size(); ++s) {
    const std::string where = element("springs", first + s);
    const BodySpring& spring = springs[s];
    if (!spring.i.is_body() && !spring.j.is_body()) {
      r.fail(where, "a body spring needs a body point at one end at least");
    }
    check_end(r, where, "i", spring.i, scene);
    check_end(r, where, "j", spring.j, scene);
    check_nonnegative(r, field(where, "k"), spring.k);
    check_nonnegative(r, field(where, "rest"), spring.rest);
    check_ends(r, where, spring, scene, /*rest_given=*/true);
  }
}

std::string end_json(const SpringEnd& e) {
  if (!e.is_body()) return std::to_string(e.particle);
  return "{\"body\": " + std::to_string(e.body) + ", \"X\": " + json_vector(e.X, 3) + "}";
}

// Appended to the "springs" entry the spring kind wrote.
void write_body_springs(const Scene& scene,
                        std::vector<std::pair<std::string, std::string>>& entries) {
  const BodySprings* springs = scene.find<BodySprings>();
  if (springs == nullptr || springs->empty()) return;
  std::string* text = nullptr;
  for (auto& [key, value] : entries) {
    if (key == "springs") text = &value;
  }
  if (text == nullptr) text = &entries.emplace_back("springs", "[]").second;
  const bool empty = *text == "[]";
  std::string items = empty ? "[" : text->substr(0, text->size() - 4);  // drop "\n  ]"
  bool first = empty;
  for (const BodySpring& s : *springs) {
    items += (first ? "\n    " : ",\n    ") + std::string("{\"i\": ") + end_json(s.i) +
             ", \"j\": " + end_json(s.j) + ", \"k\": " + json_number(s.k) +
             ", \"rest\": " + json_number(s.rest) + "}";
    first = false;
  }
  *text = items + "\n  ]";
}

// Random instances: two free bodies (unstrained, unless the scene has one
// already), then springs from body 0 to a free particle, to the fixed
// particle 2, and to body 1, with random stiffness: zero rest length,
// stretched and (unless the states must be definite) compressed.
void add_random_body_springs(Scene& scene, std::mt19937& rng, RandomStates states) {
  if (scene.dimension != 3) {
    // (In 2-D, which has no bodies, particle springs: the column's energy.)
    if (scene.get<Springs>().empty()) spring_kind().add_random(scene, rng, states);
    return;
  }
  // A body added here is moved 5 m along the first plane (or z), away from
  // the others: body-body contact (body_body_contact.cc) stays out of these
  // instances, whose kDefinite states must have an exact definite part.
  while (scene.get<Bodies>().size() < 2) {
    add_random_body_with(scene, rng, states, false);
    Eigen::Vector3d along = Eigen::Vector3d::UnitZ();
    if (!scene.get<Planes>().empty()) {
      const Eigen::Vector3d n = scene.get<Planes>().front().normal.normalized();
      along = n.unitOrthogonal();
    }
    Body& added = scene.block<Bodies>().back();
    added.position = *added.position + 5.0 * static_cast<double>(scene.get<Bodies>().size()) * along;
  }
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  auto body_point = [&](int b) {
    const Body& body = scene.get<Bodies>()[static_cast<std::size_t>(b)];
    SpringEnd e;
    e.body = b;
    const Eigen::Vector3d half =
        body.shape == Body::Shape::kBox ? Eigen::Vector3d(0.5 * body.size)
                                        : Eigen::Vector3d::Constant(0.3);
    e.X = half.cwiseProduct(Eigen::Vector3d(u(rng), u(rng), u(rng)));
    return e;
  };
  auto particle = [](int p) {
    SpringEnd e;
    e.particle = p;
    return e;
  };
  const SpringEnd others[] = {particle(0), particle(2), body_point(1)};
  int shape = 0;
  for (const SpringEnd& other : others) {
    BodySpring s;
    s.i = body_point(0);
    s.j = other;
    s.k = 10.0 + 20.0 * (0.5 + 0.5 * u(rng));
    const double l = (spring_end_rest_point(scene, s.i) - spring_end_rest_point(scene, s.j)).norm();
    if (shape == 0) {
      s.rest = 0.0;
    } else if (shape == 1 || states == RandomStates::kDefinite) {
      s.rest = l * (0.6 + 0.3 * (0.5 + 0.5 * u(rng)));  // stretched
    } else {
      s.rest = l * (1.2 + 0.4 * (0.5 + 0.5 * u(rng)));  // compressed
    }
    ++shape;
    scene.block<BodySprings>().push_back(s);
  }
}

}  // namespace

const ElementKind& body_spring_kind() {
  static const ElementKind kind = {
      .name = "body-spring",
      .refers_to_particles = true,
      .read = read_body_springs,
      .validate = validate_body_springs,
      .write = write_body_springs,
      .make = make_body_spring_force,
      .energy = {.name = "spring", .always = true, .counts_with_spring = true},
      .add_random = add_random_body_springs,
  };
  return kind;
}

}  // namespace springlab
