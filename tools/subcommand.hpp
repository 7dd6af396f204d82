// How a subcommand plugs into the loopfarm command line: it registers its
// options on a CLI11 sub-app and hands back the function that runs it once
// the command line has been parsed. Adding a subcommand means writing one
// add_<name>_command function and listing it in loopfarm.cpp.
#pragma once

#include <functional>

#include <CLI/CLI.hpp>

namespace loopfarm::cli {

struct Subcommand {
  CLI::App* app = nullptr;
  // Runs the parsed command and returns the exit code. May throw: UsageError
  // and std::invalid_argument mean bad input (exit 2), EnvironmentError and
  // anything else a failure (exit 1); main reports them in one line.
  std::function<int()> run;
};

}  // namespace loopfarm::cli
