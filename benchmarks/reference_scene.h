// reference_scene.h: what the plain reference programs of benchmarks/
// (xpbd_reference.cc, pd_reference.cc, newton_reference.cc,
// lbfgs_reference.cc, vbd_reference.cc) share, so that each file holds its method and little
// else: the command line, the mass-spring scene file, the energies, the time
// loop with the divergence test `springlab run` applies, the springs'
// Laplacian matrix, and the output (one JSON line, the final positions).
// Plain C++ with nlohmann::json and Eigen: no springlab header or library,
// so a reference checks springlab from outside.
//
// How a reference uses it (pd_reference.cc is a short example; add the
// program to benchmarks/CMakeLists.txt beside the others):
//   reference::CommandLine args;  // SCENE.json --dt H --t-end T
//   std::string positions_file;   // and its own options
//   if (!reference::read_command_line("my_reference", argc, argv, {{"--positions", "FILE", &positions_file}},
//                                     args)) {
//     return 2;
//   }
//   reference::Scene scene;  // what it does not model (Models) comes back as a Refusal, for it to word
//   if (const reference::Refusal refusal = reference::read_scene(args.scene, {}, scene); refusal.refused()) {
//     std::fprintf(stderr, "my_reference: error: %s: %s: not modelled\n", args.scene, refusal.key.c_str());
//     return 2;
//   }
//   std::vector<double> x = scene.x, v = scene.v;  // scene order, scene.D numbers per particle
//   auto energy = [&] { return reference::spring_energy(scene, x, reference::kinetic_energy(scene, v)); };
//   reference::TimeLoop loop(args.dt, args.t_end, reference::energy_scale(scene, energy()));
//   while (loop.running()) {
//     const double h = loop.h();
//     ... one step of the method from (x, v) ...
//     loop.step_done(h, energy());
//   }
//   if (!reference::write_positions(args.program, positions_file, scene, x)) return 1;
//   reference::print_summary(loop, energy() + reference::gravity_energy(scene, x), args.start,
//                            {{"x_sum", reference::number(reference::coordinate_sum(x))}});
#pragma once

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <initializer_list>
#include <string>
#include <utility>
#include <variant>
#include <vector>

#include <Eigen/SparseCore>
#include <nlohmann/json.hpp>

namespace reference {

// ---- The command line: PROGRAM SCENE.json --dt H --t-end T [--name value]... ----

// A reference's own option, the variable its value goes to (an int takes the
// number's integer part) and its value's name in the usage line.
struct Option {
  const char* name;  // "--tol"
  const char* meta;  // "TOL"
  std::variant<double*, int*, std::string*> into;
};

// What every reference reads from its command line.
struct CommandLine {
  const char* program = "";  // the reference's name, for its messages
  const char* scene = "";    // the scene file
  double dt = 1.0 / 60.0;    // --dt H: the step [s]
  double t_end = 1.0;        // --t-end T: the end of the run [s]
  std::chrono::steady_clock::time_point start;  // when it was read; the output's "seconds" count from there
};

// Reads `args`, then the reference's `options`; false after one line on
// stderr (without a scene file the usage, "usage: PROGRAM SCENE.json --dt H
// --t-end T [--name META]...", else "unknown option --x" for a name it does
// not know, "PROGRAM: an option lacks its value" for a name without one at
// the end): the reference then exits with status 2.
inline bool read_command_line(const char* program, int argc, char** argv, std::initializer_list<Option> options,
                              CommandLine& args) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: %s SCENE.json --dt H --t-end T", program);
    for (const Option& o : options) std::fprintf(stderr, " [%s %s]", o.name, o.meta);
    std::fprintf(stderr, "\n");
    return false;
  }
  args.program = program;
  args.scene = argv[1];
  if (argc % 2 != 0) {
    std::fprintf(stderr, "%s: an option lacks its value\n", program);
    return false;
  }
  for (int a = 2; a + 1 < argc; a += 2) {
    const std::string key = argv[a];
    const double value = std::atof(argv[a + 1]);
    if (key == "--dt") {
      args.dt = value;
      continue;
    }
    if (key == "--t-end") {
      args.t_end = value;
      continue;
    }
    const Option* option = std::find_if(options.begin(), options.end(),
                                        [&](const Option& o) { return key == o.name; });
    if (option == options.end()) {
      std::fprintf(stderr, "unknown option %s\n", key.c_str());
      return false;
    }
    if (double* const* d = std::get_if<double*>(&option->into)) **d = value;
    if (int* const* i = std::get_if<int*>(&option->into)) **i = static_cast<int>(value);
    if (std::string* const* text = std::get_if<std::string*>(&option->into)) **text = argv[a + 1];
  }
  args.start = std::chrono::steady_clock::now();
  return true;
}

