// One candidate whole (`loopfarm report DB --candidate ID`): every stored
// column of its row, its canonical key, singular values and grid cell, and
// each joint's axis (a point and a unit direction in the base frame) at a
// closed pose; as text, Markdown, CSV (a row per joint) or JSON.
#pragma once

#include <optional>
#include <string>

#include "loopfarm/farm/candidate_pose.hpp"
#include "loopfarm/farm/results_database.hpp"

namespace loopfarm::cli {

// Each prints the candidate `c` and, with `pose`, its axes at that pose;
// without one, the axes empty (null in JSON) and `missing` saying why.
void print_candidate_text(const CandidateDetails& c, const std::optional<CandidatePose>& pose,
                          const std::string& missing);
void print_candidate_markdown(const CandidateDetails& c, const std::optional<CandidatePose>& pose,
                              const std::string& missing);
void print_candidate_csv(const CandidateDetails& c, const std::optional<CandidatePose>& pose,
                         const std::string& missing);
void print_candidate_json(const CandidateDetails& c, const std::optional<CandidatePose>& pose,
                          const std::string& missing);

}  // namespace loopfarm::cli
