// BM_OdeintStep/<method>/<scene>/<n>: Boost.Odeint stepping the same model
// (its own Model::force, divided by the lumped mass) with the same
// dt as springlab's BM_Step/<method>/<scene>/<n> (0.5 / w_max), so
// springlab / odeint time ratios can be read off one run:
//   - rk4: odeint::runge_kutta4 on the first-order state y = (x, v) (one
//     Eigen vector of 2n, vector_space_algebra). The right-hand side copies
//     y's halves into the x and v vectors force() takes — the natural way to
//     hand this model to odeint;
//   - symplectic-euler: odeint::symplectic_euler on the pair (q, p) = (x, v)
//     (unit-mass form: dq/dt = p, dp/dt = M^-1 F(q)). Odeint's variant
//     drifts first (x+ = x + h v, v+ = v + h a(x+)), springlab's kicks first
//     (v+ = v + h a(x, v), x+ = x + h v+): the adjoint pair, one force
//     evaluation per step either way. odeint's momentum function sees q only,
//     so this family runs only on scenes whose forces do not depend on v
//     (true of the default cloth and chain).
// Both loops carry the same instrumentation as BM_Step (a divergence check
// outside the timing every kCheckEvery steps) so the comparison is even, and
// the same repetitions (mean / median / stddev of 3 runs).
//
// BM_OdeintPair/<method>/<scene>/<n> runs springlab's and odeint's step in
// alternation inside one benchmark and reports their ratio directly (see
// paired_benchmark): on a busy machine two separate runs can differ by 30%,
// the paired ratio much less. The report prefers it for the ratio.
#include <boost/numeric/odeint.hpp>
#include <boost/numeric/odeint/external/eigen/eigen.hpp>
#include <chrono>
#include <memory>
#include <string>
#include <utility>

#include "benchmarks/bench_support.h"
#include "integrators/registry/registry.h"

namespace springlab::bench {
namespace {

namespace odeint = boost::numeric::odeint;

constexpr long kCheckEvery = 16;
constexpr double kBlowup = 1000.0;
constexpr int kRepetitions = 3;  // as BM_Step's rk4 and symplectic-euler

double explicit_dt(const SceneCase& c) {
  const double w_max = max_frequency_for(c);
  return w_max > 0.0 ? 0.5 / w_max : 1.0 / 60.0;
}

bool diverged(const Model& model, const Vector& x, const Vector& v) {
  if (!x.allFinite() || !v.allFinite()) return true;
  const double scale = model.energy_scale();
  if (!(scale > 0.0)) return false;
  const Energies e = model.energies(x, v);
  return !(e.kinetic_and_spring() <= kBlowup * scale);
}

void finish(benchmark::State& state, const Model& model, double dt, long force_evals,
            long restarts) {
  using benchmark::Counter;
  const double iterations = static_cast<double>(state.iterations());
  state.counters["force_evals_per_step"] =
      Counter(static_cast<double>(force_evals), Counter::kAvgIterations);
  state.counters["restarts"] = static_cast<double>(restarts);
  state.counters["dt"] = dt;
  state.counters["cpu_per_sim_second"] =
      Counter(iterations * dt, Counter::kIsRate | Counter::kInvert);
  state.counters["unknowns_per_second"] =
      Counter(iterations * static_cast<double>(model.dofs()), Counter::kIsRate);
  add_size_counters(state, model);
  state.SetLabel("dt=0.5/w_max=" + short_number(dt) + " s");
}

// y' = f(y) for y = (x, v): (v, M^-1 F(t, x, v)).
class FirstOrderRhs {
 public:
  explicit FirstOrderRhs(const Model& model)
      : model_(&model), n_(model.dofs()), inv_mass_(model.mass().cwiseInverse()) {}
  void operator()(const Vector& y, Vector& dydt, double t) {
    ++evals;
    x_ = y.head(n_);
    v_ = y.tail(n_);
    model_->force(t, x_, v_, f_);
    dydt.resize(2 * n_);
    dydt.head(n_) = v_;
    dydt.tail(n_) = f_.cwiseProduct(inv_mass_);
  }
  long evals = 0;