// ---- The scene file (docs/physics.md "Scene files"): particles, springs, gravity, drag, wind ----

struct Spring {
  int i, j;        // the particles it joins (scene indices)
  double k, rest;  // stiffness [N/m]; rest length L [m]: the file's, else the initial |x_i - x_j|
  double damping;  // along the spring [N s/m]; 0 where the reference does not model it
};

struct Wind {  // w(t) = velocity (1 + gust sin(2 pi frequency t)), force coefficient (w(t) - v)
  double velocity[3] = {0.0, 0.0, 0.0};
  double coefficient = 0.0, gust = 0.0, frequency = 0.0;
};

struct Scene {
  int D = 0;                    // the dimension: particle i's coordinates are x[i * D + r], r < D
  int n = 0;                    // the particles
  std::vector<double> x, v;     // their initial positions and velocities, scene order (v = 0 if fixed)
  std::vector<double> m;        // their masses [kg]
  std::vector<int> row;         // the particle's number among the free ones (scene order); -1: fixed
  int free = 0;                 // how many are free
  std::vector<Spring> springs;  // in the file's order
  double g[3] = {0.0, 0.0, 0.0};  // gravity [m/s^2]
  double drag = 0.0;            // the drag force -drag v on every particle [kg/s]
  Wind wind;                    // zero without one

  bool fixed(int i) const { return row[i] < 0; }
};

// What a reference models; read_scene refuses the rest. The defaults:
// gravity, drag, springs and fixed particles only.
struct Models {
  bool ignore_other_keys = false;  // false: refuse any key but name, dimension, gravity, drag, particles, springs
  int dimension = 0;               // 0: the file's; else refuse another
  bool spring_damping = false;     // false: refuse a spring with damping
  bool wind = false;               // false: refuse a wind
};

// Why read_scene refused a scene, as data: the reference words its message.
enum class Unmodelled { kNothing, kKey, kDimension, kSpringDamping, kWind };
struct Refusal {
  Unmodelled what = Unmodelled::kNothing;
  std::string key;  // the file's key: the unmodelled one, "dimension", "springs" or "wind"
  bool refused() const { return what != Unmodelled::kNothing; }
};

// Coordinate r of a JSON vector, 0 past its end.
inline double component(const nlohmann::json& j, int r) {
  return r < static_cast<int>(j.size()) ? j[r].get<double>() : 0.0;
}

// Reads the scene file at `path` into `scene`, or says what of it `models`
// leaves out (first found first: other keys, the dimension, a damped spring,
// the wind). A file that is no JSON or lacks a key throws nlohmann's
// exception.
inline Refusal read_scene(const char* path, const Models& models, Scene& scene) {
  std::ifstream file(path);
  const nlohmann::json j = nlohmann::json::parse(file);
  if (!models.ignore_other_keys) {
    for (const auto& [key, value] : j.items()) {
      if (key != "name" && key != "dimension" && key != "gravity" && key != "drag" && key != "particles" &&
          key != "springs") {
        return {Unmodelled::kKey, key};
      }
    }
  }
  const int D = scene.D = j.at("dimension").get<int>();
  if (models.dimension != 0 && D != models.dimension) return {Unmodelled::kDimension, "dimension"};
  const int n = scene.n = static_cast<int>(j.at("particles").size());
  scene.x.assign(n * D, 0.0);
  scene.v.assign(n * D, 0.0);
  scene.m.assign(n, 0.0);
  scene.row.assign(n, -1);
  scene.free = 0;
  for (int i = 0; i < n; ++i) {
    const nlohmann::json& q = j["particles"][i];
    scene.m[i] = q.value("mass", 1.0);
    if (!q.value("fixed", false)) scene.row[i] = scene.free++;
    for (int r = 0; r < D; ++r) {
      scene.x[i * D + r] = component(q["x"], r);
      if (q.contains("v") && !scene.fixed(i)) scene.v[i * D + r] = component(q["v"], r);
    }
  }
  const std::vector<double>& x = scene.x;
  scene.springs.clear();
  for (const nlohmann::json& s : j.at("springs")) {
    const int a = s.at("i").get<int>(), b = s.at("j").get<int>();
    double rest = 0.0;
    if (s.contains("rest")) {
      rest = s["rest"].get<double>();
    } else {
      for (int r = 0; r < D; ++r) rest += (x[a * D + r] - x[b * D + r]) * (x[a * D + r] - x[b * D + r]);
      rest = std::sqrt(rest);
    }
    if (!models.spring_damping && s.value("damping", 0.0) != 0.0) return {Unmodelled::kSpringDamping, "springs"};
    const double k = s.at("k").get<double>();
    scene.springs.push_back({a, b, k, rest, models.spring_damping ? s.value("damping", 0.0) : 0.0});
  }
  if (!models.wind && j.contains("wind")) return {Unmodelled::kWind, "wind"};
  scene.drag = j.value("drag", 0.0);
  if (j.contains("gravity")) for (int r = 0; r < D; ++r) scene.g[r] = component(j["gravity"], r);
  if (models.wind && j.contains("wind")) {
    const nlohmann::json& w = j["wind"];
    for (int r = 0; r < D; ++r) scene.wind.velocity[r] = component(w.at("velocity"), r);
    scene.wind.coefficient = w.value("coefficient", 0.0);
    scene.wind.gust = w.value("gust", 0.0);
    scene.wind.frequency = w.value("frequency", 0.0);
  }
  return {};
}

