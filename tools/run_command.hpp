// `loopfarm run`: the discovery farm (run_command.cpp).
#pragma once

#include "subcommand.hpp"

namespace loopfarm::cli {

Subcommand add_run_command(CLI::App& parent);

}  // namespace loopfarm::cli
