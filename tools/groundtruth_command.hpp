// `loopfarm groundtruth`: the ground-truth set of 4R loops (known movable and
// known rigid, labelled; include/loopfarm/study/ground_truth.hpp) as CSV or JSON.
#pragma once

#include "subcommand.hpp"

namespace loopfarm::cli {

Subcommand add_groundtruth_command(CLI::App& parent);

}  // namespace loopfarm::cli