// ---- Energies (positions and velocities in scene order, D per particle) ----

// e + the kinetic energy sum over the free particles of m |v|^2 / 2. (The
// `e +` lets a reference choose the order of its sums: a different order
// rounds differently, and the reference's printed numbers would change.)
inline double kinetic_energy(const Scene& s, const std::vector<double>& v, double e = 0.0) {
  for (int i = 0; i < s.n; ++i) {
    if (s.fixed(i)) continue;
    for (int r = 0; r < s.D; ++r) e += 0.5 * s.m[i] * v[i * s.D + r] * v[i * s.D + r];
  }
  return e;
}

// e + the springs' energy E(x) = sum over springs of k/2 (|x_i - x_j| - L)^2.
inline double spring_energy(const Scene& s, const std::vector<double>& x, double e = 0.0) {
  const int D = s.D;
  for (const Spring& sp : s.springs) {
    double l = 0.0;
    for (int r = 0; r < D; ++r) l += (x[sp.i * D + r] - x[sp.j * D + r]) * (x[sp.i * D + r] - x[sp.j * D + r]);
    const double stretch = std::sqrt(l) - sp.rest;
    e += 0.5 * sp.k * stretch * stretch;
  }
  return e;
}

// Gravity's potential -sum over the free particles of m g . x.
inline double gravity_energy(const Scene& s, const std::vector<double>& x) {
  double e = 0.0;
  for (int i = 0; i < s.n; ++i) {
    if (s.fixed(i)) continue;
    for (int r = 0; r < s.D; ++r) e -= s.m[i] * s.g[r] * x[i * s.D + r];
  }
  return e;
}

// The energy scale E_s the divergence test compares with, as springlab's
// (docs/command-line.md): e0 (the initial kinetic + spring energy) + sum over
// the free particles of m (|g| d + |w_max|^2 / 2), d the diameter of the
// initial positions' bounding box, |w_max| = |wind velocity| (1 + |gust|).
inline double energy_scale(const Scene& s, double e0) {
  double lo[3] = {1e300, 1e300, 1e300}, hi[3] = {-1e300, -1e300, -1e300};
  for (int i = 0; i < s.n; ++i) {
    for (int r = 0; r < s.D; ++r) {
      lo[r] = std::min(lo[r], s.x[i * s.D + r]);
      hi[r] = std::max(hi[r], s.x[i * s.D + r]);
    }
  }
  double diameter = 0.0, g_norm = 0.0, w_max = 0.0;
  for (int r = 0; r < s.D; ++r) {
    diameter += (hi[r] - lo[r]) * (hi[r] - lo[r]);
    g_norm += s.g[r] * s.g[r];
    w_max += s.wind.velocity[r] * s.wind.velocity[r];
  }
  diameter = std::sqrt(diameter);
  g_norm = std::sqrt(g_norm);
  w_max = std::sqrt(w_max) * (1.0 + std::abs(s.wind.gust));
  double scale = e0;
  for (int i = 0; i < s.n; ++i) {
    if (!s.fixed(i)) scale += s.m[i] * g_norm * diameter + 0.5 * s.m[i] * w_max * w_max;
  }
  return scale;
}

// ---- The time loop, as `springlab run`'s ----

