// damping-budget: with drag and spring damping the mechanical energy falls
// by exactly the work W_nc the non-conservative forces do,
//   E(t) - E(0) = W_nc(t) = integral of sum F_nc . v dt,
// so budget = E - W_nc stays at E(0) for an exact solution. What an
// integrator leaves over, numerical = budget - E(0), is its own numerical
// dissipation (negative: it removed energy the physics did not), shown apart
// from the physical damping. W_nc is accumulated with the trapezoid rule on
// every step of the output grid, so it has its own O(dt^2) quadrature error.
#include <memory>

#include "experiments/kinds/experiment.h"
#include "experiments/kinds/experiment_support.h"

namespace springlab {
namespace {

class BudgetRows final : public Observer {
 public:
  BudgetRows(const Model& model, std::string prefix, int every,
             std::vector<std::string>& rows)
      : model_(model), prefix_(std::move(prefix)), every_(every), rows_(rows) {}

  void observe(double t, const Vector& x, const Vector& v) override {
    const double energy = model_.energies(x, v).total();
    const double power = model_.nonconservative_power(t, x, v);
    if (count_ == 0) {
      initial_ = energy;
    } else {
      work_ += 0.5 * (t - t_previous_) * (power + power_previous_);
    }
    t_previous_ = t;
    power_previous_ = power;
    last_ = Row().raw(prefix_).add(t).add(energy).add(work_).add(energy - work_)
                .add(energy - work_ - initial_).str();
    last_written_ = count_ % every_ == 0;
    if (last_written_) rows_.push_back(last_);
    ++count_;
  }
  // The final state always gets a row.
  void finish() {
    if (!last_written_ && !last_.empty()) rows_.push_back(last_);
  }

 private:
  const Model& model_;
  std::string prefix_;
  int every_;
  std::vector<std::string>& rows_;
  long count_ = 0;
  double initial_ = 0.0, work_ = 0.0, t_previous_ = 0.0, power_previous_ = 0.0;
  std::string last_;
  bool last_written_ = true;
};

class DampingBudgetExperiment final : public TimedCasesExperiment {
 public:
  explicit DampingBudgetExperiment(const DefinitionObject& d) : TimedCasesExperiment(d) {}

  std::vector<TableSpec> tables() const override {
    return {{"", {"scene", "integrator", "dt", "t", "mechanical", "work_nonconservative", "budget",
                  "numerical"}}};
  }

  TaskOutput run_task(std::size_t index) const override {
    Task t = task(index);
    const Model model(t.c.scene);
    t.run.every = 1;  // every step observed: the work needs each one
    TaskOutput out;
    out.rows.resize(1);
    BudgetRows rows(model, t.prefix, t.c.every, out.rows[0]);
    simulate(model, t.run, {&rows});
    rows.finish();
    return out;
  }
};

}  // namespace

std::unique_ptr<Experiment> make_damping_budget_experiment(const DefinitionObject& d) {
  return std::make_unique<DampingBudgetExperiment>(d);
}

const ExperimentKind& damping_budget_experiment_kind() {
  static const ExperimentKind kind{"damping-budget", &make_damping_budget_experiment};
  return kind;
}

}  // namespace springlab
