// The "spring" element kind: the "springs" key of a scene file (docs/physics.md "Scene files") --
// reading, checks, writing -- and its registration. The force itself, Hooke's
// law, is spring_force.cc (its SIMD kernels in kernels/); spring damping, read here
// from each spring's "damping", is its own kind (spring_damping_force.cc).
#include "models/springs/spring_reading.h"
#include "models/springs/springs.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <utility>

#include "models/core/element_kind.h"

namespace springlab {

// Hooke's law, in spring_force.cc.
std::unique_ptr<ForceTerm> make_spring_force(const Scene&, const ParticleOrder&);
void spring_memory(const Scene& scene, MemoryEstimate& out);  // spring_force.cc

namespace {

void check_not_self(const Reporter& r, const std::string& where, const Spring& s) {
  if (s.i == s.j) r.fail(where, "joins particle " + std::to_string(s.i) + " to itself");
}

// Coinciding ends (at x) have no spring direction; only a zero-rest-length
// spring (a linear force, docs/physics.md "The physics") is defined there. Returns the distance of
// the ends' rest positions X (docs/physics.md "Finite elements"; X = x when not given): the rest
// length of a spring that gives none.
double check_spring_ends(const Reporter& r, const std::string& where, const Spring& s,
                         const std::vector<Particle>& particles, bool rest_given) {
  const double distance = (particles[s.i].x - particles[s.j].x).norm();
  const std::string ends = std::to_string(s.i) + " and " + std::to_string(s.j);
  if (distance == 0 && !(rest_given && s.rest == 0)) {
    r.fail(where,
           "particles " + ends + " coincide " +
               (rest_given ? "but the rest length is positive" : "and no rest length is given"));
  }
  const double rest_distance =
      (particles[s.i].rest_position() - particles[s.j].rest_position()).norm();
  if (!rest_given && !std::isfinite(rest_distance)) {
    r.fail(where, "particles " + ends + " are too far apart to take their distance as rest length");
  }
  return rest_distance;
}

// The first spring (in order) among springs[0, count) that joins the same
// unordered pair as an earlier one: {later, earlier}. Bucketing by the lower
// end keeps time and memory O(N + M) for the largest built-ins.
std::optional<std::pair<std::size_t, std::size_t>> first_duplicate(const Springs& springs,
                                                                   std::size_t count,
                                                                   std::size_t particle_count) {
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

// `file_index[s]`: the place of springs[s] in the file's "springs", where
// springs with a body end (left to body_springs.cc) sit among them; empty:
// the same place.
void check_no_duplicate(const Reporter& r, const Springs& springs, std::size_t count,
                        std::size_t particle_count,
                        const std::vector<std::size_t>& file_index = {}) {
  if (const auto dup = first_duplicate(springs, count, particle_count)) {
    const Spring& s = springs[dup->first];
    auto place = [&](std::size_t k) { return file_index.empty() ? k : file_index[k]; };
    r.fail(element("springs", place(dup->first)), "duplicates " + element("springs", place(dup->second)) +
                                               " (both join particles " +
                                               std::to_string(std::min(s.i, s.j)) + " and " +
                                               std::to_string(std::max(s.i, s.j)) + ")");
  }
}

// Runs check(s) for every spring in order. Duplicates are found only in bulk,
// so before a failing spring's message, any duplicate among the springs before
// it is reported: the user always sees the first problem in the file.
template <typename CheckOne>
void check_springs_in_order(const Reporter& r, const Springs& springs, std::size_t spring_count,
                            std::size_t particle_count, CheckOne check,
                            const std::vector<std::size_t>& file_index = {}) {
  for (std::size_t s = 0; s < spring_count; ++s) {
    try {
      check(s);
    } catch (const SceneError&) {
      check_no_duplicate(r, springs, std::min(s, springs.size()), particle_count, file_index);
      throw;
    }
  }
  check_no_duplicate(r, springs, springs.size(), particle_count, file_index);
}


}  // namespace

bool is_body_spring(const Json& j) {
  return j.is_object() && ((j.contains("i") && j.at("i").is_object()) ||
                           (j.contains("j") && j.at("j").is_object()));
}

bool read_stiffness_and_rest(const Reporter& r, const std::string& where, const Json& j,
                             double& k, double& rest) {
  k = read_number(r, field(where, "k"), j.at("k"));
  check_nonnegative(r, field(where, "k"), k);
  if (!j.contains("rest")) return false;
  rest = read_number(r, field(where, "rest"), j.at("rest"));
  check_nonnegative(r, field(where, "rest"), rest);
  return true;
}

namespace {

Spring read_spring(const Reporter& r, const std::string& where, const Json& j,
                   const std::vector<Particle>& particles) {
  require_object(r, where, j);
  check_keys(r, where, j, {"i", "j", "k", "rest", "damping"}, {"i", "j", "k"});
  Spring s;
  s.i = check_particle_index(r, where, "i", read_number(r, field(where, "i"), j.at("i")),
                             particles.size());
  s.j = check_particle_index(r, where, "j", read_number(r, field(where, "j"), j.at("j")),
                             particles.size());
  check_not_self(r, where, s);
  const bool rest_given = read_stiffness_and_rest(r, where, j, s.k, s.rest);
  if (j.contains("damping")) {
    s.damping = read_number(r, field(where, "damping"), j.at("damping"));
    check_nonnegative(r, field(where, "damping"), s.damping);
  }
  const double rest_distance = check_spring_ends(r, where, s, particles, rest_given);
  if (!rest_given) s.rest = rest_distance;
  return s;
}

void read_springs(const Json& document, const Reporter& r, Scene& scene) {
  const Json& springs = document.at("springs");
  require_array(r, "springs", springs);
  Springs& out = scene.block<Springs>();
  out.reserve(springs.size());
  std::vector<std::size_t> file_index;
  bool body_springs = false;
  check_springs_in_order(
      r, out, springs.size(), scene.particles.size(),
      [&](std::size_t s) {
        if (is_body_spring(springs[s])) {
          body_springs = true;
          return;
        }
        if (body_springs && file_index.empty()) {
          for (std::size_t k = 0; k < out.size(); ++k) file_index.push_back(k);
        }
        if (body_springs) file_index.push_back(s);
        out.push_back(read_spring(r, element("springs", s), springs[s], scene.particles));
      },
      file_index);
}

void validate_springs(const Scene& scene, const Reporter& r) {
  const Springs& springs = scene.get<Springs>();
  const std::size_t n = scene.particles.size();
  check_springs_in_order(r, springs, springs.size(), n, [&](std::size_t s) {
    const std::string where = element("springs", s);
    const Spring& spring = springs[s];
    check_particle_index(r, where, "i", spring.i, n);
    check_particle_index(r, where, "j", spring.j, n);
    check_not_self(r, where, spring);
    check_nonnegative(r, field(where, "k"), spring.k);
    check_nonnegative(r, field(where, "rest"), spring.rest);
    check_nonnegative(r, field(where, "damping"), spring.damping);
    check_spring_ends(r, where, spring, scene.particles, /*rest_given=*/true);
  });
}

// "springs" is required, so it is written even when empty.
void write_springs(const Scene& scene, std::vector<std::pair<std::string, std::string>>& entries) {
  JsonLines lines;
  for (const Spring& spring : scene.get<Springs>()) {
    std::string item = "{\"i\": " + std::to_string(spring.i) + ", \"j\": " +
                       std::to_string(spring.j) + ", \"k\": " + json_number(spring.k) +
                       ", \"rest\": " + json_number(spring.rest);
    if (spring.damping != 0) item += ", \"damping\": " + json_number(spring.damping);
    lines.add(item + "}");
  }
  entries.emplace_back("springs", lines.str());
}

// Springs between most pairs of particles (free-free and free-fixed), with
// random stiffness: zero rest length (linear), stretched and, unless the
// states must be definite, compressed (negative transverse stiffness).
void add_random_springs(Scene& scene, std::mt19937& rng, RandomStates states) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Springs& springs = scene.block<Springs>();
  const int n = static_cast<int>(scene.particles.size());
  for (int i = 0; i < n; ++i) {
    for (int j = i + 1; j < n; ++j) {
      if ((i + j) % 3 == 0) continue;  // not every pair: a sparse pattern
      const double l = (scene.particles[i].x - scene.particles[j].x).norm();
      const double shape = u(rng);
      Spring s;
      s.i = i;
      s.j = j;
      s.k = 10.0 + 20.0 * u(rng);
      if (shape < 0.2) {
        s.rest = 0.0;
      } else if (shape < 0.6 || states == RandomStates::kDefinite) {
        s.rest = l * (0.5 + 0.4 * u(rng));  // stretched
      } else {
        s.rest = l * (1.1 + 0.5 * u(rng));  // compressed
      }
      springs.push_back(s);
    }
  }
}

std::size_t count_springs(const Scene& scene) { return scene.get<Springs>().size(); }

void spring_cells(const Scene& scene, std::vector<Cell>& out) {
  for (const Spring& s : scene.get<Springs>()) out.push_back({.size = 2, .nodes = {s.i, s.j, 0, 0}});
}

}  // namespace

const ElementKind& spring_kind() {
  static const ElementKind kind = {
      .name = "spring",
      .refers_to_particles = true,
      .keys = {{.name = "springs", .required = true, .cap = kMaxSceneSprings,
                .count = count_springs}},
      .read = read_springs,
      .validate = validate_springs,
      .write = write_springs,
      .make = make_spring_force,
      .energy = {.name = "spring", .always = true, .counts_with_spring = true},
      .memory = spring_memory,
      .cells = spring_cells,
      .add_random = add_random_springs,
  };
  return kind;
}

}  // namespace springlab
