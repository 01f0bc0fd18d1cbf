// CLI11's parse errors as one line each (parse_errors.h). Which option is at
// fault is found by reading argv against the parser's options, as CLI11
// did; the error's type says what went wrong.
#include "experiments/cli/parse_errors.h"

#include <cctype>
#include <charconv>
#include <map>
#include <vector>

#include "models/core/registry.h"  // did_you_mean
#include "models/core/scene.h"     // printable

namespace springlab {
namespace {

// The option named by an argument ("--dt", "--dt=0.1" -> "--dt"), or "" for
// a value, a negative number or "-" (stdin).
std::string option_name(const std::string& arg) {
  if (arg.size() < 2 || arg[0] != '-' || arg == "--") return "";
  if (std::isdigit(static_cast<unsigned char>(arg[1])) || arg[1] == '.') return "";
  return arg.substr(0, arg.find('='));
}

// The option `name` of the chosen command, or else of the program.
const CLI::Option* find_option(const CLI::App& app, const CLI::App& scope, const std::string& name) {
  const CLI::Option* option = scope.get_option_no_throw(name);
  return option != nullptr ? option : app.get_option_no_throw(name);
}

// Argv read against the parser: the command chosen, and each option given
// with its values.
struct ReadArguments {
  const CLI::App* command = nullptr;  // nullptr: none chosen
  std::string unknown;                // the first option no parser has
  std::vector<std::pair<std::string, std::vector<std::string>>> options;
};

ReadArguments read_arguments(const CLI::App& app, int argc, char** argv) {
  ReadArguments read;
  for (int k = 1; k < argc; ++k) {
    const std::string arg = argv[k];
    const std::string name = option_name(arg);
    if (name.empty()) {
      if (read.command == nullptr) {
        for (const CLI::App* sub : app.get_subcommands({})) {
          if (sub->get_name() == arg) read.command = sub;
        }
      }
      continue;
    }
    const CLI::App& scope = read.command != nullptr ? *read.command : app;
    const CLI::Option* option = find_option(app, scope, name);
    if (option == nullptr) {
      if (read.unknown.empty()) read.unknown = name;
      continue;
    }
    std::vector<std::string> values;
    if (name.size() < arg.size()) {
      values.push_back(arg.substr(name.size() + 1));  // --dt=0.1
    } else if (option->get_expected_max() > 0 && k + 1 < argc) {
      values.push_back(argv[++k]);
    }
    read.options.emplace_back(name, values);
  }
  return read;
}

// Whether `text` is a whole number (for an integer option) or a number.
bool reads_as(const std::string& text, bool integer) {
  const char* first = text.data();
  const char* last = first + text.size();
  if (first != last && *first == '+') ++first;
  if (integer) {
    long long value = 0;
    const auto [end, ec] = std::from_chars(first, last, value);
    return ec == std::errc() && end == last;
  }
  double value = 0.0;
  const auto [end, ec] = std::from_chars(first, last, value);
  return ec == std::errc() && end == last;
}

std::string command_list(const CLI::App& app, const char* last_joint) {
  std::vector<std::string> names;
  for (const CLI::App* sub : app.get_subcommands({})) names.push_back(sub->get_name());
  std::string list;
  for (std::size_t i = 0; i < names.size(); ++i) {
    if (i > 0) list += i + 1 == names.size() ? last_joint : ", ";
    list += names[i];
  }
  return list;
}

}  // namespace

std::string parse_error_line(const CLI::ParseError& e, const CLI::App& app, int argc, char** argv,
                             const std::string& command) {
  const ReadArguments read = read_arguments(app, argc, argv);
  std::string help = "springlab --help";
  if (!command.empty()) help = "springlab " + command + " --help";
  if (read.command != nullptr) help = "springlab " + read.command->get_name() + " --help";
  const CLI::App& scope = read.command != nullptr ? *read.command : app;
  if (!read.unknown.empty()) {
    // The command's long options and the program's, for "did you mean".
    std::vector<std::string> names;
    for (const CLI::App* where : {&scope, &app}) {
      for (const CLI::Option* option : where->get_options()) {
        for (const std::string& name : option->get_lnames()) names.push_back("--" + name);
      }
    }
    return "unknown option " + printable(read.unknown) + did_you_mean(read.unknown, names) + " (" +
           help + " lists the options)";
  }
  if (dynamic_cast<const CLI::ArgumentMismatch*>(&e) != nullptr) {
    // An option that takes one value, given twice.
    std::map<std::string, int> count;
    for (const auto& [name, values] : read.options) {
      const CLI::Option* option = find_option(app, scope, name);
      if (++count[name] == 2 && option->get_expected_max() <= 1) {
        return option->get_name() + ": given more than once";
      }
    }
  }
  if (dynamic_cast<const CLI::ConversionError*>(&e) != nullptr) {
    // The first value that is not a number of its option's type.
    for (const auto& [name, values] : read.options) {
      const CLI::Option* option = find_option(app, scope, name);
      const std::string type = option->get_type_name();
      const bool integer = type == "INT" || type == "UINT";
      if (!integer && type != "FLOAT") continue;
      for (const std::string& value : values) {
        if (!reads_as(value, integer)) {
          return name + ": '" + printable(value) + "' is not " +
                 (integer ? "a whole number" : "a number");
        }
      }
    }
  }
  if (dynamic_cast<const CLI::ExtrasError*>(&e) != nullptr) {
    std::vector<std::string> extras = scope.remaining();
    if (extras.empty()) extras = app.remaining();
    std::string list;
    for (const std::string& x : extras) list += " " + printable(x);
    return "unexpected argument" + list + " (" + help + " lists the arguments)";
  }
  if (dynamic_cast<const CLI::RequiredError*>(&e) != nullptr && read.command == nullptr &&
      command.empty() && !app.get_subcommands({}).empty()) {
    if (argc > 1 && argv[1][0] != '-') {
      return "unknown command '" + printable(argv[1]) + "' (commands: " + command_list(app, ", ") +
             "; springlab --help)";
    }
    return "a command is required: " + command_list(app, " or ") + " (springlab --help)";
  }
  // Anything else in CLI11's words, on one line.
  std::string what = e.what();
  for (char& c : what) {
    if (c == '\n') c = ' ';
  }
  return printable(what) + " (" + help + ")";
}

}  // namespace springlab
