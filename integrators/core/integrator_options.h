// The run options of the integrators, each declared once (issue 32.4): its
// name, type, default, allowed range and help. The command line
// (experiments/cli/cli.cc: options, --help, checks, the note on options a method
// ignores), the experiment definitions (experiments/kinds/experiment_support.cc:
// the same names with '_' for '-') and Python (springlab.run's keywords,
// through the command line's parser) read integrator_options(). Adding an
// option is a field of IntegratorOptions and a line of the table
// (integrator_options.cc); the method that reads it lists it in
// Integrator::options_read().
#pragma once

#include <atomic>
#include <limits>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

namespace springlab {

// Which stiffness dF/dx a linearized step uses: the exact one, or its
// definite part (each compressed spring's negative transverse stiffness
// dropped, Choi and Ko 2002), which keeps M - h^2 dF/dx positive definite.
enum class Stiffness { kExact, kDefinite };
// "exact" / "definite" (the command line's and definitions' names); false
// for another name.
bool parse_stiffness(const std::string& name, Stiffness& stiffness);
const char* to_string(Stiffness stiffness);

// How implicit-euler solves its step (docs/integrators.md "Fast solvers"): Newton, or
// L-BFGS with the local/global matrix as its initial Hessian.
enum class Solver { kNewton, kQuasiNewton };
bool parse_solver(const std::string& name, Solver& solver);
const char* to_string(Solver solver);

// Every knob any method reads; each method uses only the ones it needs
// (Integrator::options_read). Each is declared in integrator_options() below.
struct IntegratorOptions {
  double newton_tol = 1e-4;   // m/s: converged when the Newton update ||dv||_inf is below it
  int max_newton = 200;       // Newton iterations per step before giving up (measured: benchmarks/README.md)
  Stiffness stiffness = Stiffness::kExact;  // linear-implicit-euler's dF/dx
  Solver solver = Solver::kNewton;          // implicit-euler's
  int iterations = 0;  // projective-dynamics, xpbd, vbd: iterations per (sub)step; 0 = the method's
  // projective-dynamics, vbd: Chebyshev's spectral radius rho; 0 = off;
  // kChebyshevOn (--chebyshev without RHO) = on at vbd's own rho.
  double chebyshev = 0.0;
  bool no_chebyshev = false;  // --no-chebyshev: off, whatever --chebyshev says
  int substeps = 0;    // xpbd, vbd: substeps per step; 0 = the method's
  double rtol = 1e-6;         // adaptive methods
  double atol = 1e-8;
  long max_steps = 0;         // adaptive: internal steps per output interval; 0 = scaled to the system
  int max_order = 0;          // adaptive: 0 = the method's default
  std::string linear_solver = "auto";
  bool dq_jacobian = false;
  bool stald = false;
  // A stop request (Ctrl-C in a sweep): when set and true, a method that
  // takes many internal steps in one advance_to() fails at the next one.
  const std::atomic<bool>* stop = nullptr;
  // The Newmark family (newmark_family.h); NaN: the method's own value.
  double beta = std::numeric_limits<double>::quiet_NaN();     // newmark: --beta
  double gamma = std::numeric_limits<double>::quiet_NaN();    // newmark: --gamma
  double alpha = std::numeric_limits<double>::quiet_NaN();    // hht-alpha: --alpha
  double rho_inf = std::numeric_limits<double>::quiet_NaN();  // generalized-alpha: --rho-inf
};

// One option as the table declares it.
struct OptionSpec {
  std::string_view name;  // --name on the command line; name_with_underscores elsewhere
  // Where the value lives: a number, a count or a flag; a choice (a name)
  // is read and set through `get` and `set` instead (std::monostate).
  std::variant<std::monostate, double IntegratorOptions::*, int IntegratorOptions::*,
               long IntegratorOptions::*, bool IntegratorOptions::*>
      field;
  // The values it takes (the refusal's problem, which the caller puts
  // after its own name of the option: "--name: ..." on the command line):
  enum class Range {
    kAny,         // any value (a method checks its own: --beta, --alpha, ...)
    kPositive,    // > 0 ("must be a positive number (got x)")
    kAtLeastOne,  // >= 1 ("must be >= 1")
    kAtLeastOneIfGiven,  // >= 1 when given; 0 left alone is the method's own
    kOneToCap,    // 1 ... kMaxInnerCount when given
    kUnitOpen,    // [0, 1) (--chebyshev: 0 is off)
    kChoice,      // one of `choices`
  } range = Range::kAny;
  std::vector<std::string_view> choices = {};
  const char* default_text = "";  // as --help shows it; empty: the field's initial value
  const char* help = "";
  // A choice's value as written ("definite"), and setting it (false for a
  // name that is not one of `choices`).
  std::string (*get)(const IntegratorOptions&) = nullptr;
  bool (*set)(IntegratorOptions&, const std::string&) = nullptr;
  // The value an option given without one takes (NaN: a value is required):
  // --chebyshev alone is kChebyshevOn.
  double bare_value = std::numeric_limits<double>::quiet_NaN();
};

// The table, in the order --help lists them.
const std::vector<OptionSpec>& integrator_options();
// The spec of --name (nullptr when there is none).
const OptionSpec* find_integrator_option(std::string_view name);

// --chebyshev given without RHO: Chebyshev acceleration on, at the
// method's own rho (vbd's; projective dynamics has none and refuses it).
inline constexpr double kChebyshevOn = -1.0;

// Iterations or substeps per step at most (--iterations, --substeps, and
// the experiment definitions' caps): more would only spin.
inline constexpr int kMaxInnerCount = 100000;

// Empty when the option's value in `options` is in its range (`given`:
// whether the user gave it; counts left at 0 mean "the method's own"),
// otherwise the problem only, "must be ..." (a choice's name is checked
// where it is set: choice_refusal). The caller names the option its own
// way: the command line "--newton-tol: ", a definition "newton_tol: " in
// its file-and-place format.
std::string check_option_range(const OptionSpec& spec, const IntegratorOptions& options,
                               bool given);
// The problem with a choice's value: "unknown 'value' (a, b, c)" (the
// caller names the option, as for check_option_range).
std::string choice_refusal(const OptionSpec& spec, const std::string& printable_value);

}  // namespace springlab
