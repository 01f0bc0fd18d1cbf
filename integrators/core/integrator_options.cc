#include "integrators/core/integrator_options.h"

#include "models/core/decimal_text.h"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace springlab {
namespace {

using Range = OptionSpec::Range;

// The shortest text that reads back to the value ("1e-06", "0.5"): a
// refusal prints the value as given (--beta 0.5000001, not 0.5).
std::string number_text(double value) { return shortest_decimal(value); }

std::string choices_text(const OptionSpec& spec) {
  std::string text;
  for (std::string_view c : spec.choices) text += (text.empty() ? "" : ", ") + std::string(c);
  return text;
}

}  // namespace

bool parse_stiffness(const std::string& name, Stiffness& stiffness) {
  if (name == "exact") {
    stiffness = Stiffness::kExact;
  } else if (name == "definite") {
    stiffness = Stiffness::kDefinite;
  } else {
    return false;
  }
  return true;
}

bool parse_solver(const std::string& name, Solver& solver) {
  if (name == "newton") {
    solver = Solver::kNewton;
  } else if (name == "quasi-newton") {
    solver = Solver::kQuasiNewton;
  } else {
    return false;
  }
  return true;
}

const char* to_string(Solver solver) {
  return solver == Solver::kQuasiNewton ? "quasi-newton" : "newton";
}

const char* to_string(Stiffness stiffness) {
  return stiffness == Stiffness::kDefinite ? "definite" : "exact";
}

const std::vector<OptionSpec>& integrator_options() {
  using O = IntegratorOptions;
  static const std::vector<OptionSpec> table = {
      {.name = "rtol", .field = &O::rtol, .range = Range::kPositive,
       .help = "adaptive methods: relative tolerance"},
      {.name = "atol", .field = &O::atol, .range = Range::kPositive,
       .help = "adaptive methods: absolute tolerance"},
      {.name = "newton-tol", .field = &O::newton_tol, .range = Range::kPositive,
       .help = "implicit methods: Newton stops when its update ||dv||_inf <= tol [m/s]"},
      {.name = "max-newton", .field = &O::max_newton, .range = Range::kAtLeastOne,
       .help = "implicit methods: Newton iterations per step before the run fails"},
      {.name = "stiffness", .range = Range::kChoice, .choices = {"exact", "definite"},
       .help = "linear-implicit-euler: exact dF/dx, or definite (compressed springs' negative "
               "transverse stiffness dropped, Choi and Ko 2002)",
       .get = [](const O& o) { return std::string(to_string(o.stiffness)); },
       .set = [](O& o, const std::string& v) { return parse_stiffness(v, o.stiffness); }},
      {.name = "solver", .range = Range::kChoice, .choices = {"newton", "quasi-newton"},
       .help = "implicit-euler: newton, or quasi-newton (L-BFGS with the local/global matrix "
               "as its initial Hessian, Liu et al. 2017)",
       .get = [](const O& o) { return std::string(to_string(o.solver)); },
       .set = [](O& o, const std::string& v) { return parse_solver(v, o.solver); }},
      {.name = "iterations", .field = &O::iterations, .range = Range::kOneToCap,
       .default_text = "the method's",
       .help = "projective-dynamics (default 10), xpbd (default 1), vbd (default 10): "
               "iterations per step or substep"},
      {.name = "chebyshev", .field = &O::chebyshev, .range = Range::kUnitOpen,
       .default_text = "0",
       .help = "projective-dynamics, vbd: Chebyshev acceleration with this spectral radius rho "
               "of the plain iteration, in (0, 1) (Wang 2015); 0: off; vbd also without a value: "
               "on at its own rho, 0.9",
       .bare_value = kChebyshevOn},
      {.name = "no-chebyshev", .field = &O::no_chebyshev,
       .help = "projective-dynamics, vbd: no Chebyshev acceleration, whatever --chebyshev says"},
      {.name = "substeps", .field = &O::substeps, .range = Range::kOneToCap,
       .default_text = "the method's", .help = "xpbd (default 10), vbd (default 1): substeps "
                                               "per --dt"},
      {.name = "beta", .field = &O::beta, .default_text = "1/4",
       .help = "newmark: beta in [0, 1/2]"},
      {.name = "gamma", .field = &O::gamma, .default_text = "1/2",
       .help = "newmark: gamma in [1/2, 1] (above 1/2 damps every mode)"},
      {.name = "alpha", .field = &O::alpha, .default_text = "-0.1",
       .help = "hht-alpha: alpha in [-1/3, 0]"},
      {.name = "rho-inf", .field = &O::rho_inf, .default_text = "0.5",
       .help = "generalized-alpha: spectral radius at infinity in [0, 1]"},
      {.name = "max-steps", .field = &O::max_steps, .range = Range::kAtLeastOneIfGiven,
       .default_text = "scaled",
       .help = "adaptive methods: internal steps per output interval before failing (default: "
               "5e6 / unknowns, between 500 and 100000)"},
      {.name = "max-order", .field = &O::max_order, .range = Range::kAtLeastOneIfGiven,
       .default_text = "the method's",
       .help = "adaptive methods: highest order (ARKODE: the method's order)"},
      {.name = "linear-solver", .range = Range::kChoice,
       .choices = {"auto", "dense", "klu", "gmres", "reduced"},
       .help = "implicit adaptive methods: dense, klu, gmres, reduced (the n x n matrix "
               "M - gamma D - gamma^2 K) or auto (dense up to 100 unknowns, reduced above)",
       .get = [](const O& o) { return o.linear_solver; },
       .set =
           [](O& o, const std::string& v) {
             for (const char* c : {"auto", "dense", "klu", "gmres", "reduced"}) {
               if (v == c) {
                 o.linear_solver = v;
                 return true;
               }
             }
             return false;
           }},
      {.name = "dq-jacobian", .field = &O::dq_jacobian,
       .help = "implicit adaptive methods: SUNDIALS difference quotients instead of the analytic "
               "Jacobian"},
      {.name = "stald", .field = &O::stald, .help = "cvode-bdf: stability limit detection"},
  };
  return table;
}

