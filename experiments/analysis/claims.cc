#include "experiments/analysis/claims.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "experiments/analysis/stability.h"
#include "experiments/driver/simulation.h"
#include "integrators/registry/registry.h"
#include "models/bodies/bodies.h"
#include "models/model/scene_file.h"
#include "models/scenes/builtin_scenes.h"

namespace springlab {
namespace {

constexpr double kPi = 3.14159265358979323846;
using Json = nlohmann::ordered_json;

std::string text(double value) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.3g", value);
  return buffer;
}
std::string exact_text(double value) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.10g", value);
  return buffer;
}

// Every step's state, to a function.
class EachStep final : public Observer {
 public:
  explicit EachStep(std::function<void(double, const Vector&, const Vector&)> see)
      : see_(std::move(see)) {}
  void observe(double t, const Vector& x, const Vector& v) override { see_(t, x, v); }

 private:
  std::function<void(double, const Vector&, const Vector&)> see_;
};

RunResult run_method(const Model& model, const std::string& method, double dt, double t_end,
                     Observer* observer) {
  RunSettings settings;
  settings.integrator = method;
  settings.dt = dt;
  settings.t_end = t_end;
  std::vector<Observer*> observers;
  if (observer != nullptr) observers.push_back(observer);
  return simulate(model, settings, observers);
}

// "diverged at t = 3.1" / "failed at t = 0.2: why".
std::string run_trouble(const RunResult& r) {
  const double at = r.diverged_at.value_or(r.t_final);
  if (r.status == RunStatus::kFailed) return "failed at t = " + text(at) + ": " + r.failure;
  return "diverged at t = " + text(at);
}

// The oscillator x'' = -x (k = m = 1, w = 1), released at rest from
// x0 = anchor + d0: x(t) = anchor + d0 cos t, v(t) = -d0 sin t,
// E = (|v|^2 + |x - anchor|^2) / 2.
struct Oscillator {
  Scene scene = make_builtin_scene("oscillator", {{"k", "1"}, {"mass", "1"}, {"amplitude", "1"}});
  Model model{scene};
  Vector anchor, d0;
  Oscillator() {
    const int d = scene.dimension;
    for (const Particle& p : scene.particles) {
      if (p.fixed) anchor = p.x.head(d);
    }
    d0 = model.initial_positions() - anchor;
  }
  double energy(const Vector& x, const Vector& v) const {
    return 0.5 * (v.squaredNorm() + (x - anchor).squaredNorm());
  }
  double error(double t, const Vector& x, const Vector& v) const {
    const Vector xe = anchor + d0 * std::cos(t);
    const Vector ve = -d0 * std::sin(t);
    return std::max((x - xe).lpNorm<Eigen::Infinity>(), (v - ve).lpNorm<Eigen::Infinity>());
  }
};
// A built-in scene and its parameters, as a claim's runs use it and as the
// command that reproduces the claim names it.
struct CheckScene {
  std::string name;
  std::vector<std::pair<std::string, std::string>> parameters;

  // "oscillator -p k=1 ...", for the command line.
  std::string command_text() const {
    std::string out = name;
    for (const auto& [key, value] : parameters) out += " -p " + key + "=" + value;
    return out;
  }
  // springlab.load_scene("oscillator", k=1, ...), for Python.
  std::string python_text() const {
    std::string out = "springlab.load_scene(\"" + name + "\"";
    for (const auto& [key, value] : parameters) out += ", " + key + "=" + value;
    return out + ")";
  }
};
const CheckScene kOscillator{"oscillator", {{"k", "1"}, {"mass", "1"}, {"amplitude", "1"}}};

// The run that shows a claim's numbers, on the oscillator: a command line,
// or for a method written in Python the same run from Python.
std::string run_command(const CheckSubject& s, double dt, double t_end, const std::string& extra,
                        const CheckScene& scene = kOscillator) {
  if (!s.python_call.empty()) {
    return "springlab.run(" + scene.python_text() + ", " + s.python_call + ", dt=" +
           exact_text(dt) + ", t_end=" + exact_text(t_end) + ")";
  }
  return "springlab run " + scene.command_text() + " " + s.method_arguments + " --dt " + exact_text(dt) +
         " --t-end " + exact_text(t_end) + extra;
}

