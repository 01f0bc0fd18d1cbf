#include "experiments/experiment_runner.h"

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <stdexcept>
#include <system_error>
#include <thread>

#include "experiments/experiment.h"
#include "experiments/output_files.h"

namespace springlab {
namespace {

namespace fs = std::filesystem;

std::string table_stem(const std::string& name, const TableSpec& spec) {
  return spec.suffix.empty() ? name : name + "-" + spec.suffix;
}

std::string shard_suffix(const ExperimentRunOptions& o, int index) {
  if (o.shard_count == 1 && o.merge == 0) return "";
  const int count = o.merge > 0 ? o.merge : o.shard_count;
  return ".shard-" + std::to_string(index) + "-of-" + std::to_string(count);
}

std::string header(const TableSpec& spec) {
  std::string line = "task";
  for (const std::string& c : spec.columns) line += "," + c;
  return line + "\n";
}

// One line on stderr that a terminal overwrites in place; a log gets a line
// every 10%.
class Progress {
 public:
  Progress(std::string name, std::size_t total, bool enabled)
      : name_(std::move(name)), total_(total), enabled_(enabled), tty_(::isatty(2) != 0) {}
  void done_one() {
    if (!enabled_) return;
    std::lock_guard<std::mutex> lock(mutex_);
    ++done_;
    const std::size_t decile = total_ == 0 ? 10 : done_ * 10 / total_;
    if (tty_) {
      std::fprintf(stderr, "\r[%s] %zu/%zu tasks", name_.c_str(), done_, total_);
      if (done_ == total_) std::fprintf(stderr, "\n");
    } else if (decile != last_decile_ || done_ == total_) {
      std::fprintf(stderr, "[%s] %zu/%zu tasks\n", name_.c_str(), done_, total_);
      last_decile_ = decile;
    }
    std::fflush(stderr);
  }

