#include "candidate_detail.hpp"

#include <algorithm>
#include <cstdio>
#include <set>
#include <vector>

#include <nlohmann/json.hpp>

#include "candidate_display.hpp"
#include "candidate_list.hpp"
#include "cli_support.hpp"

namespace loopfarm::cli {
namespace {

constexpr double kDegreesPerRadian = 180.0 / 3.14159265358979323846;

std::string g(double v, int digits = 3) { return format_significant(v, digits); }

// The stored singular_values text ("[2,0.5]") as a JSON array when it is one
// list of numbers (or nulls), else as the string it is.
nlohmann::ordered_json singular_values_json(const std::string& stored) {
  const nlohmann::ordered_json parsed = nlohmann::ordered_json::parse(stored, nullptr, false);
  if (parsed.is_array() && std::all_of(parsed.begin(), parsed.end(), [](const nlohmann::ordered_json& element) {
        return element.is_number() || element.is_null();
      })) {
    return parsed;
  }
  return stored;
}

std::vector<Field> detail_fields(const CandidateDetails& c) {
  std::vector<Field> f = candidate_fields(c.row, stored_joints(c.row));
  f.push_back({"canonical_key", csv_text(c.canonical_key), c.canonical_key, c.canonical_key});
  f.push_back(
      {"singular_values", csv_text(c.singular_values), singular_values_json(c.singular_values), c.singular_values});
  f.push_back({"grid_cell", csv_text(c.grid_cell), c.grid_cell, c.grid_cell});
  return f;
}

// The pose's fields (without the axes), each present and null without a pose.
std::vector<Field> pose_fields(const std::optional<CandidatePose>& pose, const std::string& missing) {
  Fields f;
  if (pose) {
    f.integer("input_joint", 1);
    f.number("input_deg", pose->input_deg, kAngleRoundOffDeg);
    f.flag("input_full_turn", pose->full_turn);
    f.number("input_range_lo_deg", pose->range_lo_deg, kAngleRoundOffDeg);
    f.number("input_range_hi_deg", pose->range_hi_deg, kAngleRoundOffDeg);
    f.number("closure_residual", pose->closure_residual, 0.0, 2);
    f.text("pose_note", "");
  } else {
    for (const char* name : {"input_joint", "input_deg", "input_full_turn", "input_range_lo_deg", "input_range_hi_deg",
                             "closure_residual"}) {
      f.raw({name, "", nullptr, "-"});
    }
    f.text("pose_note", missing);
  }
  return std::move(f.list());
}

// Per joint: theta_deg, then the axis's point and direction.
std::vector<Field> axis_fields(const std::optional<CandidatePose>& pose, int joint, double length) {
  Fields f;
  f.integer("joint", joint + 1);
  if (!pose) {
    for (const char* name :
         {"theta_deg", "point_x", "point_y", "point_z", "direction_x", "direction_y", "direction_z"}) {
      f.raw({name, "", nullptr, "-"});
    }
    return std::move(f.list());
  }
  const Axis& axis = pose->axes[static_cast<size_t>(joint)];
  f.number("theta_deg", pose->theta[joint] * kDegreesPerRadian, kAngleRoundOffDeg);
  const char* xyz = "xyz";
  for (int i = 0; i < 3; ++i) f.number(std::string("point_") + xyz[i], axis.point[i], length);
  for (int i = 0; i < 3; ++i) f.number(std::string("direction_") + xyz[i], axis.direction[i], kRoundOff);
  return std::move(f.list());
}

}  // namespace

void print_candidate_text(const CandidateDetails& c, const std::optional<CandidatePose>& pose,
                          const std::string& missing) {
  const CandidateRow& r = c.row;
  std::printf("candidate %lld\n", r.id);
  const std::vector<Field> f = detail_fields(c);
  size_t width = 0;
  for (const Field& x : f) width = std::max(width, x.name.size());
  // The geometry columns follow as a table, one row per joint.
  std::set<std::string> geometry;
  for (const Field& x : candidate_fields(CandidateRow{}, stored_joints(r))) geometry.insert(x.name);
  for (const Field& x : candidate_fields(CandidateRow{}, 0)) geometry.erase(x.name);
  for (const Field& x : f) {
    if (!geometry.count(x.name)) std::printf("  %-*s %s\n", static_cast<int>(width), x.name.c_str(), x.text.c_str());
  }
  if (pose) {
    std::printf("pose: joint 1 at %s deg (joint 1 %s), closure residual %s\n",
                shown(pose->input_deg, kAngleRoundOffDeg, 6).c_str(),
                pose->full_turn ? "turns fully"
                                : ("rocks in [" + shown(pose->range_lo_deg, kAngleRoundOffDeg, 4) + ", " +
                                   shown(pose->range_hi_deg, kAngleRoundOffDeg, 4) + "] deg")
                                      .c_str(),
                g(pose->closure_residual, 2).c_str());
  } else {
    std::printf("pose: none (%s)\n", missing.c_str());
  }
  std::printf(
      "joints: canonical geometry (L = 1, twists in deg), and each joint's axis at the pose in the base frame\n");
  std::vector<TextColumn> columns = {{"joint", {}},
                                     {"a", {}},
                                     {"alpha_deg", {}},
                                     {"d", {}},
                                     {"theta_deg", {}},
                                     {"point (x, y, z)", {}},
                                     {"direction (x, y, z)", {}}};
  const double length = kRoundOff * scale_of(r);
  for (int j = 0; j < stored_joints(r); ++j) {
    const size_t i = static_cast<size_t>(j);
    columns[0].cells.push_back(std::to_string(j + 1));
    columns[1].cells.push_back(shown(r.a[i], length, 6));
    columns[2].cells.push_back(shown(r.alpha_deg[i], kAngleRoundOffDeg, 6));
    columns[3].cells.push_back(shown(r.d[i], length, 6));
    const std::vector<Field> a = axis_fields(pose, j, length);
    columns[4].cells.push_back(a[1].text);
    columns[5].cells.push_back(a[2].text + ", " + a[3].text + ", " + a[4].text);
    columns[6].cells.push_back(a[5].text + ", " + a[6].text + ", " + a[7].text);
  }
  print_columns(columns, 0);
}

void print_candidate_markdown(const CandidateDetails& c, const std::optional<CandidatePose>& pose,
                              const std::string& missing) {
  const CandidateRow& r = c.row;
  std::printf("## Candidate %lld\n\n| column | value |\n|---|---|\n", r.id);
  for (const Field& x : detail_fields(c)) std::printf("| %s | %s |\n", x.name.c_str(), x.text.c_str());
  std::printf("\n");
  for (const Field& x : pose_fields(pose, missing)) {
    if (x.name != "pose_note" || !x.text.empty()) std::printf("- %s: %s\n", x.name.c_str(), x.text.c_str());
  }
  std::printf("\n| joint | theta [deg] | point x | point y | point z | direction x | direction y | direction z |\n");
  std::printf("|---|---|---|---|---|---|---|---|\n");
  const double length = kRoundOff * scale_of(r);
  for (int j = 0; j < stored_joints(r); ++j) {
    const std::vector<Field> a = axis_fields(pose, j, length);
    std::printf("|");
    for (const Field& x : a) std::printf(" %s |", x.text.c_str());
    std::printf("\n");
  }
}

// One row per joint: the candidate's columns repeated, then the pose's and
// that joint's axis.
void print_candidate_csv(const CandidateDetails& c, const std::optional<CandidatePose>& pose,
                         const std::string& missing) {
  const std::vector<Field> common = detail_fields(c);
  const std::vector<Field> at = pose_fields(pose, missing);
  for (int j = 0; j < stored_joints(c.row); ++j) {
    std::vector<Field> row = common;
    row.insert(row.end(), at.begin(), at.end());
    const std::vector<Field> a = axis_fields(pose, j, 0.0);
    row.insert(row.end(), a.begin(), a.end());
    if (j == 0) {
      for (size_t i = 0; i < row.size(); ++i) std::printf("%s%s", i ? "," : "", row[i].name.c_str());
      std::printf("\n");
    }
    for (size_t i = 0; i < row.size(); ++i) std::printf("%s%s", i ? "," : "", row[i].csv.c_str());
    std::printf("\n");
  }
}

void print_candidate_json(const CandidateDetails& c, const std::optional<CandidatePose>& pose,
                          const std::string& missing) {
  nlohmann::ordered_json out = json_object(detail_fields(c));
  out["pose"] = json_object(pose_fields(pose, missing));
  nlohmann::ordered_json axes = nlohmann::ordered_json::array();
  for (int j = 0; j < stored_joints(c.row); ++j) {
    const std::vector<Field> a = axis_fields(pose, j, 0.0);
    nlohmann::ordered_json axis;
    axis["joint"] = a[0].json;
    axis["theta_deg"] = a[1].json;
    // Without a pose the axis is null, not a triple of nulls.
    axis["point"] = pose ? nlohmann::ordered_json{a[2].json, a[3].json, a[4].json} : nlohmann::ordered_json(nullptr);
    axis["direction"] =
        pose ? nlohmann::ordered_json{a[5].json, a[6].json, a[7].json} : nlohmann::ordered_json(nullptr);
    axes.push_back(axis);
  }
  out["axes"] = axes;
  std::printf("%s\n", out.dump().c_str());
}

}  // namespace loopfarm::cli
