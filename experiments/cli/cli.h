// The `springlab` command line (docs/command-line.md "The command line"). Kept out of main() so the
// commands' pieces can be reused by later tools (experiments, bindings).
#pragma once

#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "experiments/driver/simulation.h"
#include "models/model/model.h"
#include "models/core/scene.h"

namespace springlab {

// SCENE is a scene file's path or a built-in scene's name; `-p key=value`
// applies to built-ins only. Throws SceneError with a one-line message.
Scene resolve_scene(const std::string& scene_arg, const std::vector<std::string>& parameters);

int run_cli(int argc, char** argv);

// `springlab run`'s options for a caller inside this process (the Python
// module): `options` as typed on the command line, without the leading
// dashes' meaning changed ({"--newton-tol", "1e-6"}, {"--stald", ""} for a
// flag), parsed and checked exactly as `run` checks them, against the method
// and the model too, so a bad value throws std::runtime_error with the same
// one line the command line prints after "springlab: error: ". Options the
// method does not read are named in `notes` (one sentence each, as `run`
// prints them after "springlab: note: "; on stderr when notes is nullptr).
// `integrator` is the one object the options were checked against; it is
// the one to hand to prepare_run, as the command line does (one per run).
struct CheckedRun {
  RunSettings settings;
  std::unique_ptr<Integrator> integrator;
};
CheckedRun run_settings_for(const Model& model, const std::string& integrator, double dt,
                            double t_end, int every,
                            const std::vector<std::pair<std::string, std::string>>& options,
                            std::vector<std::string>* notes = nullptr);

// simulate()'s integrator for `run` (run_settings_for's), bound to the
// model's initial state before any output is opened (prepare_integrator): a
// pairing the method refuses throws std::runtime_error with `run`'s one line
// ("--integrator xpbd: ..."; for a built-in scene named by `scene_arg`, the
// -p value that fixes it; "" for none).
std::unique_ptr<Integrator> prepare_run(const Model& model, const RunSettings& settings,
                                        const std::string& scene_arg,
                                        std::unique_ptr<Integrator> integrator);

// The statistics every integrator reports, by the names of `run --json`.
nlohmann::ordered_json stats_json(const IntegratorStats& s);
// The rule that ended a diverged run (`run --json`'s "verdict": rule,
// value, bound, and where: the particle or body, plane).
nlohmann::ordered_json verdict_json(const Verdict& v);

// Rows one output of a run may hold (docs/reliability.md "Reliability"): about 1 GB of CSV.
inline constexpr double kMaxOutputRows = 10'000'000;

}  // namespace springlab
