// `springlab experiment FILE --out DIR [--jobs N] [--shard i/N] [--merge N]`.
#pragma once

#include <atomic>
#include <cstddef>
#include <string>

namespace springlab {

struct ExperimentRunOptions {
  std::string out_dir;
  int jobs = 0;         // 0: all cores
  int shard_index = 1;  // 1-based
  int shard_count = 1;
  int merge = 0;        // > 0: merge that many shards instead of running
  bool progress = true;
  // When set (e.g. by Ctrl-C), no further task starts; the tasks already
  // finished are written and the output is marked incomplete.
  const std::atomic<bool>* cancel = nullptr;
};

struct ExperimentRunSummary {
  std::size_t tasks_total = 0;  // in this shard
  std::size_t tasks_done = 0;
  bool complete() const { return tasks_done == tasks_total; }
};

// Runs (or merges) one experiment. Throws on bad input or I/O errors. Every
// table is written whole or not at all; an interrupted run writes whole
// tables of the finished tasks and says "complete": false in <name>.json.
ExperimentRunSummary run_experiment(const std::string& definition_path,
                                    const ExperimentRunOptions& options);

}  // namespace springlab
