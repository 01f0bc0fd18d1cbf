#include "experiments/kinds/experiment_runner.h"

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <sstream>
#include <stdexcept>
#include <string_view>
#include <system_error>
#include <thread>

#include "experiments/kinds/experiment.h"
#include "experiments/kinds/integrator_facts.h"
#include "experiments/io/output_files.h"
#include "experiments/driver/simulation.h"
#include "integrators/registry/registry.h"

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

// FNV-1a, 64 bits, as 16 hex digits: tells apart what two shards were run
// from (not a cryptographic digest: it catches mistakes, not forgeries).
std::string digest(std::string_view text) {
  std::uint64_t h = 14695981039346656037ull;
  for (const char c : text) {
    h ^= static_cast<unsigned char>(c);
    h *= 1099511628211ull;
  }
  char hex[17];
  std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(h));
  return hex;
}

// What a run is made from: the definition and everything resolved from it
// (integrators, scenes as scene files, settings). Shards of one sweep share it.
std::string definition_digest(const LoadedExperiment& loaded) {
  const nlohmann::json made_from = {{"definition", loaded.definition},
                                    {"settings", loaded.experiment->settings()}};
  return digest(made_from.dump());
}

// The tasks of shard i of N: i-1, i-1+N, ...
std::size_t shard_tasks(std::size_t total, int index, int count) {
  const auto first = static_cast<std::size_t>(index - 1);
  return first >= total ? 0 : (total - first - 1) / static_cast<std::size_t>(count) + 1;
}

std::string read_file(const std::string& path, bool& ok) {
  std::ifstream in(path, std::ios::binary);
  ok = static_cast<bool>(in);
  std::ostringstream text;
  if (ok) text << in.rdbuf();
  return text.str();
}

// Joins shards 1..N of every table, after checking that each shard was run
// from this definition, as shard i of N, to completion, and that its tables
// are the ones it wrote: anything else is refused, naming the shard.
std::size_t merge_shards(const LoadedExperiment& loaded, const ExperimentRunOptions& o) {
  const int n = o.merge;
  const std::string expected_digest = definition_digest(loaded);
  const std::size_t task_total = loaded.experiment->task_count();
  const std::vector<TableSpec> specs = loaded.experiment->tables();
  auto rerun = [&](int i) {
    return "run --shard " + std::to_string(i) + "/" + std::to_string(n) + " again";
  };

  // The shards' settings files first: they say what each shard is.
  std::vector<nlohmann::ordered_json> shards;
  for (int i = 1; i <= n; ++i) {
    const std::string path = (fs::path(o.out_dir) / loaded.name).string() + shard_suffix(o, i) + ".json";
    bool found = false;
    const std::string text = read_file(path, found);
    if (!found) {
      throw std::runtime_error(path + ": missing shard (run --shard " + std::to_string(i) + "/" +
                               std::to_string(n) + " first)");
    }
    nlohmann::ordered_json shard;
    int index = 0, count = 0;
    std::string made_from;
    std::size_t total = 0, done = 0;
    try {
      shard = nlohmann::ordered_json::parse(text);
      const auto& s = shard.at("shard");
      index = s.at("index").get<int>();
      count = s.at("count").get<int>();
      made_from = shard.at("definition_digest").get<std::string>();
      total = shard.at("tasks_total").get<std::size_t>();
      done = shard.at("tasks_done").get<std::size_t>();
      if (!s.at("tables").is_object()) throw std::runtime_error("tables");
    } catch (const std::exception&) {
      throw std::runtime_error(path + ": not a shard's settings file (" + rerun(i) + ")");
    }
    if (index != i || count != n) {
      throw std::runtime_error(path + ": holds shard " + std::to_string(index) + "/" +
                               std::to_string(count) + ", not " + std::to_string(i) + "/" +
                               std::to_string(n) + " (a copy or another split?): " + rerun(i));
    }
    if (made_from != expected_digest) {
      throw std::runtime_error(path + ": made from a different definition (digest " + made_from +
                               ", this one gives " + expected_digest + "): " + rerun(i) +
                               " with this definition");
    }
    if (total != shard_tasks(task_total, i, n) || done != total) {
      throw std::runtime_error(path + ": incomplete (" + std::to_string(done) + " of " +
                               std::to_string(shard_tasks(task_total, i, n)) + " tasks): " + rerun(i));
    }
    shards.push_back(std::move(shard));
  }

  std::vector<std::unique_ptr<OutputFile>> files;
  std::vector<std::string> contents;
  for (const TableSpec& spec : specs) {
    const std::string stem = (fs::path(o.out_dir) / table_stem(loaded.name, spec)).string();
    std::vector<std::pair<long, std::string>> rows;
    for (int i = 1; i <= n; ++i) {
      const std::string path = stem + shard_suffix(o, i) + ".csv";
      const std::string file = fs::path(path).filename().string();
      bool found = false;
      const std::string text = read_file(path, found);
      if (!found) {
        throw std::runtime_error(path + ": missing shard (run --shard " + std::to_string(i) + "/" +
                                 std::to_string(n) + " first)");
      }
      const auto& recorded = shards[static_cast<std::size_t>(i - 1)]["shard"]["tables"];
      if (!recorded.contains(file) || recorded[file].value("digest", "") != digest(text)) {
        throw std::runtime_error(path + ": not the table its shard wrote (its digest differs from "
                                 "the one in the shard's settings file): " + rerun(i));
      }
      std::istringstream in(text);
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
        if (static_cast<std::size_t>(task) >= task_total || task % n != i - 1) {
          throw std::runtime_error(path + ":" + std::to_string(number) + ": task " +
                                   std::to_string(task) + " is not one of shard " +
                                   std::to_string(i) + "/" + std::to_string(n) + "'s: " + rerun(i));
        }
        rows.emplace_back(task, line);
      }
    }
    std::stable_sort(rows.begin(), rows.end(),
                     [](const auto& a, const auto& b) { return a.first < b.first; });
    std::string text = header(spec);
    for (const auto& row : rows) text += row.second + "\n";
    files.push_back(std::make_unique<OutputFile>(stem + ".csv"));
    contents.push_back(std::move(text));
  }
  // Shard 1's settings, for the whole sweep.
  nlohmann::ordered_json settings = shards.front();
  settings.erase("shard");
  settings["complete"] = true;
  settings["tasks_total"] = task_total;
  settings["tasks_done"] = task_total;
  files.push_back(std::make_unique<OutputFile>((fs::path(o.out_dir) / (loaded.name + ".json")).string()));
  contents.push_back(settings.dump(2) + "\n");
  for (std::size_t k = 0; k < files.size(); ++k) files[k]->write(contents[k]);
  for (auto& f : files) f->finish();
  for (auto& f : files) f->publish();
  return task_total;
}

}  // namespace

