// `loopfarm merge`: one results database of the slices of a job (merge_command.cpp).
#pragma once

#include "subcommand.hpp"

namespace loopfarm::cli {

Subcommand add_merge_command(CLI::App& parent);

}  // namespace loopfarm::cli