const OptionSpec* find_integrator_option(std::string_view name) {
  for (const OptionSpec& spec : integrator_options()) {
    if (spec.name == name) return &spec;
  }
  return nullptr;
}

std::string check_option_range(const OptionSpec& spec, const IntegratorOptions& options,
                               bool given) {
  // The value as a number (flags and choices have no range to check).
  double value = 0.0;
  bool integral = true;
  if (const auto* d = std::get_if<double IntegratorOptions::*>(&spec.field)) {
    value = options.**d;
    integral = false;
  } else if (const auto* i = std::get_if<int IntegratorOptions::*>(&spec.field)) {
    value = options.**i;
  } else if (const auto* l = std::get_if<long IntegratorOptions::*>(&spec.field)) {
    value = static_cast<double>(options.**l);
  } else {
    return {};
  }
  switch (spec.range) {
    case Range::kPositive:
      if (!(value > 0.0) || !std::isfinite(value)) return "must be a positive number (got " + number_text(value) + ")";
      break;
    case Range::kAtLeastOne:
      if (value < 1.0) return "must be >= 1";
      break;
    case Range::kAtLeastOneIfGiven:
      if (value < 0.0 || (given && value < 1.0)) return "must be >= 1";
      break;
    case Range::kOneToCap:
      if (given && (value < 1.0 || value > kMaxInnerCount)) {
        return "must be between 1 and " + std::to_string(kMaxInnerCount) + " (got " +
               (integral ? std::to_string(static_cast<long long>(value)) : number_text(value)) +
               ")";
      }
      break;
    case Range::kUnitOpen:
      if (value == spec.bare_value) break;     // given without a value
      if (!(value >= 0.0 && value < 1.0)) return "must be in [0, 1) (0: off)";
      break;
    case Range::kAny:
      // (Unset is NaN, the method's default: a given NaN or infinity is no
      // value, not a request for the default.)
      if (given && !integral && !std::isfinite(value)) {
        return "must be a finite number (got " + number_text(value) + ")";
      }
      break;
    case Range::kChoice:
      break;
  }
  return {};
}

std::string choice_refusal(const OptionSpec& spec, const std::string& printable_value) {
  return "unknown '" + printable_value + "' (" + choices_text(spec) + ")";
}

}  // namespace springlab