 private:
  const Model* model_;
  Eigen::Index n_;
  Vector inv_mass_, x_, v_, f_;
};

// odeint::runge_kutta4 on y = (x, v).
class OdeintRk4 {
 public:
  static constexpr const char* kName = "rk4";
  OdeintRk4(const Model& model, double dt)
      : model_(&model), dt_(dt), n_(model.dofs()), y0_(2 * n_), rhs_(model) {
    y0_ << model.initial_positions(), model.initial_velocities();
    y_ = y0_;
  }
  void step() {
    stepper_.do_step(std::ref(rhs_), y_, t_, dt_);
    t_ += dt_;
  }
  bool diverged_state() const { return diverged(*model_, y_.head(n_), y_.tail(n_)); }
  void reset() {
    y_ = y0_;
    t_ = 0.0;
  }
  long evals() const { return rhs_.evals; }

 private:
  const Model* model_;
  double dt_;
  Eigen::Index n_;
  Vector y0_, y_;
  double t_ = 0.0;
  FirstOrderRhs rhs_;
  odeint::runge_kutta4<Vector, double, Vector, double, odeint::vector_space_algebra> stepper_;
};

// dp/dt = M^-1 F(q) (p = v: unit-mass form of the Hamiltonian system).
class MomentumRhs {
 public:
  explicit MomentumRhs(const Model& model)
      : model_(&model),
        inv_mass_(model.mass().cwiseInverse()),
        zero_v_(Vector::Zero(model.dofs())) {}
  void operator()(const Vector& q, Vector& dpdt) {
    ++evals;
    model_->force(0.0, q, zero_v_, f_);
    dpdt = f_.cwiseProduct(inv_mass_);
  }
  long evals = 0;

 private:
  const Model* model_;
  Vector inv_mass_, zero_v_, f_;
};

// odeint::symplectic_euler on (q, p) = (x, v).
class OdeintSymplecticEuler {
 public:
  static constexpr const char* kName = "symplectic-euler";
  OdeintSymplecticEuler(const Model& model, double dt)
      : model_(&model), dt_(dt), rhs_(model) {
    reset();
  }
  void step() {
    stepper_.do_step(std::ref(rhs_), std::make_pair(std::ref(q_), std::ref(p_)), t_, dt_);
    t_ += dt_;
  }
  bool diverged_state() const { return diverged(*model_, q_, p_); }
  void reset() {
    q_ = model_->initial_positions();
    p_ = model_->initial_velocities();
    t_ = 0.0;
  }
  long evals() const { return rhs_.evals; }

