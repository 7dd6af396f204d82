// The family atlas of `loopfarm report --atlas DIR` (atlas.cpp): per family of
// the candidates read from a results database, the count, the spread of the
// parameters in their conventional form, the local dimension found against the
// family's known one, and one representative with its cycle-energy chart (PNG,
// gnuplot) and a strip of frames of its motion (SVG, drawn from the forward
// kinematics of its stored canonical form), driven by a joint that its rigid
// motion turns (compute_cycle).
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
#include "loopfarm/core/motion.hpp"
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
// along the motion of its rigid loop, as `loopfarm verify` computes it. The
// stored full_turn and input range belong to the labelling the search
// verified the loop in, whose input need not be the canonical form's joint
// 1; so every circuit of the canonical form is traced here (verify_motion)
// and the joint driven is the first, in the canonical numbering, that turns
// fully on a moving circuit, over a full turn. When no joint turns fully:
// joint 1 over a window of its range (cycle_window) on the moving circuit
// where it travels farthest, or, where joint 1 moves on none, the joint that
// travels farthest. The geometry is relabelled (loop.hpp relabelled) so that
// the driven joint is the cycle model's joint 1, assembled at a pose on that
// circuit (motion_window: a full turn starts at 0 unless a sample would lie
// at a singular pose there) and cycled over kAtlasCycleSamples samples. A
// row whose rigid loop is not found to move (a stored row is only data) is
// cycled as before, joint 1 over a full turn from the assembly at 0.
inline constexpr int kAtlasCycleSamples = 360;
struct Representation {
  CycleSummary cycle;   // theta_in: the driven joint's angle; states in the relabelled order
  int input_joint = 0;  // the joint driven, in the canonical numbering (0-based)
  double theta0 = 0.0;  // [rad]
  bool full_turn = true;
  bool on_motion = false;  // driven along a moving circuit of the rigid loop
  // That circuit, in the canonical numbering (empty when not on_motion).
  std::optional<Circuit> circuit;
};
Representation compute_cycle(const CandidateRow& row);

// "theta3": the name of the angle the cycle drives (canonical numbering).
std::string input_name(const Representation& rep);

// What the representative's drawings (`drawings`: "The cycle-energy chart and
// the motion drawing") are drawn from, for both atlases: the stored canonical
// form, the joint `rep` drives (and why that one), and which joint of the
// conventional form (the parameters printed beside them) each of its joints
// and the driven one are.
std::string chart_joints_sentence(const CandidateRow& row, const Representation& rep, const std::string& drawings);

// `count` poses of the cycle, evenly spaced in input angle, in input order
// (failed samples left out): a full turn at k/count of the turn, a range
// with both ends. `theta` gets each pose's joint angles [rad] in the
// canonical numbering, `input_deg` its input angle (the driven joint's).
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
// its motion. `theta` holds each frame's joint angles [rad] (canonical
// numbering), `input_deg` the input angle shown under each frame, named
// `input` ("theta3").
std::string motion_strip_svg(const CandidateRow& row, const std::vector<std::vector<double>>& theta,
                             const std::vector<double>& input_deg, const std::string& input, const std::string& title);

}  // namespace loopfarm::cli
