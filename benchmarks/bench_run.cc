// BM_RunPair/<method>/<scene>/<n>: what `springlab run` costs per step
// (experiments/driver/simulation.h's driver: the integrator's step plus the
// driver's divergence check and bookkeeping, no output files) against the
// kernel doing the same work, timed in alternation in one benchmark so both
// see the same machine load:
//   - symplectic-euler: the kernel is the bare step, Integrator::advance_to
//     (one force evaluation, BM_Force's work, plus one pass updating v and x);
//     ratio = run / step;
//   - rk4: the kernel is Boost.Odeint's runge_kutta4 on the same model and
//     dt (bench_odeint.cc's peer); ratio = run / odeint.
// One benchmark iteration: kBatch steps of each side (which goes first
// alternates). The run side is simulate() over kBatch steps from the initial
// state, as a user's run from t = 0 (its set-up, the energy of the first and
// last state, is part of it: 1 / kBatch of a step's worth per step); the
// kernel side continues from where it stopped. dt = 0.5 / w_max (as
// BM_Step's explicit methods); kBatch steps of it never diverge from rest.
// Counters: run_us and kernel_us per step, ratio, force_us (one
// Model::force at the initial state, timed in the same loop: the
// floor of a symplectic Euler step); run_min_us, kernel_min_us and
// ratio_min from the fastest batch of each side (on a busy machine, the
// batch least disturbed by other processes: a batch of the chain is about
// 1.5 ms, shorter than a scheduler's time slice).
#include <algorithm>
#include <chrono>
#include <limits>
#include <memory>
#include <string>

#include <boost/numeric/odeint.hpp>
#include <boost/numeric/odeint/external/eigen/eigen.hpp>

#include "benchmarks/bench_support.h"
#include "experiments/driver/simulation.h"
#include "integrators/registry/registry.h"

namespace springlab::bench {
namespace {

namespace odeint = boost::numeric::odeint;
using Clock = std::chrono::steady_clock;

constexpr long kBatch = 256;

double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

// The kernel: kBatch steps of springlab's integrator alone, or of odeint's
// runge_kutta4 on y = (x, v).
class Kernel {
 public:
  Kernel(const Model& model, const std::string& method, double dt)
      : model_(model), dt_(dt), odeint_(method == "rk4"), n_(model.dofs()) {
    if (odeint_) {
      y_.resize(2 * n_);
      y_ << model.initial_positions(), model.initial_velocities();
    } else {
      integrator_ = make_integrator(method);
      integrator_->initialize(model, 0.0, model.initial_positions(), model.initial_velocities(),
                              {});
    }
  }
  void steps(long count) {
    for (long k = 0; k < count; ++k) {
      if (odeint_) {
        rk4_.do_step(
            [this](const Vector& y, Vector& dydt, double t) {
              x_ = y.head(n_);
              v_ = y.tail(n_);
              model_.force(t, x_, v_, f_);
              dydt.resize(2 * n_);
              dydt.head(n_) = v_;
              dydt.tail(n_) = f_.cwiseQuotient(model_.mass());
            },
            y_, t_, dt_);
        t_ += dt_;
      } else {
        integrator_->advance_to(integrator_->t() + dt_);
      }
    }
  }

 private:
  const Model& model_;
  double dt_;
  bool odeint_;
  Eigen::Index n_;
  std::unique_ptr<Integrator> integrator_;
  odeint::runge_kutta4<Vector, double, Vector, double, odeint::vector_space_algebra> rk4_;
  Vector y_, x_, v_, f_;
  double t_ = 0.0;
};

void run_pair(benchmark::State& state, const std::string& method, const SceneCase& c) {
  const Model& model = model_for(c);
  const double w_max = max_frequency_for(c);
  const double dt = w_max > 0.0 ? 0.5 / w_max : 1.0 / 60.0;
  RunSettings settings;
  settings.integrator = method;
  settings.dt = dt;
  settings.t_end = static_cast<double>(kBatch) * dt;
  Kernel kernel(model, method, dt);
  Vector f;
  double run_s = 0.0, kernel_s = 0.0, force_s = 0.0;
  double run_min = std::numeric_limits<double>::infinity(), kernel_min = run_min;
  long steps = 0, forces = 0;
  bool run_first = true;
  for (auto _ : state) {
    for (int side = 0; side < 2; ++side) {
      const auto start = Clock::now();
      if ((side == 0) == run_first) {
        const RunResult r = simulate(model, settings);
        const double batch = seconds_since(start);
        run_s += batch;
        run_min = std::min(run_min, batch);
        if (r.status != RunStatus::kCompleted) {
          state.SkipWithError(("the run did not complete: " + r.failure).c_str());
          return;
        }
      } else {
        kernel.steps(kBatch);
        const double batch = seconds_since(start);
        kernel_s += batch;
        kernel_min = std::min(kernel_min, batch);
      }
    }
    const auto start = Clock::now();
    for (int k = 0; k < 16; ++k) {
      model.force(0.0, model.initial_positions(), model.initial_velocities(), f);
    }
    force_s += seconds_since(start);
    forces += 16;
    run_first = !run_first;
    steps += kBatch;
  }
  if (steps > 0 && kernel_s > 0.0) {
    const double per_step = 1e6 / static_cast<double>(steps);
    state.counters["run_us"] = run_s * per_step;
    state.counters["kernel_us"] = kernel_s * per_step;
    state.counters["force_us"] = 1e6 * force_s / static_cast<double>(forces);
    state.counters["ratio"] = run_s / kernel_s;
    state.counters["run_min_us"] = 1e6 * run_min / static_cast<double>(kBatch);
    state.counters["kernel_min_us"] = 1e6 * kernel_min / static_cast<double>(kBatch);
    state.counters["ratio_min"] = run_min / kernel_min;
  }
  add_size_counters(state, model);
  state.SetLabel(std::string(method == "rk4" ? "kernel: odeint runge_kutta4" :
                                               "kernel: the bare step") +
                 "; dt=0.5/w_max=" + short_number(dt) + " s; " + std::to_string(kBatch) +
                 " steps of each per iteration");
}

}  // namespace

void register_run_benchmarks() {
  for (const SceneCase& c : all_cases()) {
    for (const char* method : {"symplectic-euler", "rk4"}) {
      benchmark::RegisterBenchmark(
          ("BM_RunPair/" + std::string(method) + "/" + c.path()).c_str(),
          [c, m = std::string(method)](benchmark::State& s) { run_pair(s, m, c); })
          ->Unit(benchmark::kMillisecond)
          ->MinTime(0.5);
    }
  }
}

}  // namespace springlab::bench