// `springlab check` of one claim: "--symplectic" (Python: symplectic=True).
std::string check_command(const CheckSubject& s, const std::string& option,
                          const std::string& keyword) {
  if (!s.python_call.empty()) return "springlab.check(" + s.python_call + ", " + keyword + ")";
  return s.check_command + " " + option;
}

// Least-squares slope of log e against log h over the points with e above
// the round-off floor; nullopt when fewer than two are.
std::optional<double> observed_order(const std::vector<double>& h, const std::vector<double>& e) {
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  int n = 0;
  for (std::size_t k = 0; k < h.size(); ++k) {
    if (!(e[k] > 1e-12) || !std::isfinite(e[k])) continue;
    const double lx = std::log(h[k]), ly = std::log(e[k]);
    sx += lx, sy += ly, sxx += lx * lx, sxy += lx * ly, ++n;
  }
  if (n < 2) return std::nullopt;
  return (n * sxy - sx * sy) / (n * sxx - sx * sx);
}

ClaimResult check_order(const CheckSubject& s, int order) {
  ClaimResult out{"--order " + std::to_string(order)};
  const Oscillator osc;
  const double h0 = order >= 3 ? 0.4 : 0.2, t_end = 2.4;
  std::vector<double> hs, errors;
  for (int k = 0; k < 4; ++k) {
    const double h = h0 / (1 << k);
    double error = 0.0;
    EachStep watch([&](double t, const Vector& x, const Vector& v) {
      error = std::max(error, osc.error(t, x, v));
    });
    const RunResult r = run_method(osc.model, s.integrator, h, t_end, &watch);
    if (r.diverged()) {
      out.measured = "the run at dt " + text(h) + " " + run_trouble(r);
      out.run = run_command(s, h, t_end, " --trajectory x.csv");
      return out;
    }
    hs.push_back(h);
    errors.push_back(error);
  }
  // The three finest steps: the asymptotic regime.
  const std::vector<double> fine_h(hs.begin() + 1, hs.end()), fine_e(errors.begin() + 1, errors.end());
  const std::optional<double> p = observed_order(fine_h, fine_e);
  out.figures["dt"] = hs;
  out.figures["error"] = errors;
  out.figures["observed_order"] = p ? Json(*p) : Json(nullptr);
  std::string list;
  for (std::size_t k = 0; k < hs.size(); ++k) {
    list += (k ? ", " : "") + text(errors[k]) + " at dt " + text(hs[k]);
  }
  if (!p) {
    out.passed = true;
    out.measured = "exact to round-off on the oscillator (errors " + list + ")";
  } else {
    out.passed = *p >= order - 0.3;
    char number[32];
    std::snprintf(number, sizeof number, "%.2f", *p);
    out.measured = std::string("observed order ") + number + (out.passed ? " >= " : " < ") +
                   std::to_string(order) + " - 0.3 (largest error of (x, v) on the oscillator: " +
                   list + ")";
  }
  out.run = run_command(s, hs.back(), t_end, " --trajectory x.csv");
  return out;
}

StabilitySettings oscillator_search(const std::string& method, double dt_min, double dt_max) {
  StabilitySettings settings;
  settings.run.integrator = method;
  settings.run.t_end = 500;  // >= 250 steps near w h = 2
  settings.run.blowup = 1e4;
  settings.dt_min = dt_min;
  settings.dt_max = dt_max;
  settings.rel_tol = 1e-3;
  return settings;
}

