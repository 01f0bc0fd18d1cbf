#include "experiments/kinds/experiment_support.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <type_traits>
#include <variant>
#include <string>

#include "experiments/io/output_files.h"
#include "models/core/element_kind.h"
#include "models/springs/springs.h"
#include "models/model/scene_file.h"
#include "models/model/element_registry.h"
#include "experiments/driver/run_warnings.h"

namespace springlab {

IntegratorOptions definition_options(const DefinitionObject& o) {
  // Every integrator option the definition gives (its allow_only list says
  // which it may), under the command line's name with '_' for '-'
  // (integrators/core/integrator_options.h), checked as the command line checks it;
  // o.fail names the key where the definition gives it.
  IntegratorOptions options;
  for (const OptionSpec& spec : integrator_options()) {
    std::string key(spec.name);
    std::replace(key.begin(), key.end(), '-', '_');
    if (!o.has(key.c_str())) continue;
    std::visit(
        [&](auto field) {
          using Field = decltype(field);
          if constexpr (std::is_same_v<Field, std::monostate>) {
            if (!spec.set(options, o.string(key.c_str()))) {
              o.fail(key, choice_refusal(spec, o.string(key.c_str())));
            }
          } else if constexpr (std::is_same_v<Field, bool IntegratorOptions::*>) {
            const nlohmann::json& value = o.raw(key.c_str());
            if (!value.is_boolean()) o.fail(key, "expected true or false");
            options.*field = value.get<bool>();
          } else if constexpr (std::is_same_v<Field, double IntegratorOptions::*>) {
            options.*field = o.number(key.c_str());
          } else {
            options.*field = o.count(key.c_str(), 0, 0, std::numeric_limits<int>::max());
          }
        },
        spec.field);
    const std::string why = check_option_range(spec, options, true);
    if (!why.empty()) o.fail(key, why);
  }
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
  auto check = [&](std::size_t total, std::size_t cap, const std::string& what) {
    if (total > cap) {
      o.fail(key, "the experiment's scenes would hold " + std::to_string(total) + " " + what +
                      " in all, over the cap of " + std::to_string(cap));
    }
  };
  particles_ += scene.particles.size();
  check(particles_, kMaxSceneParticles, "particles");
  const std::vector<ElementCount> counts = element_counts(scene);
  elements_.resize(counts.size(), 0);
  for (std::size_t k = 0; k < counts.size(); ++k) {
    elements_[k] += counts[k].count;
    check(elements_[k], counts[k].cap, std::string(counts[k].key));
  }
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

TimedCasesExperiment::TimedCasesExperiment(const DefinitionObject& d) {
  d.allow_only({"experiment", "name", "title", "description", "integrators", "rtol", "atol",
                "newton_tol", "cases"});
  options_ = definition_options(d);
  integrators_ = definition_integrators(d, "integrators", "all");
  cases_ = read_timed_cases(d);
  check_timed_case_rows(d, cases_, integrators_.size());
}

TimedCasesExperiment::Task TimedCasesExperiment::task(std::size_t index) const {
  const TimedCase& c = cases_[index / integrators_.size()];
  const std::string& name = integrators_[index % integrators_.size()];
  RunSettings s;
  s.integrator = name;
  s.dt = c.dt;
  s.t_end = c.t_end;
  s.every = c.every;
  s.options = options_;
  return {c, s, Row().add(c.scene.name).add(name).add(c.dt).str()};
}

nlohmann::json TimedCasesExperiment::settings() const {
  return {{"integrators", integrators_}, {"cases", timed_cases_json(cases_)}};
}

nlohmann::json scene_as_json(const Scene& scene) { return nlohmann::json::parse(scene_to_json(scene)); }

void check_time_grid(const DefinitionObject& o, const char* key, double dt, double t_end) {
  try {
    make_time_grid(dt, t_end);
  } catch (const std::invalid_argument& e) {
    o.fail(key, e.what());
  }
}

std::string warnings_cell(const RunResult& r) {
  std::string cell;
  for (const std::string& line : warning_texts(r.warnings, r.integrator)) {
    cell += (cell.empty() ? "" : "; ") + line;
  }
  return cell;
}

}  // namespace springlab
