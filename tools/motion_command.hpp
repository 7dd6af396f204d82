// `loopfarm motion`: every circuit of one geometry's rigid motion, printed,
// as CSV of the input-output curves and as a plot.
#pragma once

#include "subcommand.hpp"

namespace loopfarm::cli {

Subcommand add_motion_command(CLI::App& parent);

}  // namespace loopfarm::cli