std::string stability_command(const CheckSubject& s, const StabilitySettings& settings,
                              const std::string& keyword) {
  if (!s.python_call.empty()) return check_command(s, "", keyword);
  return "springlab stability " + kOscillator.command_text() + " " + s.method_arguments +
         " --t-end " + exact_text(settings.run.t_end) + " --blowup " +
         exact_text(settings.run.blowup) + " --dt-min " + exact_text(settings.dt_min) +
         " --dt-max " + exact_text(settings.dt_max);
}

// Whether a run of `steps` steps at w h = wh (w = 1) stays below the
// blow-up energy.
bool stable_at(const Oscillator& osc, const std::string& method, double wh, int steps) {
  RunSettings settings;
  settings.integrator = method;
  settings.dt = wh;
  settings.t_end = steps * wh;
  settings.blowup = 1e4;
  return !simulate(osc.model, settings).diverged();
}

ClaimResult check_stable_limit(const CheckSubject& s, double limit) {
  ClaimResult out{"--stable-limit " + exact_text(limit)};
  const Oscillator osc;
  // The first instability from below: a scan up from limit / 4 in steps of
  // 1 % (a method's stable interval need not be one piece: yoshida6 is
  // unstable just past 2.27 and stable again near 2.4), then the stability
  // search inside the first bracket.
  constexpr int kSteps = 300;
  const double ratio = 1.01;
  double lo = limit / 4, hi = 0.0;
  if (!stable_at(osc, s.integrator, lo, kSteps)) {
    out.measured = "unstable already at w h = " + text(lo) + ", a quarter of the claim";
    out.run = run_command(s, lo, kSteps * lo, " --blowup 10000 --energy energy.csv");
    return out;
  }
  for (double wh = lo * ratio; wh <= 4 * limit; wh *= ratio) {
    if (!stable_at(osc, s.integrator, wh, kSteps)) {
      hi = wh;
      break;
    }
    lo = wh;
  }
  out.figures["claimed"] = limit;
  if (hi == 0.0) {
    out.measured = "stable at every w h up to " + text(lo) + ", 4 x the claim: the limit is not " +
                   exact_text(limit);
    out.figures["measured"] = nullptr;
    out.run = run_command(s, lo, kSteps * lo, " --blowup 10000 --energy energy.csv");
    return out;
  }
  StabilitySettings settings = oscillator_search(s.integrator, lo, hi);
  settings.run.t_end = kSteps * hi;
  const StabilityResult r = find_max_stable_dt(osc.model, settings);
  const double wh = r.max_stable_dt * r.mode.w;
  out.figures["measured"] = wh;
  out.figures["bracket"] = {r.lo * r.mode.w, r.hi * r.mode.w};
  out.run = stability_command(s, settings, "stable_limit=" + exact_text(limit));
  out.passed = std::abs(wh / limit - 1.0) <= 0.02;
  out.measured = "first unstable w h " + text(wh) + (out.passed ? ", within" : ", not within") +
                 " 2 % of " + exact_text(limit) + " (undamped oscillator: a scan from " +
                 text(limit / 4) + " in steps of 1 %, then the stability search)";
  return out;
}

