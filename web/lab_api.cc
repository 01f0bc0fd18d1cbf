// The lab page's interface to the C++ core (docs/browser-lab.md "The page's
// API"): C functions exported from the WebAssembly module, called by
// web/lab.js. Settings and results cross as JSON text; a panel's positions
// as a pointer into the module's memory (read as a Float64Array, no copy).
// An error (a bad parameter, an unknown method) comes back as
// {"error": "the command line's message"}.
#include <emscripten/emscripten.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <set>
#include <stdexcept>
#include <string>

#include "experiments/io/body_output.h"
#include "experiments/driver/simulation.h"
#include "integrators/registry/registry.h"
#include "models/scenes/builtin_scenes.h"
#include "models/contact/contact.h"
#include "models/fem/fem.h"
#include "models/fluids/fluids.h"
#include "models/springs/gravity.h"
#include "models/springs/springs.h"
#include "web/lab_panel.h"

namespace springlab {
namespace {

using Json = nlohmann::json;

// The text the last call returns: valid until the next call.
std::string& reply() {
  static std::string text;
  return text;
}
const char* answer(const Json& j) {
  reply() = j.dump();
  return reply().c_str();
}
const char* error_answer(const std::string& what) { return answer(Json{{"error", what}}); }

// A JSON number, or null for infinity and NaN (which JSON has no words for).
Json number(double value) { return std::isfinite(value) ? Json(value) : Json(nullptr); }

// "params": {"n": 8, "k": "1000"} -> the command line's -p pairs, as typed.
std::vector<std::pair<std::string, std::string>> scene_params(const Json& request) {
  std::vector<std::pair<std::string, std::string>> pairs;
  if (!request.contains("params")) return pairs;
  for (const auto& [key, value] : request.at("params").items()) {
    pairs.emplace_back(key, value.is_string() ? value.get<std::string>() : value.dump());
  }
  return pairs;
}

// The method options the page sets; absent: the method's defaults (the
// command line's).
IntegratorOptions integrator_options(const Json& request) {
  IntegratorOptions options;
  if (request.contains("iterations")) options.iterations = request.at("iterations").get<int>();
  if (request.contains("substeps")) options.substeps = request.at("substeps").get<int>();
  if (request.contains("newton_tol")) options.newton_tol = request.at("newton_tol").get<double>();
  return options;
}

Json integrator_json(const Integrator& method) {
  const IntegratorInfo& info = method.info();
  return Json{{"name", info.name},
              {"scheme", info.scheme},
              {"order", info.order},
              {"implicit", info.implicit},
              {"symplectic", info.symplectic},
              {"adaptive", info.adaptive},
              {"jacobian_free", info.jacobian_free},
              {"stability", to_string(info.stability)},
              {"stability_text", stability_text(info)},
              // Largest stable w h undamped; null: no limit (A-, L-stable) or
              // not one number.
              {"stability_limit", number(info.stability_limit)},
              {"unconditionally_stable", stable_on_imaginary_axis(info)},
              {"options", method.options_read()}};
}

Json positions_json(const Model& model, const Vector& x) {
  const Eigen::MatrixXd rows = model.scene_positions(x);
  Json out = Json::array();
  for (Eigen::Index s = 0; s < rows.rows(); ++s) {
    Json row = Json::array();
    for (Eigen::Index r = 0; r < rows.cols(); ++r) row.push_back(rows(s, r));
    out.push_back(row);
  }
  return out;
}

// What the page draws: each spring and each element edge once.
Json edges_json(const Scene& scene) {
  std::set<std::pair<int, int>> edges;
  auto add = [&](int a, int b) { edges.emplace(std::min(a, b), std::max(a, b)); };
  for (const Spring& s : scene.get<Springs>()) add(s.i, s.j);
  for (const Triangle& t : scene.get<Triangles>()) {
    for (int e = 0; e < 3; ++e) add(t.nodes[e], t.nodes[(e + 1) % 3]);
  }
  for (const Tetrahedron& t : scene.get<Tetrahedra>()) {
    for (int a = 0; a < 4; ++a) {
      for (int b = a + 1; b < 4; ++b) add(t.nodes[a], t.nodes[b]);
    }
  }
  Json out = Json::array();
  for (const auto& [a, b] : edges) out.push_back({a, b});
  return out;
}

// The fluids' moving particles (scene indices), coloured by speed, and
// their smallest spacing l (the dots' size); their fixed wall particles are
// among the scene's fixed ones.
Json fluid_json(const Scene& scene) {
  Json particles = Json::array();
  double spacing = 0.0;
  for (const Fluid& f : scene.get<Fluids>()) {
    for (int s = f.first; s < f.first + f.count; ++s) {
      if (!scene.particles[s].fixed) particles.push_back(s);
    }
    spacing = spacing > 0.0 ? std::min(spacing, f.spacing) : f.spacing;
  }
  return {{"particles", particles}, {"spacing", spacing}};
}

// The contact planes (the ground, a slope), drawn as lines: a point and the normal.
Json planes_json(const Scene& scene) {
  Json out = Json::array();
  for (const Plane& plane : scene.get<Planes>()) {
    const Eigen::Vector3d n = plane.normal.normalized();
    out.push_back({{"point", {plane.point.x(), plane.point.y(), plane.point.z()}},
                   {"normal", {n.x(), n.y(), n.z()}}});
  }
  return out;
}

std::map<int, std::unique_ptr<LabPanel>>& panels() {
  static std::map<int, std::unique_ptr<LabPanel>> all;
  return all;
}
LabPanel* find_panel(int id) {
  const auto it = panels().find(id);
  return it == panels().end() ? nullptr : it->second.get();
}

}  // namespace
}  // namespace springlab

