// loopfarm tradeoff: a job measured under many configurations (speed against
// accuracy, docs/quality/tradeoff.md).
#pragma once

#include "subcommand.hpp"

namespace loopfarm::cli {

Subcommand add_tradeoff_command(CLI::App& parent);

}  // namespace loopfarm::cli
