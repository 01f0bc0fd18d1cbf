#include "experiments/experiment_support.h"

#include <cmath>
#include <string>

#include "experiments/output_files.h"

namespace springlab {

IntegratorOptions definition_options(const DefinitionObject& o) {
  IntegratorOptions options;
  options.rtol = o.positive("rtol", options.rtol);
  options.atol = o.positive("atol", options.atol);
  options.newton_tol = o.positive("newton_tol", options.newton_tol);
  return options;
}

std::string format_count(double value) {
  value = std::ceil(value);
  return value < 1e15 ? std::to_string(static_cast<long long>(value)) : format_number(value);
}

void check_task_count(const DefinitionObject& o, const std::string& key, double tasks) {
  if (tasks > static_cast<double>(kMaxExperimentTasks)) {
    o.fail(key, "the experiment would have " + format_count(tasks) + " tasks, over the cap of " +
                    std::to_string(kMaxExperimentTasks));
  }
}

void check_output_rows(const DefinitionObject& o, const std::string& key, double rows) {
  if (rows > static_cast<double>(kMaxExperimentRows)) {
    o.fail(key, "the experiment would hold " + format_count(rows) +
                    " output rows in memory, over the cap of " +
                    std::to_string(kMaxExperimentRows));
  }
}

void SceneTotals::add(const DefinitionObject& o, const std::string& key, const Scene& scene) {
  particles_ += scene.particles.size();
  springs_ += scene.springs.size();
  auto check = [&](std::size_t total, std::size_t cap, const char* what) {
    if (total > cap) {
      o.fail(key, "the experiment's scenes would hold " + std::to_string(total) + " " + what +
                      " in all, over the cap of " + std::to_string(cap));
    }
  };
  check(particles_, kMaxSceneParticles, "particles");
  check(springs_, kMaxSceneSprings, "springs");
}

std::vector<TimedCase> read_timed_cases(const DefinitionObject& d) {
  std::vector<TimedCase> cases;
  SceneTotals totals;
  for (const DefinitionObject& c : d.objects("cases")) {
    c.allow_only({"scene", "parameters", "dt", "t_end", "every"});
    cases.push_back({definition_scene(c), c.positive("dt"), c.positive("t_end"),
                     c.count("every", 1, 1, 1000000)});
    totals.add(c, "scene", cases.back().scene);
    check_time_grid(c, "dt", cases.back().dt, cases.back().t_end);
  }
  return cases;
}

void check_timed_case_rows(const DefinitionObject& d, const std::vector<TimedCase>& cases,
                           std::size_t integrators) {
  double rows = 0.0;
  for (std::size_t k = 0; k < cases.size(); ++k) {
    const TimedCase& c = cases[k];
    // t = 0, every K-th step, the last one (and a run summary row).
    const double steps = static_cast<double>(make_time_grid(c.dt, c.t_end).steps);
    rows += static_cast<double>(integrators) * (std::floor(steps / c.every) + 3.0);
    check_output_rows(d, "cases[" + std::to_string(k) + "]", rows);
  }
}

nlohmann::json timed_cases_json(const std::vector<TimedCase>& cases) {
  nlohmann::json out = nlohmann::json::array();
  for (const TimedCase& c : cases) {
    out.push_back({{"scene", scene_as_json(c.scene)}, {"dt", c.dt}, {"t_end", c.t_end},
                   {"every", c.every}});
  }
  return out;
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

nlohmann::json scene_as_json(const Scene& scene) { return nlohmann::json::parse(scene_to_json(scene)); }

std::optional<Vector> exact_oscillator_positions(const Scene& s, double t) {
  if (s.particles.size() != 2 || s.springs.size() != 1 || !s.gravity.isZero() || s.drag != 0.0 ||
      (s.wind && s.wind->coefficient != 0.0) || s.springs[0].damping != 0.0) {
    return std::nullopt;
  }
  const int fixed = s.particles[0].fixed ? 0 : 1;
  const Particle& anchor = s.particles[static_cast<std::size_t>(fixed)];
  const Particle& mass = s.particles[static_cast<std::size_t>(1 - fixed)];
  if (!anchor.fixed || mass.fixed || !mass.v.isZero()) return std::nullopt;
  const Eigen::Vector3d d = mass.x - anchor.x;
  const double l = d.norm();
  const double rest = s.springs[0].rest;
  const double w = std::sqrt(s.springs[0].k / mass.mass);
  // Along the spring axis u: l(t) = rest + (l0 - rest) cos(w t) (linear while l > 0).
  const Eigen::Vector3d x = anchor.x + d / l * (rest + (l - rest) * std::cos(w * t));
  return Vector(x.head(s.dimension));
}

void check_time_grid(const DefinitionObject& o, const char* key, double dt, double t_end) {
  try {
    make_time_grid(dt, t_end);
  } catch (const std::invalid_argument& e) {
    o.fail(key, e.what());
  }
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
