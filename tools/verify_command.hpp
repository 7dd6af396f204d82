// `loopfarm verify`: verify and classify one geometry given by the same flags
// as `loopfarm energy`.
#pragma once

#include "subcommand.hpp"

namespace loopfarm::cli {

Subcommand add_verify_command(CLI::App& parent);

}  // namespace loopfarm::cli