 private:
  std::string name_;
  std::size_t total_, done_ = 0, last_decile_ = 0;
  bool enabled_, tty_;
  std::mutex mutex_;
};

std::size_t merge_shards(const LoadedExperiment& loaded, const ExperimentRunOptions& o) {
  std::vector<std::unique_ptr<AtomicFile>> files;
  std::vector<std::string> contents;
  for (const TableSpec& spec : loaded.experiment->tables()) {
    const std::string stem = (fs::path(o.out_dir) / table_stem(loaded.name, spec)).string();
    std::vector<std::pair<long, std::string>> rows;
    for (int i = 1; i <= o.merge; ++i) {
      const std::string path = stem + shard_suffix(o, i) + ".csv";
      std::ifstream in(path);
      if (!in) {
        throw std::runtime_error(path + ": missing shard (run --shard " + std::to_string(i) + "/" +
                                 std::to_string(o.merge) + " first)");
      }
      std::string line;
      std::getline(in, line);
      if (line + "\n" != header(spec)) throw std::runtime_error(path + ": unexpected header");
      long number = 1;
      while (std::getline(in, line)) {
        ++number;
        std::size_t end = 0;
        long task = -1;
        try {
          task = std::stol(line, &end);
        } catch (const std::exception&) {
        }
        if (task < 0 || end >= line.size() || line[end] != ',') {
          throw std::runtime_error(path + ":" + std::to_string(number) + ": no task index");
        }
        rows.emplace_back(task, line);
      }
    }
    std::stable_sort(rows.begin(), rows.end(),
                     [](const auto& a, const auto& b) { return a.first < b.first; });
    std::string text = header(spec);
    for (const auto& row : rows) text += row.second + "\n";
    files.push_back(std::make_unique<AtomicFile>(stem + ".csv"));
    contents.push_back(std::move(text));
  }
  // The shards' settings, with their task counts summed.
  nlohmann::ordered_json settings;
  std::size_t total = 0, done = 0;
  for (int i = 1; i <= o.merge; ++i) {
    const std::string path = (fs::path(o.out_dir) / loaded.name).string() + shard_suffix(o, i) + ".json";
    std::ifstream in(path);
    if (!in) {
      throw std::runtime_error(path + ": missing shard (run --shard " + std::to_string(i) + "/" +
                               std::to_string(o.merge) + " first)");
    }
    nlohmann::ordered_json shard;
    try {
      in >> shard;
      total += shard.at("tasks_total").get<std::size_t>();
      done += shard.at("tasks_done").get<std::size_t>();
    } catch (const nlohmann::json::exception&) {
      throw std::runtime_error(path + ": not a shard settings file");
    }
    if (i == 1) settings = shard;
  }
  settings["complete"] = total == done;
  settings["tasks_total"] = total;
  settings["tasks_done"] = done;
  files.push_back(std::make_unique<AtomicFile>((fs::path(o.out_dir) / (loaded.name + ".json")).string()));
  contents.push_back(settings.dump(2) + "\n");
  for (std::size_t k = 0; k < files.size(); ++k) files[k]->write(contents[k]);
  for (auto& f : files) f->finish();
  for (auto& f : files) f->publish();
  return static_cast<std::size_t>(o.merge);
}

}  // namespace

ExperimentRunSummary run_experiment(const std::string& definition_path,
                                    const ExperimentRunOptions& o) {
  if (o.shard_count < 1 || o.shard_index < 1 || o.shard_index > o.shard_count) {
    throw std::invalid_argument("--shard: expected i/N with 1 <= i <= N");
  }
  const LoadedExperiment loaded = load_experiment(definition_path);
  std::error_code ec;
  fs::create_directories(o.out_dir, ec);
  if (!fs::is_directory(o.out_dir)) {
    throw std::runtime_error(o.out_dir + ": cannot create the output directory");
  }
  if (o.merge > 0) {
    const std::size_t merged = merge_shards(loaded, o);
    return {merged, merged};
  }

  const Experiment& experiment = *loaded.experiment;
  const std::vector<TableSpec> specs = experiment.tables();
  // Every output file exists (as a temporary) before any task runs.
  std::vector<std::unique_ptr<AtomicFile>> files;
  for (const TableSpec& spec : specs) {
    files.push_back(std::make_unique<AtomicFile>(
        (fs::path(o.out_dir) / table_stem(loaded.name, spec)).string() +
        shard_suffix(o, o.shard_index) + ".csv"));
    files.back()->write(header(spec));
  }
  auto settings_file = std::make_unique<AtomicFile>(
      (fs::path(o.out_dir) / loaded.name).string() + shard_suffix(o, o.shard_index) + ".json");

  std::vector<std::size_t> tasks;
  for (std::size_t t = static_cast<std::size_t>(o.shard_index - 1); t < experiment.task_count();
       t += static_cast<std::size_t>(o.shard_count)) {
    tasks.push_back(t);
  }
  std::vector<TaskOutput> outputs(tasks.size());
  std::vector<std::exception_ptr> errors(tasks.size());
  std::vector<char> done(tasks.size(), 0);
  Progress progress(loaded.name, tasks.size(), o.progress);
  std::atomic<std::size_t> next{0};
  auto cancelled = [&] { return o.cancel != nullptr && o.cancel->load(); };
  auto worker = [&] {
    for (std::size_t k = next++; k < tasks.size() && !cancelled(); k = next++) {
      try {
        outputs[k] = experiment.run_task(tasks[k]);
        done[k] = 1;
      } catch (...) {
        errors[k] = std::current_exception();
      }
      progress.done_one();
    }
  };
  const unsigned cores = std::max(1u, std::thread::hardware_concurrency());
  const std::size_t jobs =
      std::min<std::size_t>(o.jobs > 0 ? static_cast<std::size_t>(o.jobs) : cores, tasks.size());
  std::vector<std::thread> threads;
  for (std::size_t j = 1; j < jobs; ++j) {
    // A huge --jobs runs into the system's thread limit: run on the threads
    // there are (each takes tasks until none is left) instead of failing with
    // threads still running.
    try {
      threads.emplace_back(worker);
    } catch (const std::system_error&) {
      break;
    }
  }
  worker();
  for (std::thread& t : threads) t.join();
  for (const std::exception_ptr& e : errors) {
    if (e) std::rethrow_exception(e);
  }

  ExperimentRunSummary summary;
  summary.tasks_total = tasks.size();
  for (std::size_t k = 0; k < tasks.size(); ++k) {
    if (!done[k]) continue;
    ++summary.tasks_done;
    const std::string prefix = std::to_string(tasks[k]) + ",";
    for (std::size_t table = 0; table < outputs[k].rows.size(); ++table) {
      std::string text;
      for (const std::string& row : outputs[k].rows[table]) text += prefix + row + "\n";
      files.at(table)->write(text);
    }
  }
  nlohmann::ordered_json settings;
  settings["name"] = loaded.name;
  settings["experiment"] = loaded.definition.at("experiment");
  settings["title"] = loaded.definition.value("title", loaded.name);
  settings["description"] = loaded.definition.value("description", "");
  // The tables this run wrote and their columns, so a reader (the report)
  // takes the schema from here instead of keeping its own copy.
  nlohmann::ordered_json tables = nlohmann::ordered_json::array();
  for (const TableSpec& spec : specs) {
    std::vector<std::string> columns = {"task"};
    columns.insert(columns.end(), spec.columns.begin(), spec.columns.end());
    tables.push_back({{"file", table_stem(loaded.name, spec) + ".csv"}, {"suffix", spec.suffix},
                      {"columns", columns}});
  }
  settings["tables"] = tables;
  const nlohmann::json extra = experiment.settings();  // named: items() must not outlive it
  for (const auto& [key, value] : extra.items()) settings[key] = value;
  settings["complete"] = summary.complete();
  settings["tasks_total"] = summary.tasks_total;
  settings["tasks_done"] = summary.tasks_done;
  settings["definition"] = loaded.definition;
  settings_file->write(settings.dump(2) + "\n");

  for (auto& f : files) f->finish();
  settings_file->finish();
  for (auto& f : files) f->publish();
  settings_file->publish();
  return summary;
}

}  // namespace springlab
