// `loopfarm energy`: the cycle energy of one loop, with its curve as CSV and
// plot. See docs/guide/commands.md for the options.
#pragma once

#include "subcommand.hpp"

namespace loopfarm::cli {

Subcommand add_energy_command(CLI::App& parent);

}  // namespace loopfarm::cli