ClaimResult check_a_stable(const CheckSubject& s) {
  ClaimResult out{"--a-stable"};
  const Oscillator osc;
  // The search with a blow-up far above any bounded overshoot (the
  // alpha-methods' first steps overshoot by ~ w h at large steps: Hilber and
  // Hughes 1978), so it finds only growth.
  StabilitySettings settings = oscillator_search(s.integrator, 1e-2, 1e4);
  settings.run.blowup = 1e12;
  const StabilityResult r = find_max_stable_dt(osc.model, settings);
  out.run = stability_command(s, settings, "a_stable=True");
  if (r.outcome != StabilityOutcome::kStableUpToDtMax) {
    out.measured = "the stability search found a limit: largest stable w h " +
                   text(r.max_stable_dt * r.mode.w) + " (bracket [" + text(r.lo) + ", " +
                   text(r.hi) + "])";
    out.figures["max_stable_wh"] = r.max_stable_dt * r.mode.w;
    return out;
  }
  // Bounded at large steps: over 50 steps at each w h, the energy of the
  // last 25 at most 2 x the largest of the first 5 (no growth).
  double worst = 0.0, overshoot = 0.0;
  Json growth = Json::object();
  const double e0 = osc.energy(osc.model.initial_positions(), osc.model.initial_velocities());
  for (const double wh : {1.0, 10.0, 100.0, 1e3, 1e4}) {
    double early = e0, late = 0.0;
    EachStep watch([&](double t, const Vector& x, const Vector& v) {
      const double e = osc.energy(x, v);
      if (t <= 5 * wh) early = std::max(early, e);
      if (t > 25 * wh) late = std::max(late, e);
    });
    RunSettings run;
    run.integrator = s.integrator;
    run.dt = wh;
    run.t_end = 50 * wh;
    run.blowup = 1e12;
    const RunResult result = simulate(osc.model, run, {&watch});
    if (result.diverged()) {
      out.measured = "the run at w h = " + text(wh) + " " + run_trouble(result);
      out.run = run_command(s, wh, 50 * wh, " --blowup 1e12 --energy energy.csv");
      return out;
    }
    growth[exact_text(wh)] = late / early;
    overshoot = std::max(overshoot, early / e0);
    if (late / early > worst) {
      worst = late / early;
      out.run = run_command(s, wh, 50 * wh, " --blowup 1e12 --energy energy.csv");
    }
  }
  out.figures["growth"] = growth;
  out.figures["overshoot"] = overshoot;
  out.passed = worst <= 2.0;
  out.measured = "stable up to w h = 1e4 (stability search); over 50 steps at w h = 1 ... 1e4 the "
                 "energy of the last 25 steps is at most " + text(worst) +
                 " x the largest of the first 5" + (out.passed ? " (bounded" : ": it grows (") +
                 (overshoot > 1.0 + 1e-9 ? ", overshoot " + text(overshoot) + " E_0)" : ")");
  return out;
}

ClaimResult check_symplectic(const CheckSubject& s, double limit) {
  ClaimResult out{"--symplectic"};
  const Oscillator osc;
  const double wh = std::isfinite(limit) && limit > 0 ? std::min(0.5, limit / 4) : 0.5;
  const double period = 2 * kPi, t_end = 1e4 * period, first = 10 * period;
  const double e0 = osc.energy(osc.model.initial_positions(), osc.model.initial_velocities());
  double band_lo = 0, band_hi = 0, lo = 0, hi = 0, first_sum = 0, last_sum = 0;
  long first_n = 0, last_n = 0;
  std::vector<double> after;  // e over the rest, judged against the band at the end
  double out_lo = 0, out_hi = 0;
  EachStep watch([&](double t, const Vector& x, const Vector& v) {
    const double e = osc.energy(x, v) / e0 - 1.0;
    if (t <= first) {
      band_lo = std::min(band_lo, e), band_hi = std::max(band_hi, e);
      first_sum += e, ++first_n;
    } else {
      out_lo = std::min(out_lo, e), out_hi = std::max(out_hi, e);
    }
    if (t >= t_end - first) last_sum += e, ++last_n;
    lo = std::min(lo, e), hi = std::max(hi, e);
  });
  const RunResult r = run_method(osc.model, s.integrator, wh, t_end, &watch);
  out.run = run_command(s, wh, t_end, " --energy energy.csv --every 100");
  out.figures["wh"] = wh;
  out.figures["periods"] = 1e4;
  if (r.diverged()) {
    out.measured = "over 1e4 periods at w h = " + text(wh) + " the run " + run_trouble(r);
    return out;
  }
  const double width = band_hi - band_lo, tol = 0.05 * width + 1e-9;
  const double drift = last_sum / std::max(1L, last_n) - first_sum / std::max(1L, first_n);
  out.figures["first_band"] = {band_lo, band_hi};
  out.figures["whole_band"] = {lo, hi};
  out.figures["drift"] = drift;
  out.passed = out_lo >= band_lo - tol && out_hi <= band_hi + tol;
  out.measured = "energy error E/E_0 - 1 in [" + text(band_lo) + ", " + text(band_hi) +
                 "] over the first 10 periods, in [" + text(lo) + ", " + text(hi) +
                 "] over 1e4 periods at w h = " + text(wh) + " (mean drift " + text(drift) + ")" +
                 (out.passed ? ": bounded, no drift" : ": it leaves its band (drift)");
  return out;
}

