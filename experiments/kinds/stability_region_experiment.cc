// stability-region: each fixed-step method's stability region |R(z)| <= 1 in
// the complex plane with the scene's own scaled eigenvalues z_i = h lambda_i
// overlaid, at a step just below and one just above the method's limit, so a
// student sees which mode leaves the region when the run explodes.
//
// lambda_i are the eigenvalues of the first-order linearization at the
// initial state, J = [[0, I], [M^-1 K, M^-1 D]] (models/model/modal_analysis.h),
// damping included. A method whose step is the scalar map R (IntegratorInfo::
// stability_function) advances mode i by R(h lambda_i) per step, so its limit
// h* is the smallest h at which some |R(h lambda_i)| exceeds 1 (a scan on log
// h refined by bisection). A partitioned method (symplectic Euler, Verlet)
// has no region in the z-plane, its step not being a function of h J alone:
// its h* is measured by bisection on runs, starting from its declared
// undamped limit. A method with no limit (h* beyond max_scaled_step /
// max |lambda|) is shown at max_scaled_step / max |lambda|; one with no
// stable step (an undamped mode and explicit Euler) at 0.1 / max |lambda|.
//
// Each method then runs at factor x h* for each of `factors` for the time of
// `steps` steps of h*: the run's `diverged` is the measurement, max |R| over
// the modes the prediction (they agree on a linear scene).
#include <algorithm>
#include <cmath>
#include <complex>
#include <memory>
#include <optional>

#include "experiments/kinds/experiment.h"
#include "experiments/kinds/experiment_support.h"
#include "experiments/analysis/stability.h"
#include "integrators/registry/registry.h"
#include "models/model/modal_analysis.h"

namespace springlab {
namespace {

using Complex = std::complex<double>;

// Where the limit h* comes from.
constexpr const char* kFromR = "R";        // max_i |R(h lambda_i)| <= 1
constexpr const char* kFromRuns = "runs";  // bisection on runs (partitioned methods)
constexpr const char* kNoLimit = "none";   // stable up to max_scaled_step / max |lambda|
constexpr const char* kNoStableStep = "no stable step";  // shown at 0.1 / max |lambda|
constexpr double kMaxAbsR = 1e6;  // the grid's |R| is capped here (poles)

struct Limit {
  double dt = 0.0;
  const char* from = kFromR;
};

double max_abs_r(const IntegratorInfo& info, const std::vector<Complex>& lambda, double h) {
  double m = 0.0;
  for (const Complex l : lambda) m = std::max(m, std::abs(info.stability_function(h * l)));
  return m;
}

// The smallest h at which a mode leaves the region: a scan of 100 points per
// decade from 1e-6 / |lambda|_max up, then bisection to 1e-10 relative.
std::optional<double> first_unstable_step(const IntegratorInfo& info,
                                          const std::vector<Complex>& lambda, double h_max) {
  constexpr double kSlack = 1e-12;  // |R| = 1 on the boundary (undamped modes of midpoint)
  auto unstable = [&](double h) { return max_abs_r(info, lambda, h) > 1.0 + kSlack; };
  const double lambda_max = std::abs(lambda.back());
  double lo = 1e-6 / lambda_max;
  if (unstable(lo)) return 0.0;
  const double ratio = std::pow(10.0, 0.01);
  double hi = lo * ratio;
  while (!unstable(hi)) {
    if (hi > h_max) return std::nullopt;
    lo = hi;
    hi *= ratio;
  }
  while (hi / lo > 1.0 + 1e-10) {
    const double mid = std::sqrt(lo * hi);
    (unstable(mid) ? hi : lo) = mid;
  }
  return lo;
}

class StabilityRegionExperiment final : public Experiment {
 public:
  explicit StabilityRegionExperiment(const DefinitionObject& d) {
    d.allow_only({"experiment", "name", "title", "description", "integrators", "newton_tol",
                  "scene", "parameters", "factors", "steps", "max_scaled_step", "grid",
                  "blowup"});
    options_ = definition_options(d);
    integrators_ = definition_integrators(d, "integrators", "fixed-step");
    for (const std::string& name : integrators_) {
      if (make_integrator(name)->info().adaptive) {
        d.fail("integrators", "'" + name + "' is adaptive: it has no step size to limit");
      }
    }
    scene_ = definition_scene(d);
    factors_ = d.has("factors") ? d.positives("factors") : std::vector<double>{0.9, 1.1};
    steps_ = d.count("steps", 1000, 10, 1000000);
    max_scaled_step_ = d.positive("max_scaled_step", 10.0);
    grid_ = d.count("grid", 81, 11, 1001);
    blowup_ = d.positive("blowup", 1000.0);
    const Model model(scene_);
    if (2 * model.dofs() > kMaxFirstOrderUnknowns) {
      d.fail("scene", "has " + std::to_string(model.dofs()) + " unknowns; the eigenvalues need " +
                          "at most " + std::to_string(kMaxFirstOrderUnknowns / 2));
    }
    lambda_ = first_order_eigenvalues(model, model.initial_positions(),
                                      model.initial_velocities());
    if (lambda_.empty() || std::abs(lambda_.back()) == 0.0) {
      d.fail("scene", "has no nonzero eigenvalue: nothing limits the step");
    }
    w_max_ = max_angular_frequency(model);
    check_task_count(d, "integrators", static_cast<double>(integrators_.size()));
  }

