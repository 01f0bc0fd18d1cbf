// What the suites instantiated over the integrator registry share: the test
// parameter is a registered integrator's name.
#pragma once

#include <gtest/gtest.h>

#include <map>
#include <string>
#include <vector>

#include "experiments/driver/simulation.h"
#include "integrators/registry/registry.h"

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

// A suite whose tests apply to some registry entries only (the symplectic
// methods, the 3 x 3 instances of a material, ...) is instantiated over the
// entries its condition selects from their declared info, never over a list
// of names, so an entry registered later joins every suite that applies to
// it, and no test is registered where it could only be skipped. Each such
// suite is recorded here ("Registry/Suite" -> the instance names it was
// given) when gtest instantiates it, so that tests/test_registry_coverage.cc
// can check what gtest made against the registries; a suite not recorded
// here is one that applies to every entry.
inline std::map<std::string, std::vector<std::string>>& conditional_suites() {
  static std::map<std::string, std::vector<std::string>> suites;
  return suites;
}

using IntegratorCondition = bool (*)(const IntegratorInfo&);

// The registered integrators whose IntegratorInfo meets `applies`.
inline std::vector<std::string> integrators_where(const std::string& suite,
                                                  IntegratorCondition applies) {
  std::vector<std::string> names, instances;
  for (const std::string& name : integrator_names()) {
    if (!applies(make_integrator(name)->info())) continue;
    names.push_back(name);
    instances.push_back(registry_test_name({name, 0}));
  }
  conditional_suites()[suite] = instances;
  return names;
}

}  // namespace springlab::testing

// INSTANTIATE_TEST_SUITE_P(Registry, Suite, ...) over the integrators whose
// info meets `applies` (a function or captureless lambda of an IntegratorInfo).
#define SPRINGLAB_INSTANTIATE_OVER_INTEGRATORS_WHERE(Suite, applies)                   \
  INSTANTIATE_TEST_SUITE_P(                                                             \
      Registry, Suite,                                                                  \
      ::testing::ValuesIn(::springlab::testing::integrators_where("Registry/" #Suite, applies)), \
      ::springlab::testing::registry_test_name)
