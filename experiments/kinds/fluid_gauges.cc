#include "experiments/kinds/fluid_gauges.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <sstream>

#include "experiments/kinds/experiment_support.h"
#include "experiments/kinds/fluid_measures.h"
#include "experiments/kinds/reference_file.h"
#include "experiments/driver/simulation.h"
#include "models/model/model.h"
#include "models/fluids/fluids.h"
#include "models/fluids/sph_kernel.h"

namespace springlab {
namespace {

// The reference CSV: '#' lines (its source), the header "t,<names>", rows
// of numbers, t increasing; every gauge needs a column.
GaugeReference read_gauge_reference(const DefinitionObject& d, const std::vector<Gauge>& gauges) {
  const ReferenceLines lines = read_reference_lines(d);
  GaugeReference r;
  r.file = lines.file;
  r.source = lines.source;
  std::vector<std::string> header;
  std::vector<int> column(gauges.size(), -1);
  r.height.resize(gauges.size());
  for (const auto& [number, line] : lines.lines) {
    std::vector<std::string> fields;
    std::istringstream split(line);
    for (std::string field; std::getline(split, field, ',');) fields.push_back(field);
    if (header.empty()) {
      header = fields;
      if (header.empty() || header[0] != "t") {
        d.fail("reference", r.file + " line " + std::to_string(number) + ": the header must start with t");
      }
      for (std::size_t g = 0; g < gauges.size(); ++g) {
        const auto at = std::find(header.begin() + 1, header.end(), gauges[g].name);
        if (at == header.end()) {
          d.fail("reference", r.file + ": no column for gauge '" + gauges[g].name + "'");
        }
        column[g] = static_cast<int>(at - header.begin());
      }
      continue;
    }
    std::vector<double> values;
    for (const std::string& field : fields) {
      std::size_t used = 0;
      double value = 0.0;
      try {
        value = std::stod(field, &used);
      } catch (const std::exception&) {
        used = 0;
      }
      if (used != field.size() || !std::isfinite(value)) values.clear();
      if (used != field.size() || !std::isfinite(value)) break;
      values.push_back(value);
    }
    if (values.size() != header.size() || (!r.t.empty() && !(values[0] > r.t.back()))) {
      d.fail("reference", r.file + " line " + std::to_string(number) + ": expected " +
                              std::to_string(header.size()) +
                              " numbers, t increasing (got '" + line + "')");
    }
    r.t.push_back(values[0]);
    for (std::size_t g = 0; g < gauges.size(); ++g) {
      r.height[g].push_back(values[static_cast<std::size_t>(column[g])]);
    }
  }
  if (r.t.size() < 2) d.fail("reference", r.file + ": needs at least two rows");
  return r;
}

// The first time a series passes `level` (linear between samples), where it
// starts below it; nullopt otherwise.
std::optional<double> arrival(const std::vector<double>& t, const std::vector<double>& h,
                              double level) {
  if (h.empty() || !(h.front() < level)) return std::nullopt;
  for (std::size_t k = 1; k < h.size(); ++k) {
    if (h[k] >= level) return t[k - 1] + (level - h[k - 1]) / (h[k] - h[k - 1]) * (t[k] - t[k - 1]);
  }
  return std::nullopt;
}

// Samples every gauge at every observed state.
class GaugeWatch final : public Observer {
 public:
  GaugeWatch(const Model& model, const std::vector<Gauge>& gauges)
      : height(gauges.size()), model_(model), gauges_(gauges) {}
  void observe(double t_now, const Vector& x, const Vector&) override {
    const Eigen::MatrixXd positions = model_.scene_positions(x);
    t.push_back(t_now);
    for (std::size_t g = 0; g < gauges_.size(); ++g) {
      height[g].push_back(gauge_height(model_.scene(), positions, gauges_[g].x, gauges_[g].z));
    }
  }
  std::vector<double> t;
  std::vector<std::vector<double>> height;