ClaimResult check_dissipative(const CheckSubject& s) {
  ClaimResult out{"--dissipative"};
  const Oscillator osc;
  const double e0 = osc.energy(osc.model.initial_positions(), osc.model.initial_velocities());
  double worst = -std::numeric_limits<double>::infinity();
  Json rises = Json::object();
  for (const double wh : {0.1, 1.0, 10.0, 100.0}) {
    double previous = e0, most = -std::numeric_limits<double>::infinity();
    EachStep watch([&](double t, const Vector& x, const Vector& v) {
      const double e = osc.energy(x, v);
      if (t > 0) most = std::max(most, (e - previous) / e0);
      previous = e;
    });
    const RunResult r = run_method(osc.model, s.integrator, wh, 200 * wh, &watch);
    if (r.diverged()) {
      // A divergence gains energy too; a rise already measured at a smaller
      // step is the plainer evidence, so it is named first.
      out.figures["largest_rise"] = rises;
      out.measured = (worst > 1e-9 ? "largest energy change in one step " + text(worst) +
                                         " E_0 (the energy rises), and "
                                   : std::string()) +
                     "the run at w h = " + text(wh) + " " + run_trouble(r);
      if (worst <= 1e-9) out.run = run_command(s, wh, 200 * wh, " --energy energy.csv");
      return out;
    }
    rises[exact_text(wh)] = most;
    if (most > worst) {
      worst = most;
      out.run = run_command(s, wh, 200 * wh, " --energy energy.csv");
    }
  }
  out.figures["largest_rise"] = rises;
  out.passed = worst <= 1e-9;
  out.measured = "largest energy change in one step " + text(worst) +
                 " E_0 over 200 steps at w h = 0.1, 1, 10, 100" +
                 (out.passed ? " (never a gain)" : ": the energy rises");
  return out;
}

// A chain of six particles in 3-D, springs to the next and the one after,
// no gravity, spinning about (0.3, 0.5, 1) and drifting: momentum and
// angular momentum are conserved by the equations.
Scene free_chain() {
  Json j;
  j["name"] = "free-chain";
  j["dimension"] = 3;
  Json particles = Json::array(), springs = Json::array();
  const Eigen::Vector3d w(0.3, 0.5, 1.0), u(0.1, -0.2, 0.05);
  for (int i = 0; i < 6; ++i) {
    const Eigen::Vector3d x(0.3 * i, 0.1 * (i % 2), 0.05 * (i % 3));
    const Eigen::Vector3d v = w.cross(x) + u + 0.05 * Eigen::Vector3d(std::sin(i), std::cos(2 * i), 0.5);
    particles.push_back({{"x", {x.x(), x.y(), x.z()}}, {"v", {v.x(), v.y(), v.z()}},
                         {"mass", 1.0 + 0.2 * i}});
    if (i >= 1) springs.push_back({{"i", i - 1}, {"j", i}, {"k", 100.0}});
    if (i >= 2) springs.push_back({{"i", i - 2}, {"j", i}, {"k", 50.0}});
  }
  j["particles"] = particles;
  j["springs"] = springs;
  return parse_scene(j.dump(), "<free chain>");
}

struct Momenta {
  Eigen::Vector3d P = Eigen::Vector3d::Zero(), L = Eigen::Vector3d::Zero();
};

