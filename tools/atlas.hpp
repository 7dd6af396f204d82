// The family atlas of `loopfarm report --atlas DIR` (atlas.cpp): per family of
// the candidates read from a results database, the count, the spread of the
// canonical parameters, the local dimension found against the family's known
// one, and one representative with its cycle-energy chart (PNG, gnuplot) and a
// strip of frames of its motion (SVG, drawn from the forward kinematics).
#pragma once

#include <cstdint>
#include <filesystem>
#include <limits>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "loopfarm/farm/results_database.hpp"

namespace loopfarm::cli {

inline constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// The dimension of a family (free real parameters, scale included, in the full
// 3n-parameter space) as docs/guide/families.md and docs/guide/classification.md give it;
// nothing when it is not one number (trivial, degenerate, unclassified).
std::optional<int> known_family_dimension(const std::string& family, int joints);

// The file name stem of a family's files in the atlas: "5r_goldberg".
std::string atlas_stem(const std::string& family, int joints);

// Writes DIR/atlas.md and, per family, STEM_cycle.png and STEM_motion.svg.
// `rows` are every candidate selected (in the report's order: unclassified
// first, then by energy); `zero_thresholds` each run's zero threshold by run
// id (a cycle chart marks the threshold of the run that found its candidate);
// `header` is Markdown put under the title (the database and its runs). Unclassified families come first, then by
// count. Returns the number of families. Throws EnvironmentError when gnuplot fails or a file cannot be written.
int write_atlas(const std::filesystem::path& gnuplot, const std::vector<CandidateRow>& rows,
                const std::map<std::int64_t, double>& zero_thresholds, const std::string& header,
                const std::filesystem::path& dir);

// The SVG strip of frames (exposed for the atlas only; one row of `frames`
// panels): the joint axes and links of the loop at evenly spaced samples of
// its motion. `theta` holds each frame's joint angles [rad], `input_deg` the
// input angle shown under each frame.
std::string motion_strip_svg(const CandidateRow& row, const std::vector<std::vector<double>>& theta,
                             const std::vector<double>& input_deg, const std::string& title);

}  // namespace loopfarm::cli