  std::vector<TableSpec> tables() const override {
    return {{"", {"scene", "integrator", "factor", "dt", "limit_dt", "limit_from", "max_abs_R",
                  "modes_outside", "diverged", "diverged_at"}},
            {"modes", {"scene", "integrator", "factor", "dt", "mode", "lambda_re", "lambda_im",
                       "z_re", "z_im", "abs_R"}},
            {"region", {"scene", "integrator", "z_re", "z_im", "abs_R"}}};
  }

  std::size_t task_count() const override { return integrators_.size(); }

  TaskOutput run_task(std::size_t index) const override {
    const std::string& name = integrators_[index];
    const IntegratorInfo info = make_integrator(name)->info();
    const Model model(scene_);
    const Limit limit = find_limit(model, info);
    TaskOutput out;
    out.rows.resize(3);
    double re_lo = 0.0, re_hi = 0.0, im_hi = 0.0;  // every z shown, and 0
    for (const double factor : factors_) {
      const double h = factor * limit.dt;
      RunSettings run = settings(name, h, steps_ * limit.dt);
      const RunResult r = simulate(model, run);
      const std::string prefix = Row().add(scene_.name).add(name).add(factor).add(h).str();
      int outside = 0;
      double max_r = 0.0;
      for (std::size_t i = 0; i < lambda_.size(); ++i) {
        const Complex z = h * lambda_[i];
        re_lo = std::min(re_lo, z.real());
        re_hi = std::max(re_hi, z.real());
        im_hi = std::max(im_hi, std::abs(z.imag()));
        Row row;
        row.raw(prefix).add(static_cast<long>(i)).add(lambda_[i].real()).add(lambda_[i].imag())
            .add(z.real()).add(z.imag());
        if (info.stability_function) {
          const double a = std::abs(info.stability_function(z));
          max_r = std::max(max_r, a);
          outside += a > 1.0 + 1e-12 ? 1 : 0;
          row.add(a);
        } else {
          row.add_empty();
        }
        out.rows[1].push_back(row.str());
      }
      Row row;
      row.raw(prefix).add(limit.dt).add(limit.from);
      if (info.stability_function) {
        row.add(max_r).add(outside);
      } else {
        row.add_empty().add_empty();
      }
      row.add(r.diverged() ? 1 : 0).add(r.diverged_at);
      out.rows[0].push_back(row.str());
    }
    if (info.stability_function) write_region(info, region_window(re_lo, re_hi, im_hi), out.rows[2]);
    return out;
  }

  nlohmann::json settings() const override {
    nlohmann::json eigenvalues = nlohmann::json::array();
    for (const Complex l : lambda_) eigenvalues.push_back({l.real(), l.imag()});
    return {{"integrators", integrators_}, {"scene", scene_as_json(scene_)},
            {"factors", factors_}, {"steps", steps_}, {"max_scaled_step", max_scaled_step_},
            {"grid", grid_}, {"blowup", blowup_}, {"w_max", w_max_},
            {"eigenvalues", eigenvalues}};
  }

 private:
  RunSettings settings(const std::string& name, double dt, double t_end) const {
    RunSettings s;
    s.integrator = name;
    s.dt = dt;
    s.t_end = t_end;
    s.blowup = blowup_;
    s.options = options_;
    return s;
  }

  struct Window {
    double re_lo, re_hi, im_hi;  // Im from -im_hi to im_hi
  };