using namespace springlab;

extern "C" {

// {"integrators": [...], "scenes": [...], "build": {...}}: what this build has.
EMSCRIPTEN_KEEPALIVE const char* lab_list() {
  Json methods = Json::array();
  for (const std::string& name : integrator_names()) {
    methods.push_back(integrator_json(*make_integrator(name)));
  }
  Json scenes = Json::array();
  for (const BuiltinScene& s : builtin_scenes()) {
    Json parameters = Json::array();
    for (const SceneParameter& p : s.parameters) {
      Json parameter = {{"name", p.name}, {"default", p.default_value}, {"meaning", p.meaning}};
      if (!p.choices.empty()) parameter["choices"] = p.choices;  // the default: their index
      parameters.push_back(parameter);
    }
    scenes.push_back({{"name", s.name}, {"description", s.description}, {"parameters", parameters}});
  }
  return answer({{"integrators", methods},
                 {"scenes", scenes},
                 {"build",
                  {{"sundials", false},
                   {"positive_definite_solver", "Eigen SimplicialLLT (AMD ordering)"}}}});
}

// `springlab run SCENE -p ... --integrator I --dt DT --t-end T --json`'s
// run: {"scene", "params", "integrator", "dt", "t_end" (or "steps": t_end =
// steps x dt), options} -> {"status", "diverged_at", "t_final", "steps",
// "energy_initial", "energy_final", "x": final positions, "v"}.
EMSCRIPTEN_KEEPALIVE const char* lab_run(const char* request_text) {
  try {
    const Json request = Json::parse(request_text);
    const Model model(
        make_builtin_scene(request.at("scene").get<std::string>(), scene_params(request)));
    RunSettings settings;
    settings.integrator = request.at("integrator").get<std::string>();
    settings.dt = request.at("dt").get<double>();
    settings.t_end = request.contains("t_end")
                         ? request.at("t_end").get<double>()
                         : static_cast<double>(request.at("steps").get<long>()) * settings.dt;
    if (request.contains("blowup")) settings.blowup = request.at("blowup").get<double>();
    settings.options = integrator_options(request);
    // As the command line: options the method cannot take, then a pairing it refuses.
    if (std::string why = make_integrator(settings.integrator)->check_options(settings.options,
                                                                              model.dofs());
        !why.empty()) {
      throw std::invalid_argument(why);
    }
    auto integrator = prepare_integrator(model, settings);
    const RunResult r = simulate(model, settings, {}, std::move(integrator));
    return answer({{"scene", request.at("scene")},
                   {"integrator", r.integrator},
                   {"dt", r.dt},
                   {"t_end", r.t_end},
                   {"status", to_string(r.status)},
                   {"diverged", r.diverged()},
                   {"diverged_at", r.diverged_at ? Json(*r.diverged_at) : Json(nullptr)},
                   {"failure", r.failure.empty() ? Json(nullptr) : Json(r.failure)},
                   {"steps", r.stats.steps},
                   {"t_final", r.t_final},
                   {"energy_initial", r.energy_initial},
                   {"energy_final", r.energy_final},
                   {"x", positions_json(model, r.x_final)},
                   // As `springlab run --json`'s "bodies" (body_output.h).
                   {"bodies", bodies_json(model, r.x_final, r.v_final)}});
  } catch (const std::exception& e) {
    return error_answer(e.what());
  }
}

// A live panel: {"scene", "params", "integrator", options} -> {"id", what
// the page draws ("particles"; "points": the particles, then the bodies'
// surface vertices; "edges", "faces" (the bodies' triangles), "fixed",
// "fluid", "planes"), "w_max", the method's info}.
EMSCRIPTEN_KEEPALIVE const char* lab_panel_new(const char* request_text) {
  static int next_id = 1;
  try {
    const Json request = Json::parse(request_text);
    PanelSettings settings;
    settings.scene = request.at("scene").get<std::string>();
    settings.params = scene_params(request);
    settings.integrator = request.at("integrator").get<std::string>();
    settings.options = integrator_options(request);
    if (request.contains("w_max")) settings.w_max = request.at("w_max").get<double>();
    auto panel = std::make_unique<LabPanel>(settings);
    const Model& model = panel->model();
    Json fixed = Json::array();
    for (std::size_t p = 0; p < model.scene().particles.size(); ++p) {
      if (model.scene().particles[p].fixed) fixed.push_back(p);
    }
    const int id = next_id++;
    Json info = {{"id", id},
                 {"particles", model.particle_count()},
                 {"points", panel->points()},
                 {"faces", panel->body_faces()},
                 {"fluid", fluid_json(model.scene())},
                 {"planes", planes_json(model.scene())},
                 {"gravity", [&] {
                    const Eigen::Vector3d& g = model.scene().get<Gravity>().acceleration;
                    return Json::array({g.x(), g.y(), g.z()});
                  }()},
                 {"dimension", model.dimension()},
                 {"fixed", fixed},
                 {"edges", edges_json(model.scene())},
                 {"w_max", panel->w_max()},
                 {"energy_scale", model.energy_scale()},
                 {"cursor_stiffness", panel->cursor().stiffness()},
                 {"integrator", integrator_json(panel->integrator())}};
    panels()[id] = std::move(panel);
    return answer(info);
  } catch (const RunRefused& e) {
    // The scene setting that makes the pairing work travels as data
    // (models/core/refusal.h); the page offers it where the scene has a
    // parameter of that name, as the command line does.
    Json out = {{"error", e.what()}};
    if (!e.remedy().empty()) {
      out["remedy"] = {{"field", e.remedy().field},
                       {"value", e.remedy().value},
                       {"meaning", e.remedy().meaning}};
    }
    return answer(out);
  } catch (const std::exception& e) {
    return error_answer(e.what());
  }
}

EMSCRIPTEN_KEEPALIVE void lab_panel_delete(int id) { panels().erase(id); }

// Up to `steps` steps of dt: the number taken (fewer when the run diverged
// or failed), -1 for an unknown panel or a bad dt.
EMSCRIPTEN_KEEPALIVE long lab_panel_step(int id, long steps, double dt) {
  LabPanel* panel = find_panel(id);
  if (panel == nullptr || !(dt > 0.0) || !std::isfinite(dt)) return -1;
  return panel->step(steps, dt);
}

// {"t", "steps", "status", "diverged_at", "failure", "kinetic", "total"}.
EMSCRIPTEN_KEEPALIVE const char* lab_panel_state(int id) {
  LabPanel* panel = find_panel(id);
  if (panel == nullptr) return error_answer("no panel " + std::to_string(id));
  return answer({{"t", panel->t()},
                 {"steps", panel->steps_taken()},
                 {"status", to_string(panel->status())},
                 {"diverged_at", panel->diverged_at() ? Json(*panel->diverged_at()) : Json(nullptr)},
                 {"failure", panel->failure().empty() ? Json(nullptr) : Json(panel->failure())},
                 {"kinetic", number(panel->kinetic_energy())},
                 {"total", number(panel->total_energy())}});
}

// The last good state's positions: x y z per point (z = 0 in 2-D): the
// scene's particles, then the bodies' surface vertices.
EMSCRIPTEN_KEEPALIVE const double* lab_panel_positions(int id) {
  LabPanel* panel = find_panel(id);
  return panel == nullptr ? nullptr : panel->positions().data();
}

// The last good state's speeds |v|, one per point.
EMSCRIPTEN_KEEPALIVE const double* lab_panel_speeds(int id) {
  LabPanel* panel = find_panel(id);
  return panel == nullptr ? nullptr : panel->speeds().data();
}

// Pulls scene particle `particle` toward (x, y, z); 0 when it cannot be
// pulled (fixed, out of range).
EMSCRIPTEN_KEEPALIVE int lab_panel_grab(int id, int particle, double x, double y, double z) {
  LabPanel* panel = find_panel(id);
  return panel != nullptr && panel->cursor().grab(particle, Eigen::Vector3d(x, y, z)) ? 1 : 0;
}

EMSCRIPTEN_KEEPALIVE void lab_panel_release(int id) {
  if (LabPanel* panel = find_panel(id)) panel->cursor().release();
}

}  // extern "C"