ExperimentRunSummary run_experiment(const std::string& definition_path,
                                    const ExperimentRunOptions& o) {
  if (o.shard_count < 1 || o.shard_index < 1 || o.shard_index > o.shard_count) {
    throw std::invalid_argument("--shard: expected i/N with 1 <= i <= N");
  }
  if (o.merge > 0 && o.shard_count > 1) {
    throw std::invalid_argument("--merge and --shard: merge the shards in a run of its own");
  }
  const LoadedExperiment loaded = load_experiment(definition_path);
  std::error_code ec;
  fs::create_directories(o.out_dir, ec);
  if (!fs::is_directory(o.out_dir, ec)) {
    throw std::runtime_error(printable(o.out_dir) + ": cannot create the output directory" +
                             (ec ? " (" + ec.message() + ")" : std::string()));
  }
  if (o.merge > 0) {
    const std::size_t merged = merge_shards(loaded, o);
    return {merged, merged};
  }

  const Experiment& experiment = *loaded.experiment;
  const std::vector<TableSpec> specs = experiment.tables();
  // Every output file exists (as a temporary) before any task runs.
  std::vector<std::unique_ptr<OutputFile>> files;
  for (const TableSpec& spec : specs) {
    files.push_back(std::make_unique<OutputFile>(
        (fs::path(o.out_dir) / table_stem(loaded.name, spec)).string() +
        shard_suffix(o, o.shard_index) + ".csv"));
  }
  auto settings_file = std::make_unique<OutputFile>(
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
    // A stop request also reaches the runs inside a task, at their next step.
    const StopScope scope(o.cancel);
    for (std::size_t k = next++; k < tasks.size() && !cancelled(); k = next++) {
      try {
        outputs[k] = experiment.run_task(tasks[k]);
        done[k] = 1;
      } catch (const StopRequested&) {
        break;  // not done: the summary says incomplete
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
  // Each table's whole text (a shard records its digest for the merge).
  std::vector<std::string> table_text(specs.size());
  std::vector<std::size_t> table_rows(specs.size(), 0);
  for (std::size_t t = 0; t < specs.size(); ++t) table_text[t] = header(specs[t]);
  for (std::size_t k = 0; k < tasks.size(); ++k) {
    if (!done[k]) continue;
    ++summary.tasks_done;
    const std::string prefix = std::to_string(tasks[k]) + ",";
    for (std::size_t table = 0; table < outputs[k].rows.size(); ++table) {
      for (const std::string& row : outputs[k].rows[table]) {
        table_text.at(table) += prefix + row + "\n";
        ++table_rows[table];
      }
    }
    outputs[k] = {};  // the text holds it now
  }
  for (std::size_t t = 0; t < specs.size(); ++t) files[t]->write(table_text[t]);
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
  // The facts of the methods the definition brought (plug-ins, Python
  // classes), which `springlab list --json` does not know: the report
  // groups them by family beside the built-ins.
  const std::string definition_text = loaded.definition.dump();
  nlohmann::ordered_json own = nlohmann::ordered_json::array();
  for (const std::string& name : integrator_names()) {
    if (is_builtin_integrator(name) ||
        definition_text.find("\"" + name + "\"") == std::string::npos) {
      continue;
    }
    own.push_back(integrator_facts_json(name, make_integrator(name)->info()));
  }
  if (!own.empty()) settings["own_integrators"] = own;
  settings["definition"] = loaded.definition;
  settings["definition_digest"] = definition_digest(loaded);
  if (o.shard_count > 1) {
    // What a merge checks: which shard this is and the tables it wrote.
    nlohmann::ordered_json tables = nlohmann::ordered_json::object();
    for (std::size_t t = 0; t < specs.size(); ++t) {
      tables[fs::path(files[t]->path()).filename().string()] = {{"digest", digest(table_text[t])},
                                                                 {"rows", table_rows[t]}};
    }
    settings["shard"] = {{"index", o.shard_index}, {"count", o.shard_count}, {"tables", tables}};
  }
  settings_file->write(settings.dump(2) + "\n");

  for (auto& f : files) f->finish();
  settings_file->finish();
  for (auto& f : files) f->publish();
  settings_file->publish();
  return summary;
}

}  // namespace springlab
