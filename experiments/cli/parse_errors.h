// The command line's parse errors in springlab's words (docs/command-line.md,
// "Errors"): one line naming the option or argument at fault. Decided from
// the error's type and springlab's own reading of the arguments, never from
// the words of CLI11's message (issue 47 item 4).
#pragma once

#include <CLI/CLI.hpp>
#include <string>

namespace springlab {

// The one line (after "springlab: error: ") for a parse error of `app` on
// argv. `command`: the command's name when `app` is a command's own parser
// (Python's run), so the help it points to is `springlab COMMAND --help`.
std::string parse_error_line(const CLI::ParseError& e, const CLI::App& app, int argc, char** argv,
                             const std::string& command = "");

}  // namespace springlab
