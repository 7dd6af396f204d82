// `loopfarm start JOB --index I`: one random start of a job, end to end, with
// its whole story (or every iteration with --trace, or one JSON object).
#pragma once

#include "subcommand.hpp"

namespace loopfarm::cli {

Subcommand add_start_command(CLI::App& parent);

}  // namespace loopfarm::cli
