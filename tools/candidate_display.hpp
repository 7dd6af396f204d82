// How a stored candidate is shown to people, shared by the report's text
// outputs (the table, Markdown, --candidate, --summary), the Markdown atlas
// and the HTML atlas: round-off of a zero printed as 0, counts grouped by
// thousands, the geometry in its conventional form, and plain-text tables.
// csv, json and the database keep the stored values.
#pragma once

#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

#include "loopfarm/farm/results_database.hpp"

namespace loopfarm::cli {

// A stored value this small beside its scale is round-off of a zero (an
// offset of -4.4e-16 at length scale 1) and prints as 0. Lengths and
// coordinates: |x| < kRoundOff * L (the loop's length scale); angles and
// unit-vector components: |x| < kRoundOff in radians or units.
inline constexpr double kRoundOff = 1e-9;
// kRoundOff radians in degrees: the round-off of an angle stored in degrees.
inline constexpr double kAngleRoundOffDeg = kRoundOff * (180.0 / 3.14159265358979323846);

// A value for people to read: `digits` significant digits, and 0 for
// round-off (|v| < threshold), never "-0".
std::string shown(double v, double threshold, int digits);
// The values so shown, joined by `separator`: "1,0,2.5".
std::string shown_list(const std::vector<double>& values, double threshold, int digits,
                       std::string_view separator = ",");

// 41100 as "41,100".
std::string grouped(long long n);
// "1 hit", "2 hits".
std::string count_of(long long count, const std::string& noun);

// A stored local dimension: "3", or "unknown" for a negative one (the
// deformation Jacobian had an entry that is not finite, LocalDimension::unknown).
std::string dimension_text(int local_dimension);
// "3/12", or "?/12" when the dimension is unknown: the tables' dim column.
std::string dimension_of(int local_dimension, int free_parameters);

// The stored geometry's length scale (core's length_scale: 1 for the
// canonical geometry); 1 when it is not a positive number (a damaged row).
double scale_of(const CandidateRow& r);

// The joints whose geometry the row holds: `joints` as stored, within what
// was read (a damaged row may claim more than kMaxJoints, or fewer than 0).
int stored_joints(const CandidateRow& r);

// The row with its geometry in the conventional form (positive twists where
// the loop's representations allow, canonical.hpp conventional_form), at the
// stored length scale, for what people read. The stored canonical values stay
// in csv, json and the database. A row whose geometry is not a loop (damage)
// is returned as stored.
CandidateRow conventional(const CandidateRow& r);

// Where each joint of the stored geometry lies in its conventional form:
// stored joint i (from 0) is joint `joint[i]` there, its angle measured the
// other way (negated) when `negated[i]`, since a reversal of the loop or a
// flipped axis negates a joint angle (canonical.hpp canonical_angles). Empty
// for a row whose geometry is not a loop.
struct ConventionalJoints {
  std::vector<int> joint;
  std::vector<bool> negated;
};
ConventionalJoints conventional_joints(const CandidateRow& r);

// A text table: columns padded to their widest cell, one space apart. The
// last column is cut to fit `width` (0: never cut) and ends in "..." then.
struct TextColumn {
  std::string header;
  std::vector<std::string> cells;
};
void print_columns(const std::vector<TextColumn>& columns, size_t width);

}  // namespace loopfarm::cli
