#include "experiments/kinds/accuracy_sweep.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "experiments/io/output_files.h"
#include "integrators/registry/registry.h"
#include "models/springs/springs.h"

namespace springlab {

AccuracySweep read_accuracy_sweep(const DefinitionObject& d) {
  AccuracySweep sweep;
  sweep.atol_factor = d.positive("atol_factor", sweep.atol_factor);
  for (const std::string& name : definition_integrators(d, "integrators", "all")) {
    SweepMethod m{name, make_integrator(name)->info(), {}};
    m.values = accuracy_sweep_values(d, m.info);
    if (!m.info.adaptive) {
      const double finest = m.values.back();
      sweep.finest_dt = sweep.finest_dt > 0.0 ? std::min(sweep.finest_dt, finest) : finest;
    }
    sweep.methods.push_back(std::move(m));
  }
  return sweep;
}

nlohmann::json sweeps_json(const std::vector<SweepMethod>& methods) {
  nlohmann::json names = nlohmann::json::array();
  nlohmann::json sweeps = nlohmann::json::object();
  for (const SweepMethod& m : methods) {
    names.push_back(m.name);
    sweeps[m.name] = {{"adaptive", m.info.adaptive},
                      {"parameter", m.info.adaptive ? "rtol" : "dt"},
                      {"values", m.values}};
  }
  return {{"integrators", names}, {"sweeps", sweeps}};
}

// Reads a reference: "exact" (the oscillator's exact solution; refused with a
// message naming the element when the scene is not that oscillator) or
// {"integrator": NAME, "dt": H} (a fixed-step run, H below finest_dt, the
// smallest step of the sweep; 0 = no fixed-step method in the sweep).
// Returns it normalized: "exact" or {"integrator", "dt"}.
nlohmann::json accuracy_reference(const DefinitionObject& o, const char* key, const Scene& scene,
                                  double finest_dt) {
  if (!o.has(key)) o.fail(key, "missing (\"exact\" or {\"integrator\": \"rk4\", \"dt\": 1e-5})");
  const nlohmann::json& raw = o.raw(key);
  if (raw.is_string()) {
    if (raw.get<std::string>() != "exact") {
      o.fail(key, "expected \"exact\" or {\"integrator\": NAME, \"dt\": H}");
    }
    bool exact = exact_oscillator_positions(scene, 0.0).has_value();
    if (exact) {
      // With rest > 0 the formula holds only while the spring keeps a positive length.
      const Spring& spring = scene.get<Springs>()[0];
      const double l0 = (scene.particles[0].x - scene.particles[1].x).norm();
      exact = spring.rest == 0.0 || std::abs(l0 - spring.rest) < spring.rest;
    }
    if (!exact) {
      o.fail(key, "\"exact\" needs the oscillator (one free particle on one undamped spring, "
                  "released at rest, no other force, never passing the anchor); scene '" +
                      scene.name + "' is not one: use {\"integrator\": \"rk4\", \"dt\": 1e-5}");
    }
    return "exact";
  }
  if (!raw.is_object()) o.fail(key, "expected \"exact\" or {\"integrator\": NAME, \"dt\": H}");
  const DefinitionObject r = o.object(key);
  r.allow_only({"integrator", "dt"});
  const std::string name = r.string("integrator");
  if (!is_integrator(name)) {
    r.fail("integrator", integrator_registry().unknown("integrator", printable(name)));
  }
  if (make_integrator(name)->info().adaptive) {
    r.fail("integrator", "'" + name + "' is adaptive; the reference must be a fixed-step method");
  }
  const double dt = r.positive("dt");
  if (finest_dt > 0.0 && !(dt < finest_dt)) {
    r.fail("dt", "must be below the smallest step of the sweep (" + format_number(finest_dt) +
                     "), got " + format_number(dt));
  }
  return {{"integrator", name}, {"dt", dt}};
}

// The reference positions of the free unknowns at t_end. Throws
// std::runtime_error, its message starting with `where` (the definition's
// element), when the reference run does not complete.
Vector accuracy_reference_positions(const nlohmann::json& reference, const Model& model,
                                    const Scene& scene, double t_end,
                                    const IntegratorOptions& options, const std::string& where) {
  if (reference.is_string()) {
    const std::optional<Vector> x = exact_oscillator_positions(scene, t_end);
    if (!x) throw std::runtime_error(where + ": scene '" + scene.name + "' has no exact solution");
    return *x;
  }
  RunSettings s;
  s.integrator = reference.at("integrator").get<std::string>();
  s.dt = reference.at("dt").get<double>();
  s.t_end = t_end;
  s.options = options;
  const RunResult r = simulate(model, s);
  if (r.status != RunStatus::kCompleted) {
    throw std::runtime_error(where + ": the reference run (" + s.integrator + ", dt " +
                             format_number(s.dt) + ") on scene '" + scene.name + "' " +
                             to_string(r.status) + " at t = " +
                             format_number(r.diverged_at.value_or(r.t_final)) +
                             (r.failure.empty() ? "" : ": " + r.failure));
  }
  return r.x_final;
}

// The sweep of one method: for a fixed-step one, base_dt (by its order) and
// `halvings` - 1 halvings of it; for an adaptive one, the `tolerances` (rtol).
// Validates halvings, tolerances and base_dt when present.
std::vector<double> accuracy_sweep_values(const DefinitionObject& d, const IntegratorInfo& info) {
  const int halvings = d.count("halvings", 5, 2, 40);
  std::vector<double> tolerances = {1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9};
  if (d.has("tolerances")) tolerances = d.positives("tolerances");
  if (d.has("base_dt")) {
    if (d.object("base_dt").json().empty()) {
      d.fail("base_dt",
             "expected steps by method order, e.g. {\"1\": 2e-3, \"2\": 1e-2, \"4\": 4e-2}");
    }
    base_dt_for_order(d, "base_dt", std::numeric_limits<int>::max());  // validates every entry
  }
  for (std::size_t k = 0; k < tolerances.size(); ++k) {
    if (tolerances[k] >= 1.0) {
      d.fail("tolerances[" + std::to_string(k) + "]", "must be below 1 (a relative tolerance)");
    }
  }
  if (info.adaptive) return tolerances;
  double dt = base_dt_for_order(d, "base_dt", info.order);
  std::vector<double> steps;
  for (int k = 0; k < halvings; ++k, dt /= 2) steps.push_back(dt);
  return steps;
}

// One point of a sweep: a fixed-step run at dt = value, or an adaptive run at
// rtol = value, atol = value * atol_factor (output only at t_end).
RunResult accuracy_run(const Model& model, const std::string& integrator, bool adaptive,
                       double value, double t_end, const IntegratorOptions& options,
                       double atol_factor) {
  RunSettings s;
  s.integrator = integrator;
  s.t_end = t_end;
  s.options = options;
  if (adaptive) {
    s.dt = t_end;
    s.options.rtol = value;
    s.options.atol = value * atol_factor;
  } else {
    s.dt = value;
  }
  return simulate(model, s);
}

std::optional<Vector> exact_oscillator_positions(const Scene& s, double t) {
  // Two particles, and of all the element kinds only one spring acts.
  const Springs& springs = s.get<Springs>();
  if (s.particles.size() != 2 || springs.size() != 1) return std::nullopt;
  const Model model(s);
  for (const auto& term : model.terms()) {
    if (term->name() != "spring") return std::nullopt;
  }
  const int fixed = s.particles[0].fixed ? 0 : 1;
  const Particle& anchor = s.particles[static_cast<std::size_t>(fixed)];
  const Particle& mass = s.particles[static_cast<std::size_t>(1 - fixed)];
  if (!anchor.fixed || mass.fixed || !mass.v.isZero()) return std::nullopt;
  const Eigen::Vector3d d = mass.x - anchor.x;
  const double l = d.norm();
  const double rest = springs[0].rest;
  const double w = std::sqrt(springs[0].k / mass.mass);
  // Along the spring axis u: l(t) = rest + (l0 - rest) cos(w t) (linear while l > 0).
  const Eigen::Vector3d x = anchor.x + d / l * (rest + (l - rest) * std::cos(w * t));
  return Vector(x.head(s.dimension));
}

double position_error(const Vector& x, const Vector& x_ref) {
  return (x - x_ref).lpNorm<Eigen::Infinity>();
}

std::optional<double> log_log_slope(const std::vector<double>& x, const std::vector<double>& y,
                                    double floor) {
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  int n = 0;
  for (std::size_t k = 0; k < x.size() && k < y.size(); ++k) {
    if (!(std::isfinite(y[k]) && y[k] > floor && x[k] > 0)) continue;
    const double lx = std::log(x[k]), ly = std::log(y[k]);
    sx += lx;
    sy += ly;
    sxx += lx * lx;
    sxy += lx * ly;
    ++n;
  }
  if (n < 2) return std::nullopt;
  const double denominator = n * sxx - sx * sx;
  if (denominator == 0.0) return std::nullopt;
  return (n * sxy - sx * sy) / denominator;
}

double base_dt_for_order(const DefinitionObject& o, const char* key, int order) {
  const DefinitionObject table = o.object(key);
  double best = 0.0;
  int best_order = 0;
  for (const auto& [name, value] : table.json().items()) {
    int k = 0;
    std::size_t end = 0;
    try {
      k = std::stoi(name, &end);
    } catch (const std::exception&) {
      end = 0;
    }
    if (end == 0 || end != name.size() || k < 1 || name[0] == '+') {
      table.fail(name, "keys are method orders (1, 2, 4, ...)");
    }
    const double dt = table.positive(name.c_str());
    if (k <= order && k > best_order) {
      best_order = k;
      best = dt;
    }
  }
  if (best_order == 0) o.fail(key, "has no entry for order " + std::to_string(order) + " or below");
  return best;
}

}  // namespace springlab