 private:
  const Model& model_;
  const std::vector<Gauge>& gauges_;
};

// The water height at which a gauge counts the front as arrived [m].
constexpr double kArrivalLevel = 0.02;

}  // namespace

double gauge_height(const Scene& scene, const Eigen::MatrixXd& positions, double x_g, double z_g) {
  const Fluid& fluid = scene.get<Fluids>().front();
  const CubicSpline w(kSmoothingPerSpacing * fluid.spacing, 2);  // in the horizontal plane
  double sum = 0.0;
  for (int s = fluid.first; s < fluid.first + fluid.count; ++s) {
    const Particle& p = scene.particles[static_cast<std::size_t>(s)];
    if (p.fixed) continue;
    const double dx = positions(s, 0) - x_g;
    const double dz = positions.cols() > 2 ? positions(s, 2) - z_g : 0.0;
    sum += p.mass / fluid.density * w.value(std::sqrt(dx * dx + dz * dz));
  }
  return sum;
}

FluidGauges::FluidGauges(const DefinitionObject& d, const IntegratorOptions& options)
    : options_(options) {
  d.allow_only({"scene", "parameters", "integrator", "dt", "substeps", "iterations", "t_end",
                "sample", "reference", "gauges", "bound"});
  scene_ = definition_scene(d);
  if (!scene_.has<Fluids>() || scene_.get<Fluids>().empty()) d.fail("scene", "needs a fluid");
  if (scene_.dimension != 3) d.fail("scene", "needs a 3-D scene (gauges on the floor x-z)");
  integrator_ = definition_integrator(d, "integrator");
  dt_ = d.positive("dt");
  t_end_ = d.positive("t_end");
  sample_ = d.positive("sample");
  if (sample_ < dt_) d.fail("sample", "must be at least dt");
  check_time_grid(d, "dt", dt_, t_end_);
  substeps_ = d.count("substeps", 0, 0, 100000);
  iterations_ = d.count("iterations", 0, 0, 100000);
  bound_ = d.positive("bound");
  for (const DefinitionObject& g : d.objects("gauges")) {
    g.allow_only({"name", "x", "z"});
    gauges_.push_back({g.string("name"), g.number("x"), g.number("z")});
  }
  reference_ = read_gauge_reference(d, gauges_);
}

std::vector<TableSpec> FluidGauges::tables() {
  return {{"gauges", {"gauge", "t", "height", "measured"}},
          {"gauge_summary", {"gauge", "x", "z", "integrator", "dt", "status", "t_final", "steps",
                             "cpu_seconds", "particles", "water", "samples", "rms_error",
                             "max_error", "bound", "within_bound", "arrival_measured",
                             "arrival_simulated", "failure"}},
          {"gauge_reference", {"gauge", "t", "height"}}};
}

nlohmann::json FluidGauges::settings() const {
  nlohmann::json gauges = nlohmann::json::array();
  for (const Gauge& g : gauges_) gauges.push_back({{"name", g.name}, {"x", g.x}, {"z", g.z}});
  const Fluid& fluid = scene_.get<Fluids>().front();
  long water = 0;
  for (int s = fluid.first; s < fluid.first + fluid.count; ++s) {
    if (!scene_.particles[static_cast<std::size_t>(s)].fixed) ++water;
  }
  return {{"scene", scene_.name}, {"integrator", integrator_}, {"dt", dt_},
          {"substeps", substeps_}, {"iterations", iterations_}, {"t_end", t_end_},
          {"sample", sample_}, {"bound", bound_}, {"arrival_level", kArrivalLevel},
          {"gauges", gauges}, {"spacing", fluid.spacing}, {"speed_of_sound", fluid.speed_of_sound},
          {"particles", scene_.particles.size()}, {"water_particles", water},
          {"reference", {{"file", reference_.file}, {"source", reference_.source}}}};
}

void FluidGauges::run(TaskOutput& out, std::size_t first) const {
  const Model model(scene_);
  GaugeWatch watch(model, gauges_);
  RunSettings run;
  run.integrator = integrator_;
  run.dt = dt_;
  run.t_end = t_end_;
  run.every = std::max(1, static_cast<int>(std::lround(sample_ / dt_)));
  run.options = options_;
  run.options.substeps = substeps_;
  run.options.iterations = iterations_;
  const double cpu_start = thread_cpu_seconds();
  const RunResult r = simulate(model, run, {&watch});
  const double cpu = thread_cpu_seconds() - cpu_start;
  const Fluid& fluid = scene_.get<Fluids>().front();
  long water = 0;
  for (int s = fluid.first; s < fluid.first + fluid.count; ++s) {
    if (!scene_.particles[static_cast<std::size_t>(s)].fixed) ++water;
  }
  for (std::size_t g = 0; g < gauges_.size(); ++g) {
    double sum2 = 0.0, worst = 0.0;
    long samples = 0;
    for (std::size_t k = 0; k < watch.t.size(); ++k) {
      const std::optional<double> measured =
          interpolate(reference_.t, reference_.height[g], watch.t[k]);
      out.rows[first].push_back(Row().add(gauges_[g].name).add(watch.t[k])
                                    .add(watch.height[g][k]).add(measured).str());
      if (!measured) continue;
      const double e = watch.height[g][k] - *measured;
      sum2 += e * e;
      worst = std::max(worst, std::abs(e));
      ++samples;
    }
    Row row;
    row.add(gauges_[g].name).add(gauges_[g].x).add(gauges_[g].z).add(integrator_).add(dt_)
        .add(to_string(r.status)).add(r.t_final).add(r.stats.steps).add(cpu)
        .add(static_cast<long>(scene_.particles.size())).add(water).add(samples);
    if (samples > 0) {
      const double rms = std::sqrt(sum2 / static_cast<double>(samples));
      row.add(rms).add(worst).add(bound_).add(rms <= bound_ ? 1L : 0L);
    } else {
      row.add_empty().add_empty().add(bound_).add_empty();
    }
    row.add(arrival(reference_.t, reference_.height[g], kArrivalLevel))
        .add(arrival(watch.t, watch.height[g], kArrivalLevel)).add(r.failure);
    out.rows[first + 1].push_back(row.str());
    for (std::size_t k = 0; k < reference_.t.size(); ++k) {
      out.rows[first + 2].push_back(
          Row().add(gauges_[g].name).add(reference_.t[k]).add(reference_.height[g][k]).str());
    }
  }
}

}  // namespace springlab
