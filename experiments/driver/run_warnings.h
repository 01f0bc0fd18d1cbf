// A run's warnings (docs/command-line.md "Warnings"; `run --json`'s
// "warnings"): what a run that went on wants its reader to know, as data (a
// code and its numbers), printed by one function for the command line, the
// Python module and the experiment tables.
#pragma once

#include <string>
#include <vector>

#include "integrators/core/integrator.h"
#include "models/core/verdict.h"

namespace springlab {

enum class WarningCode {
  // Some steps fell back to a weaker variant of the method (Integrator::
  // fallbacks): `fallback`, `steps`.
  kFallback,
  // The energy overshot the bound and then fell back below it (a
  // Newmark-alpha method's overshoot, forgiven: experiments/driver/divergence.h):
  // `rule`, `ratio` (its peak over the bound), `t` (when), `steps` (above
  // the bound).
  kOvershoot,
};

struct RunWarning {
  WarningCode code = WarningCode::kFallback;
  Fallback fallback = Fallback::kGenericDiscreteGradient;
  VerdictRule rule = VerdictRule::kEnergy;
  long steps = 0;
  double ratio = 0.0;
  double t = 0.0;
};

// The warning as one line, e.g. "discrete-gradient: 2 steps fell back to
// Gonzalez's generic discrete gradient, which does not keep a body's
// angular momentum (...)".
std::string warning_text(const RunWarning& warning, const std::string& integrator);
// Every warning's line, in order.
std::vector<std::string> warning_texts(const std::vector<RunWarning>& warnings,
                                       const std::string& integrator);

}  // namespace springlab
