#include "experiments/kinds/fluid_measures.h"

#include <algorithm>
#include <cstddef>
#include <ctime>

namespace springlab {

std::optional<double> interpolate(const std::vector<double>& x, const std::vector<double>& y,
                                  double at) {
  if (x.empty() || at < x.front() || at > x.back()) return std::nullopt;
  const auto upper = std::lower_bound(x.begin(), x.end(), at);
  const std::size_t k = static_cast<std::size_t>(upper - x.begin());
  if (k == 0) return y.front();
  const double f = (at - x[k - 1]) / (x[k] - x[k - 1]);
  return y[k - 1] + f * (y[k] - y[k - 1]);
}

double thread_cpu_seconds() {
  timespec now{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &now);
  return static_cast<double>(now.tv_sec) + 1e-9 * static_cast<double>(now.tv_nsec);
}

}  // namespace springlab
