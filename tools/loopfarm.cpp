// The loopfarm command line. Each subcommand lives in its own file and
// registers itself through add_<name>_command (see subcommand.hpp); this file
// parses the command line, runs the chosen subcommand and turns whatever goes
// wrong into one line on stderr and an exit code: 2 for bad input, 1 for
// anything else.
#include <cstdio>
#include <exception>
#include <stdexcept>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "bonds_command.hpp"
#include "cli_support.hpp"
#include "energy_command.hpp"
#include "groundtruth_command.hpp"
#include "merge_command.hpp"
#include "motion_command.hpp"
#include "report_command.hpp"
#include "run_command.hpp"
#include "start_command.hpp"
#include "subcommand.hpp"
#include "tradeoff_command.hpp"
#include "verify_command.hpp"

#ifndef LOOPFARM_VERSION
#error "LOOPFARM_VERSION is defined by the loopfarm library target"
#endif

namespace {

using loopfarm::cli::kExitFailure;
using loopfarm::cli::kExitUsage;
using loopfarm::cli::one_line;

int report(const std::string& prefix, const std::string& message, int code) {
  std::fprintf(stderr, "%s: %s\n", prefix.c_str(), one_line(message).c_str());
  return code;
}

// Runs a parsed subcommand, mapping its exceptions to messages and exit codes.
int run_subcommand(const loopfarm::cli::Subcommand& command) {
  const std::string prefix = "loopfarm " + command.app->get_name();
  try {
    return command.run();
  } catch (const loopfarm::cli::UsageError& error) {
    return report(prefix, error.what(), kExitUsage);
  } catch (const std::invalid_argument& error) {
    // The library's verdict on a geometry or an option it was handed.
    return report(prefix, error.what(), kExitUsage);
  } catch (const loopfarm::cli::EnvironmentError& error) {
    return report(prefix, error.what(), kExitFailure);
  } catch (const std::exception& error) {
    return report(prefix, std::string("unexpected error: ") + error.what(), kExitFailure);
  } catch (...) {
    return report(prefix, "unexpected error of unknown type", kExitFailure);
  }
}

int run_loopfarm(int argc, char** argv) {
  CLI::App app{"loopfarm: find movable over-constrained linkages by minimising elastic cycle energy.", "loopfarm"};
  app.set_version_flag("--version", std::string("loopfarm ") + LOOPFARM_VERSION);
  app.require_subcommand(1);
  app.footer("Run 'loopfarm SUBCOMMAND --help' for a subcommand's options.");

  // Every subcommand, in the order --help lists them.
  const std::vector<loopfarm::cli::Subcommand> commands{
      loopfarm::cli::add_energy_command(app),      loopfarm::cli::add_verify_command(app),
      loopfarm::cli::add_motion_command(app),      loopfarm::cli::add_bonds_command(app),
      loopfarm::cli::add_start_command(app),       loopfarm::cli::add_run_command(app),
      loopfarm::cli::add_merge_command(app),       loopfarm::cli::add_report_command(app),
      loopfarm::cli::add_groundtruth_command(app), loopfarm::cli::add_tradeoff_command(app),
  };

  // No option takes an empty value: "--db $OUT" with OUT unset would otherwise
  // read as --db not given (the job's own database), "--starts $N" as the
  // job's whole count. Flags take no value and are left alone.
  for (const auto& command : commands) {
    for (CLI::Option* option : command.app->get_options()) {
      if (option->get_type_size() == 0) continue;
      option->check([](const std::string& value) { return value.empty() ? std::string("empty value") : std::string(); },
                    "", "nonempty");
    }
  }

  // CLI11 would call a mistyped subcommand "missing"; name it instead.
  if (argc > 1 && argv[1][0] != '-') {
    bool known = false;
    std::string names;
    for (const auto& command : commands) {
      known = known || command.app->get_name() == argv[1];
      names += (names.empty() ? "" : ", ") + command.app->get_name();
    }
    if (!known) {
      return report("loopfarm", "unknown subcommand " + loopfarm::cli::quote_text(argv[1]) + "; available: " + names,
                    kExitUsage);
    }
  }

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& error) {
    // --help and --version arrive as "errors" with exit code 0.
    if (error.get_exit_code() == 0) return app.exit(error);
    std::string prefix = "loopfarm";
    for (const auto& command : commands) {
      if (command.app->parsed()) prefix += " " + command.app->get_name();
    }
    std::string message = error.what();
    // CLI11's words for an option given twice.
    const std::string repeated = "At Most 1 required but received ";
    if (const size_t at = message.find(repeated); at != std::string::npos) {
      message = message.substr(0, at) + "given " + message.substr(at + repeated.size()) + " times; give it once";
    }
    return report(prefix, message + " (see " + prefix + " --help)", kExitUsage);
  }

  int code = kExitFailure;
  for (const auto& command : commands) {
    if (command.app->parsed()) {
      code = run_subcommand(command);
      break;
    }
  }
  // A full disk or closed pipe on stdout must not pass for success.
  if (std::fflush(stdout) != 0 && code == 0) {
    return report("loopfarm", "cannot write to standard output", kExitFailure);
  }
  return code;
}

}  // namespace

int main(int argc, char** argv) {
  const int code = run_loopfarm(argc, argv);
  loopfarm::cli::record_exit_code(code);
  return code;
}
