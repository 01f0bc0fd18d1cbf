// Running an experiment's tasks in-process, as the experiment tests do: a
// definition parsed from JSON, one task run directly (no files), its rows
// read back by column name.
#pragma once

#include <gtest/gtest.h>

#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "csv_fields.h"
#include "experiments/kinds/definition.h"
#include "experiments/kinds/experiment.h"

namespace springlab::testing {

using Record = std::map<std::string, std::string>;

// One task's rows of every table (in tables() order), each as column ->
// field (rows carry no task column); a row of the wrong width fails the test.
inline std::vector<std::vector<Record>> task_rows(const LoadedExperiment& loaded,
                                                  std::size_t task) {
  const std::vector<TableSpec> specs = loaded.experiment->tables();
  const TaskOutput out = loaded.experiment->run_task(task);
  EXPECT_EQ(out.rows.size(), specs.size());
  std::vector<std::vector<Record>> tables(specs.size());
  for (std::size_t t = 0; t < specs.size() && t < out.rows.size(); ++t) {
    for (const std::string& line : out.rows[t]) {
      const std::vector<std::string> fields = csv_fields::split_fields(line);
      EXPECT_EQ(fields.size(), specs[t].columns.size()) << "table " << t << ": " << line;
      Record r;
      for (std::size_t c = 0; c < fields.size() && c < specs[t].columns.size(); ++c) {
        r[specs[t].columns[c]] = fields[c];
      }
      tables[t].push_back(r);
    }
  }
  return tables;
}

// The definition as if read from a file named def.json.
inline LoadedExperiment parse_definition(const nlohmann::json& definition) {
  return parse_experiment(definition.dump(), "def.json");
}

// The message of the DefinitionError parse_experiment refuses the text with
// ("" when it is accepted).
inline std::string definition_error(const std::string& text) {
  try {
    parse_experiment(text, "def.json");
  } catch (const DefinitionError& e) {
    return e.what();
  } catch (const std::exception& e) {
    return std::string("not a DefinitionError: ") + e.what();
  }
  return "";
}
inline std::string definition_error(const nlohmann::json& definition) {
  return definition_error(definition.dump());
}

}  // namespace springlab::testing