ClaimResult check_momentum(const CheckSubject& s) {
  ClaimResult out{"--momentum"};
  out.run = check_command(s, "--momentum", "momentum=True");
  double worst_p = 0.0, worst_l = 0.0;
  std::string where;
  // The chain: P = sum m v, L = sum m x cross v over the particles.
  {
    const Scene scene = free_chain();
    const Model model(scene);
    const Vector& m = model.mass();
    auto momenta = [&](const Vector& x, const Vector& v) {
      Momenta k;
      for (Eigen::Index i = 0; i < x.size(); i += 3) {
        const Eigen::Vector3d xi = x.segment<3>(i), vi = v.segment<3>(i);
        k.P += m[i] * vi;
        k.L += m[i] * xi.cross(vi);
      }
      return k;
    };
    const Vector& x0 = model.initial_positions();
    const Vector& v0 = model.initial_velocities();
    const Momenta k0 = momenta(x0, v0);
    double p_scale = 0, l_scale = 0;
    for (Eigen::Index i = 0; i < x0.size(); i += 3) {
      p_scale += m[i] * v0.segment<3>(i).norm();
      l_scale += m[i] * x0.segment<3>(i).norm() * v0.segment<3>(i).norm();
    }
    double dp = 0, dl = 0;
    EachStep watch([&](double, const Vector& x, const Vector& v) {
      const Momenta k = momenta(x, v);
      dp = std::max(dp, (k.P - k0.P).norm() / p_scale);
      dl = std::max(dl, (k.L - k0.L).norm() / l_scale);
    });
    const double h = 0.3 / fastest_mode(model).w;
    const RunResult r = run_method(model, s.integrator, h, 200 * h, &watch);
    if (r.diverged()) {
      out.measured = "the free chain " + run_trouble(r);
      return out;
    }
    out.figures["chain"] = {{"linear", dp}, {"angular", dl}};
    worst_p = dp, worst_l = dl;
  }
  // The free affine body: P = m dp/dt, L = m p x dp/dt + sum J_i a_i x da_i/dt.
  {
    const Scene scene = make_builtin_scene("tumbling-box");
    const Model model(scene);
    const BodyLayout layout = body_layout(scene, model.particle_order());
    const RigidBody& body = layout.bodies.at(0);
    const int first = layout.first.at(0);
    const BodyState s0 = body_state(body, first, model.initial_positions().data(),
                                    model.initial_velocities().data());
    const double kinetic = 0.5 * model.mass().dot(model.initial_velocities().cwiseAbs2());
    const double p_scale = std::sqrt(2 * body.mass.mass * kinetic), l_scale = s0.angular_momentum.norm();
    double dp = 0, dl = 0;
    EachStep watch([&](double, const Vector& x, const Vector& v) {
      const BodyState b = body_state(body, first, x.data(), v.data());
      dp = std::max(dp, (b.linear_momentum - s0.linear_momentum).norm() / p_scale);
      dl = std::max(dl, (b.angular_momentum - s0.angular_momentum).norm() / l_scale);
    });
    const double h = 0.3 / fastest_mode(model).w;
    const RunResult r = run_method(model, s.integrator, h, 200 * h, &watch);
    if (r.diverged()) {
      out.measured = "the free body (tumbling-box) " + run_trouble(r);
      return out;
    }
    out.figures["body"] = {{"linear", dp}, {"angular", dl}};
    worst_p = std::max(worst_p, dp), worst_l = std::max(worst_l, dl);
  }
  out.passed = worst_p <= 1e-6 && worst_l <= 1e-6;
  out.measured = "largest relative change over 200 steps at w_max h = 0.3 of the linear momentum " +
                 text(worst_p) + ", of the angular momentum " + text(worst_l) +
                 " (free chain, free body)" + (out.passed ? " <= 1e-6" : ": above 1e-6, not conserved");
  return out;
}

