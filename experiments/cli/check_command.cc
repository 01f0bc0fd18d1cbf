#include "experiments/cli/check_command.h"

#include <CLI/CLI.hpp>
#include <iostream>
#include <stdexcept>

#include "experiments/analysis/claims.h"
#include "integrators/registry/plugins.h"
#include "integrators/registry/registry.h"

namespace springlab {

CLI::App* add_check_command(CLI::App& app, CheckCommand& c) {
  CLI::App* cmd = app.add_subcommand(
      "check", "run a method against its claims: order, stability, energy, momentum, determinism");
  cmd->add_option("METHOD", c.method, "integrator name (springlab list, or a plug-in's)")->required();
  cmd->add_option("--plugin", c.plugins, "a plug-in of your own integrators (repeatable)")
      ->allow_extra_args(false);
  cmd->add_option("--order", c.order, "global order K, observed on the oscillator");
  cmd->add_option("--stable-limit", c.stable_limit,
                  "largest stable w h on the undamped oscillator, from the stability search");
  cmd->add_flag("--a-stable", c.a_stable, "stable at every step (w h up to 1e4)");
  cmd->add_flag("--symplectic", c.symplectic, "bounded energy error without drift over 1e4 periods");
  cmd->add_flag("--dissipative", c.dissipative, "never gains energy on a conservative scene");
  cmd->add_flag("--momentum", c.momentum, "conserves linear and angular momentum (free chain, free body)");
  cmd->add_flag("--deterministic", c.deterministic, "the same inputs give bit-identical results");
  cmd->add_flag("--json", c.json, "print one JSON object on stdout");
  for (const char* flag : {"--a-stable", "--symplectic", "--dissipative", "--momentum",
                           "--deterministic", "--json"}) {
    cmd->get_option(flag)->default_str("");
  }
  return cmd;
}

int run_check_command(const CheckCommand& c) {
  std::string plugin_arguments;
  for (const std::string& plugin : c.plugins) {
    load_plugin(plugin);
    plugin_arguments += " --plugin " + plugin;
  }
  if (!is_integrator(c.method)) {
    // The registry's message: did you mean, and every name.
    make_integrator(c.method);
  }
  Claims claims;
  claims.order = c.order;
  claims.stable_limit = c.stable_limit;
  claims.a_stable = c.a_stable;
  claims.symplectic = c.symplectic;
  claims.dissipative = c.dissipative;
  claims.momentum = c.momentum;
  claims.deterministic = c.deterministic;
  if (claims.stable_limit && claims.a_stable) {
    throw std::invalid_argument("--stable-limit and --a-stable: a method has a limit or none, not both");
  }
  if (!claims.any()) claims = stated_claims(make_integrator(c.method)->info());
  const CheckSubject subject{c.method, "--integrator " + c.method + plugin_arguments,
                             "springlab check " + c.method + plugin_arguments};
  const CheckReport report = check_claims(subject, claims);
  if (c.json) {
    std::cout << check_report_json(report).dump() << std::endl;
  } else {
    std::cout << check_report_text(report) << std::flush;
  }
  return report.passed() ? 0 : 1;
}

}  // namespace springlab
