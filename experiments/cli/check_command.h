// `springlab check METHOD [--plugin P] [claims] [--json]`: a method run
// against what it claims (experiments/analysis/claims.h measures each
// claim; docs/your-own-integrator.md "Checking it"). No claim given: the
// ones `springlab list` states for it. Exit 1 when any claim fails.
#pragma once

#include <optional>
#include <string>
#include <vector>

namespace CLI {
class App;
}

namespace springlab {

struct CheckCommand {
  std::string method;
  std::vector<std::string> plugins;
  std::optional<int> order;
  std::optional<double> stable_limit;
  bool a_stable = false, symplectic = false, dissipative = false, momentum = false,
       deterministic = false;
  bool json = false;
};

// Adds the subcommand `check` to `app`, its options bound to `command`.
CLI::App* add_check_command(CLI::App& app, CheckCommand& command);

// Loads the plug-ins, measures the claims, prints the report on stdout:
// 0 when every claim holds, 1 when one fails. Throws std::invalid_argument
// (one line) for an unknown method or a claim that cannot apply.
int run_check_command(const CheckCommand& command);

}  // namespace springlab
