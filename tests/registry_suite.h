// What the suites instantiated over the integrator registry share: the test
// parameter is a registered integrator's name.
#pragma once

#include <gtest/gtest.h>

#include <string>

#include "experiments/simulation.h"
#include "integrators/registry.h"

namespace springlab::testing {

class RegistryTest : public ::testing::TestWithParam<std::string> {
 protected:
  IntegratorInfo info() const { return make_integrator(GetParam())->info(); }
  // A run of this method; Newton to 1e-13 so tolerance does not blur a property.
  RunSettings settings(double dt, double t_end) const {
    RunSettings s;
    s.integrator = GetParam();
    s.dt = dt;
    s.t_end = t_end;
    s.options.newton_tol = 1e-13;
    return s;
  }
};

// "implicit-euler" -> "implicit_euler" (gtest names allow no '-').
inline std::string registry_test_name(const ::testing::TestParamInfo<std::string>& p) {
  std::string name = p.param;
  for (char& c : name) {
    if (c == '-') c = '_';
  }
  return name;
}

}  // namespace springlab::testing
