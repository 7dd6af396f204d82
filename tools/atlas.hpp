// The family atlas of `loopfarm report --atlas DIR` (atlas.cpp): per family of
// the candidates read from a results database, the count, the spread of the
// parameters in their conventional form, the local dimension found against the
// family's known one, and one representative with its cycle-energy chart (PNG,
// gnuplot) and a strip of frames of its motion (SVG, drawn from the forward
// kinematics of its stored canonical form).
#pragma once

#include <cstdint>
#include <filesystem>
#include <limits>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "loopfarm/core/cycle.hpp"
#include "loopfarm/core/loop.hpp"
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
// "Representative: candidate 262 (first found by run 1, start 640; 1 hit),
// E_mean ..., full turn, setup asymmetric.": the sentence the Markdown atlas
// and the HTML page (escaped) both print under a family's heading.
std::string representative_sentence(const CandidateRow& row);

// What the representative's drawings (`drawings`: "The cycle-energy chart and
// the motion drawing") are drawn from, for both atlases: the stored canonical
// form, its joint 1 the input (theta1), and which joint of the conventional
// form (the parameters printed beside them) each of its joints is.
std::string chart_joints_sentence(const CandidateRow& row, const std::string& drawings);

int write_atlas(const std::filesystem::path& gnuplot, const std::vector<CandidateRow>& rows,
                const std::map<std::int64_t, double>& zero_thresholds, const std::string& header,
                const std::filesystem::path& dir);

// The candidates of one family (one joint count).
struct FamilyGroup {
  int joints = 0;
  std::string family;
  std::vector<const CandidateRow*> rows;
  long long hits = 0;
};

// The candidates grouped by family: unclassified first (possible new
// families), then the most candidates, then by name.
std::vector<FamilyGroup> group_by_family(const std::vector<CandidateRow>& rows);

// The family's representative: a full turn first (the whole motion can be
// shown), then the smallest rigid-closure residual along the verified motion,
// then the lowest energy, then the first committed.
const CandidateRow& representative(const FamilyGroup& group);

// "4 (572), 5 (7)": the local dimensions found and how many candidates each.
std::string dimension_counts(const FamilyGroup& group);
// "12": the free parameter counts of the family's candidates.
std::string free_parameter_counts(const FamilyGroup& group);

// The representative's cycle energy, recomputed from its canonical geometry
// as `loopfarm energy` computes it (assembly at theta0, then the cycle of
// kAtlasCycleSamples samples): a full turn from 0 or, for a loop whose
// verified motion does not turn fully, the verified range.
inline constexpr int kAtlasCycleSamples = 360;
struct Representation {
  CycleSummary cycle;
  double theta0 = 0.0;  // [rad]
  bool full_turn = true;
};
Representation compute_cycle(const CandidateRow& row);

// `count` poses of the cycle, evenly spaced in input angle, in input order
// (failed samples left out): a full turn at k/count of the turn, a range
// with both ends. `theta` gets each pose's joint angles [rad], `input_deg`
// its input angle.
void pick_frames(const Representation& rep, int count, std::vector<std::vector<double>>& theta,
                 std::vector<double>& input_deg);

// One joint of the loop at a pose, in the base frame: the point where link
// i-1 meets axis i (o), the foot of link i's common normal on axis i
// (p = o + d_i z) and the axis's unit direction (z).
struct JointPlacement {
  Eigen::Vector3d o, p, z;
};
// Every joint's placement at the joint angles `theta` [rad], from the forward kinematics.
std::vector<JointPlacement> joint_placements(const LoopGeometry& geometry, const std::vector<double>& theta);
// How far a drawn joint axis reaches beyond its link ends [L].
inline constexpr double kAxisHalf = 0.45;

// The SVG strip of frames (exposed for the atlas only; one row of `frames`
// panels): the joint axes and links of the loop at evenly spaced samples of
// its motion. `theta` holds each frame's joint angles [rad], `input_deg` the
// input angle shown under each frame.
std::string motion_strip_svg(const CandidateRow& row, const std::vector<std::vector<double>>& theta,
                             const std::vector<double>& input_deg, const std::string& title);

}  // namespace loopfarm::cli