 private:
  const Model* model_;
  double dt_;
  Vector q_, p_;
  double t_ = 0.0;
  MomentumRhs rhs_;
  odeint::symplectic_euler<Vector, Vector, double, Vector, Vector, double,
                           odeint::vector_space_algebra>
      stepper_;
};

bool usable(benchmark::State& state, const Model& model) {
  if (model.velocity_dependence() == VelocityDependence::kNone) return true;
  // odeint's symplectic steppers give the momentum function q only.
  state.SkipWithError("forces depend on v: odeint's symplectic_euler cannot express that");
  return false;
}

template <class Stepper>
void odeint_benchmark(benchmark::State& state, const SceneCase& c) {
  const Model& model = model_for(c);
  if (std::string(Stepper::kName) == "symplectic-euler" && !usable(state, model)) return;
  const double dt = explicit_dt(c);
  Stepper stepper(model, dt);
  long restarts = 0, since_check = 0;
  for (auto _ : state) {
    stepper.step();
    if (++since_check == kCheckEvery) {
      state.PauseTiming();
      since_check = 0;
      if (stepper.diverged_state()) {
        ++restarts;
        stepper.reset();
      }
      state.ResumeTiming();
    }
  }
  finish(state, model, dt, stepper.evals(), restarts);
}

// BM_OdeintPair: springlab's method and odeint's in alternation, kCheckEvery
// steps of each per iteration (which goes first alternates), each batch timed
// with the steady clock. Both see the same machine load within milliseconds,
// so their ratio is steadier than that of two separate benchmarks on a busy
// machine. Counters: springlab_us and odeint_us per step, ratio.
template <class Stepper>
void paired_benchmark(benchmark::State& state, const SceneCase& c) {
  using Clock = std::chrono::steady_clock;
  const Model& model = model_for(c);
  if (std::string(Stepper::kName) == "symplectic-euler" && !usable(state, model)) return;
  const double dt = explicit_dt(c);
  Stepper peer(model, dt);
  std::unique_ptr<Integrator> mine = make_integrator(Stepper::kName);
  auto init_mine = [&]() {  // a new integrator per run (Integrator::initialize)
    mine = make_integrator(Stepper::kName);
    return mine->initialize(model, 0.0, model.initial_positions(), model.initial_velocities(),
                            {}).ok;
  };
  if (!init_mine()) {
    state.SkipWithError("springlab integrator failed to initialize");
    return;
  }
  double mine_s = 0.0, peer_s = 0.0;
  long steps = 0;
  bool mine_first = true;
  for (auto _ : state) {
    for (int side = 0; side < 2; ++side) {
      const auto start = Clock::now();
      if ((side == 0) == mine_first) {
        for (long k = 0; k < kCheckEvery; ++k) mine->advance_to(mine->t() + dt);
        mine_s += std::chrono::duration<double>(Clock::now() - start).count();
      } else {
        for (long k = 0; k < kCheckEvery; ++k) peer.step();
        peer_s += std::chrono::duration<double>(Clock::now() - start).count();
      }
    }
    mine_first = !mine_first;
    steps += kCheckEvery;
    state.PauseTiming();
    if (peer.diverged_state()) peer.reset();
    if (diverged(model, mine->x(), mine->v()) && !init_mine()) {
      state.SkipWithError("springlab integrator failed to re-initialize");
    }
    state.ResumeTiming();
  }
  if (steps > 0 && peer_s > 0.0) {
    state.counters["springlab_us"] = 1e6 * mine_s / static_cast<double>(steps);
    state.counters["odeint_us"] = 1e6 * peer_s / static_cast<double>(steps);
    state.counters["ratio"] = mine_s / peer_s;
  }
  add_size_counters(state, model);
  state.SetLabel("dt=0.5/w_max=" + short_number(dt) + " s; " + std::to_string(kCheckEvery) +
                 " steps of each per iteration");
}

}  // namespace

void register_odeint_benchmarks() {
  for (const SceneCase& c : all_cases()) {
    benchmark::RegisterBenchmark(("BM_OdeintStep/rk4/" + c.path()).c_str(),
                                 [c](benchmark::State& s) { odeint_benchmark<OdeintRk4>(s, c); })
        ->Unit(benchmark::kMicrosecond)
        ->MinTime(0.3)
        ->Repetitions(kRepetitions)
        ->ReportAggregatesOnly(true);
    benchmark::RegisterBenchmark(
        ("BM_OdeintStep/symplectic-euler/" + c.path()).c_str(),
        [c](benchmark::State& s) { odeint_benchmark<OdeintSymplecticEuler>(s, c); })
        ->Unit(benchmark::kMicrosecond)
        ->MinTime(0.3)
        ->Repetitions(kRepetitions)
        ->ReportAggregatesOnly(true);
  }
  for (const SceneCase& c : all_cases()) {
    benchmark::RegisterBenchmark(("BM_OdeintPair/rk4/" + c.path()).c_str(),
                                 [c](benchmark::State& s) { paired_benchmark<OdeintRk4>(s, c); })
        ->Unit(benchmark::kMillisecond)
        ->MinTime(0.5);
    benchmark::RegisterBenchmark(
        ("BM_OdeintPair/symplectic-euler/" + c.path()).c_str(),
        [c](benchmark::State& s) { paired_benchmark<OdeintSymplecticEuler>(s, c); })
        ->Unit(benchmark::kMillisecond)
        ->MinTime(0.5);
  }
}

}  // namespace springlab::bench
