#pragma once

#include <optional>
#include <vector>

namespace springlab {

// What the fluid experiment's two comparisons with measurements share
// (fluid_experiment.cc: Martin and Moyce's front; fluid_gauges.cc: MARIN's
// water heights).

// Linear interpolation in (x, y), x increasing; nullopt outside [x0, xn].
std::optional<double> interpolate(const std::vector<double>& x, const std::vector<double>& y,
                                  double at);

// CPU seconds of this thread (POSIX): a run's cost whatever else the
// machine does, and whatever the runner's --jobs.
double thread_cpu_seconds();

}  // namespace springlab