ClaimResult check_deterministic(const CheckSubject& s) {
  ClaimResult out{"--deterministic"};
  out.passed = true;
  std::string differs;
  for (const auto& [scene_name, dt, steps] :
       {std::tuple{"cloth", 0.01, 20}, std::tuple{"oscillator", 0.1, 50}}) {
    const Scene scene = make_builtin_scene(scene_name, std::string(scene_name) == "cloth"
                                                           ? std::vector<std::pair<std::string, std::string>>{{"n", "6"}}
                                                           : std::vector<std::pair<std::string, std::string>>{});
    const Model model(scene);
    const RunResult a = run_method(model, s.integrator, dt, steps * dt, nullptr);
    const RunResult b = run_method(model, s.integrator, dt, steps * dt, nullptr);
    const bool same = a.status == b.status && a.t_final == b.t_final &&
                      a.x_final.size() == b.x_final.size() && a.x_final == b.x_final &&
                      a.v_final == b.v_final;
    if (!same) {
      out.passed = false;
      const double gap = a.x_final.size() == b.x_final.size()
                             ? (a.x_final - b.x_final).lpNorm<Eigen::Infinity>()
                             : std::numeric_limits<double>::quiet_NaN();
      differs += std::string(differs.empty() ? "" : "; ") + scene_name + ": final positions differ by " + text(gap);
      out.run = run_command(s, dt, steps * dt, " --json   (twice)",
                            std::string(scene_name) == "cloth" ? CheckScene{"cloth", {{"n", "6"}}}
                                                               : kOscillator);
    }
  }
  out.measured = out.passed ? "two runs each of cloth (n = 6, 20 steps) and the oscillator (50 "
                              "steps): bit-identical final states"
                            : "two runs of the same inputs differ: " + differs;
  if (out.passed) out.run = check_command(s, "--deterministic", "deterministic=True");
  return out;
}

// Claims compared for the sanity line: what a reader sees in `list`.
bool same_stated(const Claims& a, const Claims& b) {
  auto limit_equal = [](const std::optional<double>& x, const std::optional<double>& y) {
    if (x.has_value() != y.has_value()) return false;
    return !x || std::abs(*x - *y) <= 1e-9 * std::abs(*y);
  };
  return a.order == b.order && limit_equal(a.stable_limit, b.stable_limit) &&
         a.a_stable == b.a_stable && a.symplectic == b.symplectic;
}

std::optional<SanityLine> sanity_line(const std::string& method, const Claims& claims) {
  if (is_builtin_integrator(method) || !claims.order) return std::nullopt;
  for (const std::string& name : integrator_names()) {
    if (name == method || !is_builtin_integrator(name)) continue;
    const auto builtin = make_integrator(name);
    if (builtin->info().adaptive || !same_stated(stated_claims(builtin->info()), claims)) continue;
    const Oscillator osc;
    const double h = 0.1, t_end = 2.4;
    std::vector<Vector> theirs, ours;
    EachStep keep_theirs([&](double, const Vector& x, const Vector& v) {
      Vector y(x.size() + v.size());
      y << x, v;
      theirs.push_back(y);
    });
    EachStep keep_ours([&](double, const Vector& x, const Vector& v) {
      Vector y(x.size() + v.size());
      y << x, v;
      ours.push_back(y);
    });
    run_method(osc.model, name, h, t_end, &keep_theirs);
    run_method(osc.model, method, h, t_end, &keep_ours);
    SanityLine line{name, 0.0, h};
    if (theirs.size() != ours.size()) {
      line.max_difference = std::numeric_limits<double>::infinity();
    } else {
      for (std::size_t k = 0; k < ours.size(); ++k) {
        line.max_difference = std::max(line.max_difference, (ours[k] - theirs[k]).lpNorm<Eigen::Infinity>());
      }
    }
    return line;
  }
  return std::nullopt;
}

}  // namespace