// Steps of dt from t = 0 to t_end, the last one t_end - t (a t_end within
// 1e-9 steps of a whole number of steps is that number; else one more,
// shorter step); it stops after a step whose kinetic + spring energy E is not
// finite or passes 1000 E_s (springlab run's default --blowup):
//   TimeLoop loop(dt, t_end, E_s);
//   while (loop.running()) { const double h = loop.h(); ...; loop.step_done(h, E); }
struct TimeLoop {
  TimeLoop(double dt, double t_end, double scale) : dt(dt), t_end(t_end), scale(scale) {
    const double exact = t_end / dt;
    steps = std::abs(exact - std::round(exact)) <= 1e-9 ? std::lround(exact) : static_cast<long>(std::ceil(exact));
  }
  bool running() const { return taken < steps && !diverged; }
  double h() const { return taken + 1 == steps ? t_end - t : dt; }
  void step_done(double h, double energy) {
    t += h;
    ++taken;
    diverged = !std::isfinite(energy) || (scale > 0.0 && energy > 1000.0 * scale);
  }

  double dt, t_end, scale;
  long steps = 0;         // how many steps the run has
  double t = 0.0;         // the time reached
  long taken = 0;         // the steps taken
  bool diverged = false;  // the last step's energy failed the test
};

// ---- The springs' Laplacian (projective dynamics' matrix, L-BFGS's first Hessian) ----

// The lower triangle of M + h gamma I + h^2 L over the free particles (rows:
// Scene::row), L = sum over springs of k (e_i - e_j)(e_i - e_j)^T: a spring
// to a fixed particle puts only k on the free one's diagonal. One number a
// particle: the same matrix serves x, y and z.
inline Eigen::SparseMatrix<double> mass_spring_matrix(const Scene& s, double h, double gamma) {
  std::vector<Eigen::Triplet<double>> entries;
  for (int i = 0; i < s.n; ++i) {
    if (!s.fixed(i)) entries.emplace_back(s.row[i], s.row[i], s.m[i] + h * gamma);
  }
  for (const Spring& sp : s.springs) {
    const double w = h * h * sp.k;
    const int a = s.row[sp.i], b = s.row[sp.j];
    if (a >= 0) entries.emplace_back(a, a, w);
    if (b >= 0) entries.emplace_back(b, b, w);
    if (a >= 0 && b >= 0) entries.emplace_back(std::max(a, b), std::min(a, b), -w);  // the lower triangle
  }
  Eigen::SparseMatrix<double> A(s.free, s.free);
  A.setFromTriplets(entries.begin(), entries.end());
  return A;
}

// ---- The output ----

// The sum of all coordinates: a fingerprint of the run (x_sum).
inline double coordinate_sum(const std::vector<double>& x) {
  double sum = 0.0;
  for (double c : x) sum += c;
  return sum;
}

// With a file name, writes the positions x (scene order) there, one line
// "i,x,y[,z]" per particle (scene index, %.17g); false after "PROGRAM:
// cannot write FILE" on stderr (the reference then exits with status 1).
inline bool write_positions(const char* program, const std::string& file, const Scene& s,
                            const std::vector<double>& x) {
  if (file.empty()) return true;
  std::FILE* out = std::fopen(file.c_str(), "w");
  if (out == nullptr) {
    std::fprintf(stderr, "%s: cannot write %s\n", program, file.c_str());
    return false;
  }
  for (int i = 0; i < s.n; ++i) {
    std::fprintf(out, "%d", i);
    for (int r = 0; r < s.D; ++r) std::fprintf(out, ",%.17g", x[i * s.D + r]);
    std::fprintf(out, "\n");
  }
  std::fclose(out);
  return true;
}

// A number as the JSON line writes it (%.17g: it reads back exactly).
inline std::string number(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.17g", value);
  return text;
}

// The run's one JSON line on stdout:
//   {"steps": .., "diverged": .., "diverged_at": .., "energy_final": ..,
//    "seconds": .., then `more` in their order}
// seconds: the wall time since `start`; diverged_at: t or null.
inline void print_summary(const TimeLoop& loop, double energy_final, std::chrono::steady_clock::time_point start,
                          std::initializer_list<std::pair<const char*, std::string>> more) {
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf("{\"steps\": %ld, \"diverged\": %s, \"diverged_at\": %s, \"energy_final\": %.17g, \"seconds\": %.9g",
              loop.taken, loop.diverged ? "true" : "false", loop.diverged ? std::to_string(loop.t).c_str() : "null",
              energy_final, seconds);
  for (const auto& [name, value] : more) std::printf(", \"%s\": %s", name, value.c_str());
  std::printf("}\n");
}

}  // namespace reference
