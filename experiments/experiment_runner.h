// `springlab experiment FILE --out DIR [--jobs N] [--shard i/N] [--merge N]`.
#pragma once

#include <string>

namespace springlab {

struct ExperimentRunOptions {
  std::string out_dir;
  int jobs = 0;         // 0: all cores
  int shard_index = 1;  // 1-based
  int shard_count = 1;
  int merge = 0;        // > 0: merge that many shards instead of running
  bool progress = true;
};

// Returns the number of tasks run (or shards merged). Throws on bad input or
// I/O errors; tables are written whole or not at all.
std::size_t run_experiment(const std::string& definition_path, const ExperimentRunOptions& options);

}  // namespace springlab
