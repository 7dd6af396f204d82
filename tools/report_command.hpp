// `loopfarm report`: the zero-minimum cases of a results database (report_command.cpp).
#pragma once

#include "subcommand.hpp"

namespace loopfarm::cli {

Subcommand add_report_command(CLI::App& parent);

}  // namespace loopfarm::cli