  // Where |R| is drawn: the z shown (and 0), padded by 15% of the larger
  // side, neither side under half the other; joined with the region's core
  // [-3, 1] x [-3, 3] unless the z are all much closer to 0 than that (then
  // the window zooms in on them: near 0 the boundary passes close by).
  static Window region_window(double re_lo, double re_hi, double im_hi) {
    double side = std::max(re_hi - re_lo, 2.0 * im_hi);
    if (side == 0.0) side = 1.0;
    const double mid = 0.5 * (re_lo + re_hi);
    const double half_re = std::max(0.5 * (re_hi - re_lo), 0.25 * side) + 0.15 * side;
    Window w{mid - half_re, mid + half_re, std::max(im_hi, 0.25 * side) + 0.15 * side};
    if (side >= 0.2 * 6.0) {
      w.re_lo = std::min(w.re_lo, -3.0);
      w.re_hi = std::max(w.re_hi, 1.0);
      w.im_hi = std::max(w.im_hi, 3.0);
    }
    return w;
  }

  // |R(z)| on the window at a round spacing s (1, 2, 2.5 or 5 times a power
  // of 10) with at most grid_ points a side, coordinates k s computed as k / q
  // (q = 1/s) so they print short; |R| rounded to 1e-6, enough to draw the
  // boundary |R| = 1, and capped at kMaxAbsR (R has a pole where 1 - z/2 or
  // 1 - z vanishes: implicit methods).
  void write_region(const IntegratorInfo& info, const Window& w,
                    std::vector<std::string>& rows) const {
    const double span = std::max(w.re_hi - w.re_lo, 2.0 * w.im_hi);
    double spacing = 0.0;
    for (double decade = 1e-6; spacing == 0.0; decade *= 10.0) {
      for (const double m : {1.0, 2.0, 2.5, 5.0}) {
        if (span / (m * decade) <= grid_ - 1) {
          spacing = m * decade;
          break;
        }
      }
    }
    const double q = spacing < 1.0 ? std::round(1.0 / spacing) : 0.0;
    auto at = [&](long k) { return q > 0.0 ? static_cast<double>(k) / q : k * spacing; };
    const long b_lo = std::lround(std::floor(w.re_lo / spacing));
    const long b_hi = std::lround(std::ceil(w.re_hi / spacing));
    const long a_hi = std::lround(std::ceil(w.im_hi / spacing));
    const std::string prefix = Row().add(scene_.name).add(info.name).str();
    for (long a = -a_hi; a <= a_hi; ++a) {
      for (long b = b_lo; b <= b_hi; ++b) {
        const Complex z(at(b), at(a));
        const double r =
            std::round(std::min(std::abs(info.stability_function(z)), kMaxAbsR) * 1e6) / 1e6;
        rows.push_back(Row().raw(prefix).add(z.real()).add(z.imag()).add(r).str());
      }
    }
  }

  Limit find_limit(const Model& model, const IntegratorInfo& info) const {
    const double lambda_max = std::abs(lambda_.back());
    const double no_limit_dt = max_scaled_step_ / lambda_max;
    if (info.stability_function) {
      const std::optional<double> h = first_unstable_step(info, lambda_, no_limit_dt);
      if (!h) return {no_limit_dt, kNoLimit};
      if (*h == 0.0) return {0.1 / lambda_max, kNoStableStep};  // an undamped mode, |R(i y)| > 1
      return {*h, kFromR};
    }
    // Partitioned: bisection on runs around the declared undamped limit.
    const double guess = std::isfinite(info.stability_limit) && info.stability_limit > 0.0 &&
                                 w_max_ > 0.0
                             ? info.stability_limit / w_max_
                             : 1.0 / lambda_max;
    StabilitySettings s;
    s.run = settings(info.name, guess, steps_ * guess);
    s.dt_min = 1e-3 * guess;
    s.dt_max = std::min(no_limit_dt, 10.0 * guess);
    s.rel_tol = 1e-4;
    const StabilityResult r = find_max_stable_dt(model, s);
    if (r.lo == r.hi) return {no_limit_dt, kNoLimit};
    if (r.max_stable_dt <= 0.0) return {0.1 / lambda_max, kNoStableStep};
    return {r.max_stable_dt, kFromRuns};
  }

  IntegratorOptions options_;
  std::vector<std::string> integrators_;
  Scene scene_;
  std::vector<double> factors_;
  int steps_ = 1000;
  double max_scaled_step_ = 10.0;
  int grid_ = 81;
  double blowup_ = 1000.0;
  std::vector<Complex> lambda_;
  double w_max_ = 0.0;
};

}  // namespace

std::unique_ptr<Experiment> make_stability_region_experiment(const DefinitionObject& d) {
  return std::make_unique<StabilityRegionExperiment>(d);
}

const ExperimentKind& stability_region_experiment_kind() {
  static const ExperimentKind kind{"stability-region", &make_stability_region_experiment};
  return kind;
}

}  // namespace springlab
