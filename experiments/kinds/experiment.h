// A course experiment: a set of independent tasks (runs), each producing
// rows of one or more tidy CSV tables. The runner (experiment_runner.h)
// executes the tasks in parallel, in shards, and writes the tables in task
// order, so the output does not depend on the number of threads or shards.
//
// Adding an experiment kind: one file implementing Experiment plus one line
// in experiment_registry.cc.
#pragma once

#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "experiments/kinds/definition.h"

namespace springlab {

struct TableSpec {
  std::string suffix;                // "" for <name>.csv, "runs" for <name>-runs.csv, ...
  std::vector<std::string> columns;  // after the leading "task" column
};

// Rows of each table (in tables() order), each row already CSV text.
struct TaskOutput {
  std::vector<std::vector<std::string>> rows;
};

// Builds CSV rows field by field with the project's number format.
class Row {
 public:
  Row& add(const std::string& text);
  Row& add(const char* text) { return add(std::string(text)); }
  Row& add(double value);
  Row& add(long value);
  Row& add(int value) { return add(static_cast<long>(value)); }
  Row& add_empty();
  // The value, or an empty field when there is none.
  Row& add(const std::optional<double>& value) { return value ? add(*value) : add_empty(); }
  // Appends fields that are already CSV text (a shared prefix of several rows).
  Row& raw(const std::string& csv_fields);
  const std::string& str() const { return text_; }

 private:
  // A comma before every field but the first (which may be empty: an
  // unnamed scene).
  void separate() {
    if (started_) text_ += ',';
    started_ = true;
  }
  std::string text_;
  bool started_ = false;
};

class Experiment {
 public:
  virtual ~Experiment() = default;
  virtual std::vector<TableSpec> tables() const = 0;
  virtual std::size_t task_count() const = 0;
  // Runs one task; must be safe to call from several threads at once.
  virtual TaskOutput run_task(std::size_t index) const = 0;
  // What the report shows as "settings used": scenes, integrators, extras.
  virtual nlohmann::json settings() const = 0;
};

// A definition file is at most this large; its name at most this long.
inline constexpr std::size_t kMaxDefinitionBytes = std::size_t{16} << 20;  // 16 MiB
inline constexpr std::size_t kMaxExperimentNameLength = 100;

// Reads and validates a definition file completely (throws DefinitionError
// or SceneError with a one-line message) before any task runs.
struct LoadedExperiment {
  std::string name;
  std::unique_ptr<Experiment> experiment;
  nlohmann::json definition;
};
LoadedExperiment load_experiment(const std::string& path);
LoadedExperiment parse_experiment(const std::string& json_text, const std::string& source);

// The registry of experiment kinds.
using ExperimentFactory = std::unique_ptr<Experiment> (*)(const DefinitionObject&);
struct ExperimentKind {
  const char* name;
  ExperimentFactory make;
};
std::vector<const ExperimentKind*> experiment_kinds();

}  // namespace springlab