Claims stated_claims(const IntegratorInfo& info) {
  Claims c;
  c.deterministic = true;
  if (info.adaptive) return c;
  c.order = info.order;
  if (info.stability == StabilityKind::kConditional && std::isfinite(info.stability_limit) &&
      info.stability_limit > 0) {
    c.stable_limit = info.stability_limit;
  }
  c.a_stable = stable_on_imaginary_axis(info);
  c.symplectic = info.symplectic;
  if (c.a_stable && info.stability_function) {
    // |R(i y)| <= 1 for every y: checked on a grid, not assumed from the kind.
    bool contracts = true;
    for (double y = 1e-3; y <= 1e4; y *= 1.5) {
      if (std::abs(info.stability_function({0.0, y})) > 1.0 + 1e-12) contracts = false;
    }
    c.dissipative = contracts;
  }
  return c;
}

CheckReport check_claims(const CheckSubject& subject, const Claims& claims) {
  const auto method = make_integrator(subject.integrator);  // throws for an unknown name
  const IntegratorInfo& info = method->info();
  if (info.adaptive && (claims.order || claims.stable_limit || claims.a_stable || claims.symplectic ||
                        claims.dissipative)) {
    throw std::invalid_argument(subject.integrator +
                                " is adaptive: its error control picks its steps, so order, "
                                "stability and energy claims at a given step do not apply "
                                "(--momentum and --deterministic do)");
  }
  if (claims.order && (*claims.order < 1 || *claims.order > 12)) {
    throw std::invalid_argument("--order: must be a whole number from 1 to 12");
  }
  if (claims.stable_limit && !(*claims.stable_limit > 0 && std::isfinite(*claims.stable_limit))) {
    throw std::invalid_argument("--stable-limit: must be a positive w h (--a-stable claims every step)");
  }
  CheckReport report;
  report.integrator = subject.integrator;
  if (claims.order) report.results.push_back(check_order(subject, *claims.order));
  if (claims.stable_limit) report.results.push_back(check_stable_limit(subject, *claims.stable_limit));
  if (claims.a_stable) report.results.push_back(check_a_stable(subject));
  if (claims.symplectic) {
    const double limit = claims.stable_limit.value_or(info.stability_limit);
    report.results.push_back(check_symplectic(subject, limit));
  }
  if (claims.dissipative) report.results.push_back(check_dissipative(subject));
  if (claims.momentum) report.results.push_back(check_momentum(subject));
  if (claims.deterministic) report.results.push_back(check_deterministic(subject));
  report.sanity = sanity_line(subject.integrator, claims);
  return report;
}

Json check_report_json(const CheckReport& report) {
  Json j;
  j["integrator"] = report.integrator;
  j["passed"] = report.passed();
  Json claims = Json::array();
  for (const ClaimResult& r : report.results) {
    claims.push_back({{"claim", r.claim},
                      {"passed", r.passed},
                      {"measured", r.measured},
                      {"figures", r.figures},
                      {"run", r.run}});
  }
  j["claims"] = claims;
  if (report.sanity) {
    j["sanity"] = {{"builtin", report.sanity->builtin},
                   {"max_difference", report.sanity->max_difference},
                   {"dt", report.sanity->dt}};
  } else {
    j["sanity"] = nullptr;
  }
  return j;
}

std::string check_report_text(const CheckReport& report) {
  std::ostringstream out;
  int passed = 0;
  for (const ClaimResult& r : report.results) passed += r.passed ? 1 : 0;
  out << report.integrator << ": " << passed << " of " << report.results.size()
      << " claims hold\n";
  for (const ClaimResult& r : report.results) {
    out << (r.passed ? "PASS  " : "FAIL  ") << r.claim << ": " << r.measured << "\n";
    if (!r.run.empty()) out << "      " << r.run << "\n";
  }
  if (report.sanity) {
    const SanityLine& s = *report.sanity;
    out << "sanity: " << s.builtin << " states the same claims; the largest difference of (x, v) "
        << "from it on the oscillator at dt " << text(s.dt) << " is " << text(s.max_difference)
        << (s.max_difference <= 1e-12 ? " (the same trajectory)" : " (another method)") << "\n";
  }
  return out.str();
}

}  // namespace springlab
