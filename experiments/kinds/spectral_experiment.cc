// spectral: the classic figure of structural dynamics (Hughes 1987,
// figs. 9.1.2-9.1.4; Chung and Hulbert 1993, figs. 1-3): for each fixed-step
// method, the spectral radius of its amplification matrix, its algorithmic
// damping ratio and its relative period error against w h on the undamped
// oscillator, each measured from the method's own steps (experiments/
// spectral.h), not from a formula. The scene column is "unit-oscillator"
// (w = 1, so h = w h).
//
// Definition keys: `integrators` (default "fixed-step"), `variants` (extra
// rows of one method with its parameters: {"integrator", "label", and any of
// "beta", "gamma", "alpha", "rho_inf"}), `wh_min`, `wh_max` (default 1e-2,
// 1e3) and `points_per_decade` (default 10).
#include <cmath>
#include <memory>
#include <stdexcept>

#include "experiments/kinds/experiment.h"
#include "experiments/kinds/experiment_support.h"
#include "experiments/analysis/spectral.h"
#include "integrators/registry/registry.h"

namespace springlab {
namespace {

struct MethodVariant {
  std::string integrator;
  std::string label;
  IntegratorOptions options;
};

class SpectralExperiment final : public Experiment {
 public:
  explicit SpectralExperiment(const DefinitionObject& d) {
    d.allow_only({"experiment", "name", "title", "description", "integrators", "variants",
                  "wh_min", "wh_max", "points_per_decade"});
    for (const std::string& name : definition_integrators(d, "integrators", "fixed-step")) {
      if (make_integrator(name)->info().adaptive) {
        d.fail("integrators", "'" + name + "' is adaptive: it has no fixed step to analyse");
      }
      variants_.push_back({name, name, {}});
    }
    if (d.has("variants")) {
      const std::vector<DefinitionObject> list = d.objects("variants");
      for (const DefinitionObject& v : list) {
        v.allow_only({"integrator", "label", "beta", "gamma", "alpha", "rho_inf"});
        MethodVariant variant;
        variant.integrator = definition_integrator(v, "integrator");
        if (make_integrator(variant.integrator)->info().adaptive) {
          v.fail("integrator", "is adaptive: it has no fixed step to analyse");
        }
        variant.label = v.string("label");
        IntegratorOptions& o = variant.options;
        if (v.has("beta")) o.beta = v.number("beta");
        if (v.has("gamma")) o.gamma = v.number("gamma");
        if (v.has("alpha")) o.alpha = v.number("alpha");
        if (v.has("rho_inf")) o.rho_inf = v.number("rho_inf");
        if (std::string why = make_integrator(variant.integrator)->check_options(o, 2);
            !why.empty()) {
          v.fail("integrator", why);
        }
        variants_.push_back(variant);
      }
    }
    wh_min_ = d.positive("wh_min", 1e-2);
    wh_max_ = d.positive("wh_max", 1e3);
    if (!(wh_max_ > wh_min_)) d.fail("wh_max", "must be above wh_min");
    per_decade_ = d.count("points_per_decade", 10, 1, 1000);
    check_task_count(d, "integrators", static_cast<double>(variants_.size()));
  }

  std::vector<TableSpec> tables() const override {
    return {{"", {"scene", "integrator", "method", "wh", "spectral_radius", "damping_ratio",
                  "period_error", "degree"}}};
  }

  std::size_t task_count() const override { return variants_.size(); }

  TaskOutput run_task(std::size_t index) const override {
    const MethodVariant& v = variants_[index];
    TaskOutput out;
    out.rows.resize(1);
    const double decades = std::log10(wh_max_ / wh_min_);
    const int points = static_cast<int>(std::lround(decades * per_decade_));
    for (int k = 0; k <= points; ++k) {
      // Whole powers of 10 exactly (10^(k / n), not a product of rounded factors).
      const double wh = wh_min_ * std::pow(10.0, static_cast<double>(k) / per_decade_);
      Row row;
      row.add("unit-oscillator").add(v.integrator).add(v.label).add(wh);
      try {
        const StepSpectrum s = step_spectrum(v.integrator, v.options, wh);
        row.add(s.spectral_radius);
        for (double value : {s.damping_ratio, s.period_error}) {
          if (std::isfinite(value)) {
            row.add(value);
          } else {
            row.add_empty();
          }
        }
        row.add(s.degree);
      } catch (const std::runtime_error&) {
        // The step failed at this w h (a Newton failure): no measurement.
        row.add_empty().add_empty().add_empty().add_empty();
      }
      out.rows[0].push_back(row.str());
    }
    return out;
  }

  nlohmann::json settings() const override {
    nlohmann::json variants = nlohmann::json::array();
    for (const MethodVariant& v : variants_) {
      nlohmann::json e = {{"label", v.label}, {"integrator", v.integrator}};
      const IntegratorOptions& o = v.options;
      if (!std::isnan(o.beta)) e["beta"] = o.beta;
      if (!std::isnan(o.gamma)) e["gamma"] = o.gamma;
      if (!std::isnan(o.alpha)) e["alpha"] = o.alpha;
      if (!std::isnan(o.rho_inf)) e["rho_inf"] = o.rho_inf;
      variants.push_back(e);
    }
    return {{"methods", variants}, {"wh_min", wh_min_}, {"wh_max", wh_max_},
            {"points_per_decade", per_decade_}};
  }

 private:
  std::vector<MethodVariant> variants_;
  double wh_min_ = 1e-2, wh_max_ = 1e3;
  int per_decade_ = 10;
};

}  // namespace

std::unique_ptr<Experiment> make_spectral_experiment(const DefinitionObject& d) {
  return std::make_unique<SpectralExperiment>(d);
}

const ExperimentKind& spectral_experiment_kind() {
  static const ExperimentKind kind{"spectral", &make_spectral_experiment};
  return kind;
}

}  // namespace springlab
