// loopfarm report DB: the zero-minimum cases of a results database, sorted by
// energy from zero upwards (the paper's future-work plan), with family, key
// parameters in degrees and residuals; a summary with counts and the
// histogram of all minima; PNG charts. Read-only: it works while a run is
// writing (WAL) and never changes the file. A damaged file is refused (exit
// 2), not listed from whatever its pages happen to hold.
#include "report_command.hpp"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "atlas.hpp"
#include "cli_support.hpp"
#include "html_atlas.hpp"
#include "loopfarm/core/assembly.hpp"
#include "loopfarm/core/cycle.hpp"
#include "loopfarm/farm/candidate_pose.hpp"
#include "loopfarm/farm/results_database.hpp"
#include "loopfarm/search/canonical.hpp"
#include "loopfarm/search/classify.hpp"
#include "output_format.hpp"
#include "plot.hpp"

namespace loopfarm::cli {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDegreesPerRadian = 180.0 / kPi;

// The text table's width without --wide, and the most rows it lists without --limit.
constexpr size_t kTableColumns = 120;
constexpr long long kTableDefaultLimit = 50;
// --candidate's pose: joint 1 at 90 deg unless --input-deg says otherwise,
// away from the folded poses (every link on one line) a Bennett loop passes
// at 0 and 180 deg, which draw as a collapsed linkage.
constexpr double kDefaultInputDeg = 90.0;

// Text output only: a stored value this small beside its scale is round-off
// of a zero (an offset of -4.4e-16 at length scale 1) and prints as 0.
// Lengths and coordinates: |x| < kRoundOff * L (the loop's length scale);
// angles and unit-vector components: |x| < kRoundOff in radians or units.
// csv, json and every file keep the stored value.
constexpr double kRoundOff = 1e-9;

// "bennett, planar, ..., bennett_dyads": every family, for --family's help
// and its error message.
std::string family_names() {
  std::string names;
  for (Family f : kAllFamilies) names += (names.empty() ? "" : ", ") + std::string(to_string(f));
  return names;
}

struct ReportArguments {
  std::string database;
  std::string family;
  std::string max_energy;
  std::string limit;  // empty: not given (the table's default; every row otherwise)
  FormatChoice format;
  std::string run;
  std::string candidate;
  std::string input_deg;
  std::string plot;
  std::string atlas;
  std::string html;
  bool summary = false;
  bool wide = false;
};

// A database error while reading DB: damage the open-time check could not
// see (or that appeared since) is bad input, exit 2, like a file refused at
// open; anything else (out of memory, I/O) is a failure.
[[noreturn]] void rethrow_read_error(const DatabaseError& error) {
  if (error.cause() == DatabaseError::Cause::refused) throw UsageError("DB", error.what());
  throw EnvironmentError(error.what());
}

std::optional<std::int64_t> run_filter(const ReportArguments& args) {
  if (args.run.empty()) return std::nullopt;
  return parse_integer(args.run, "--run");
}

std::string g(double v, int digits = 3) { return format_significant(v, digits); }

// A value for people to read: `digits` significant digits, and 0 for
// round-off (|v| < threshold), never "-0".
std::string shown(double v, double threshold, int digits) {
  if (std::isfinite(v) && std::abs(v) < threshold) v = 0.0;
  return format_significant(v == 0.0 ? 0.0 : v, digits);
}

std::string shown_list(const std::vector<double>& values, double threshold, int digits) {
  std::string out;
  for (double v : values) out += (out.empty() ? "" : ",") + shown(v, threshold, digits);
  return out;
}

// 41100 as "41,100".
std::string grouped(long long n) {
  std::string digits = std::to_string(n < 0 ? -n : n);
  for (int at = static_cast<int>(digits.size()) - 3; at > 0; at -= 3) digits.insert(static_cast<size_t>(at), ",");
  return (n < 0 ? "-" : "") + digits;
}

// The stored geometry's length scale (core's length_scale: 1 for the
// canonical geometry); 1 when it is not a positive number (a damaged row).
double scale_of(const CandidateRow& r) {
  const double scale = length_scale(candidate_geometry(r));
  return std::isfinite(scale) && scale > 0.0 ? scale : 1.0;
}

// The joints whose geometry the row holds: `joints` as stored, within what
// was read (a damaged row may claim more than kMaxJoints, or fewer than 0).
int stored_joints(const CandidateRow& r) { return std::clamp(r.joints, 0, static_cast<int>(r.a.size())); }

const double kAngleRoundOffDeg = kRoundOff * kDegreesPerRadian;

// The row's geometry in its conventional form (positive twists where the
// loop's representations allow, canonical.hpp), for what people read: the
// text table and Markdown. The stored canonical values stay in csv, json and
// the database. A row whose geometry is not a loop (damage) is shown as stored.
CandidateRow conventional(const CandidateRow& r) {
  CandidateRow shown = r;
  try {
    const LoopGeometry g = conventional_form(candidate_geometry(r)).geometry;
    const double scale = scale_of(r);
    for (int k = 0; k < g.joints() && k < static_cast<int>(shown.a.size()); ++k) {
      const size_t i = static_cast<size_t>(k);
      shown.a[i] = g.a[k] * scale;
      shown.alpha_deg[i] = g.alpha[k] * kDegreesPerRadian;
      shown.d[i] = g.d[k] * scale;
    }
  } catch (const std::invalid_argument&) {
  }
  return shown;
}

std::string geometry_text(const CandidateRow& stored, int digits) {
  const CandidateRow r = conventional(stored);
  const double length = kRoundOff * scale_of(r);
  return "a=" + shown_list(r.a, length, digits) + " alpha=" + shown_list(r.alpha_deg, kAngleRoundOffDeg, digits) +
         " d=" + shown_list(r.d, length, digits);
}

std::string range_text(const CandidateRow& r, bool unit) {
  if (r.full_turn) return "full turn";
  return "[" + shown(r.range_lo_deg, kAngleRoundOffDeg, 4) + ", " + shown(r.range_hi_deg, kAngleRoundOffDeg, 4) + "]" +
         (unit ? " deg" : "");
}

std::vector<CandidateRow> read_candidates(const ResultsDatabase& db, const ReportArguments& args, long long limit) {
  CandidateFilter filter;
  filter.family = args.family;
  if (!args.max_energy.empty()) filter.max_energy = parse_number(args.max_energy, "--max-energy");
  filter.first_run = run_filter(args);
  filter.limit = limit > 0 ? limit : -1;
  return db.candidates(filter);
}

std::int64_t count_candidates(const ResultsDatabase& db, const ReportArguments& args) {
  CandidateFilter filter;
  filter.family = args.family;
  if (!args.max_energy.empty()) filter.max_energy = parse_number(args.max_energy, "--max-energy");
  filter.first_run = run_filter(args);
  return db.candidate_count(filter);
}

// A text table: columns padded to their widest cell, one space apart. The
// last column is cut to fit `width` (0: never cut) and ends in "..." then.
struct TextColumn {
  std::string header;
  std::vector<std::string> cells;
};

void print_columns(const std::vector<TextColumn>& columns, size_t width) {
  std::vector<size_t> widths;
  size_t used = 0;
  for (size_t c = 0; c + 1 < columns.size(); ++c) {
    size_t w = columns[c].header.size();
    for (const std::string& cell : columns[c].cells) w = std::max(w, cell.size());
    widths.push_back(w);
    used += w + 1;
  }
  // The last column gets what is left, at least its header.
  const size_t left = width > used ? width - used : 0;
  const size_t last = width == 0 ? std::string::npos : std::max(columns.back().header.size(), left);
  const size_t rows = columns.front().cells.size();
  for (size_t r = 0; r <= rows; ++r) {
    std::string line;
    for (size_t c = 0; c < columns.size(); ++c) {
      const std::string& cell = r == 0 ? columns[c].header : columns[c].cells[r - 1];
      if (c + 1 < columns.size()) {
        line += cell + std::string(widths[c] - cell.size() + 1, ' ');
      } else {
        line += cell.size() <= last ? cell : cell.substr(0, last - 3) + "...";
      }
    }
    while (!line.empty() && line.back() == ' ') line.pop_back();
    std::printf("%s\n", line.c_str());
  }
}

// The candidates as a text table: by default the columns people scan first,
// cut to kTableColumns; --wide every column at 6 digits, uncut.
void print_table(const std::vector<CandidateRow>& rows, bool wide) {
  if (rows.empty()) {
    std::printf("(no candidates match)\n");
    return;
  }
  std::vector<TextColumn> columns;
  auto column = [&](const std::string& header, auto cell) {
    TextColumn c{header, {}};
    for (const CandidateRow& r : rows) c.cells.push_back(cell(r));
    columns.push_back(std::move(c));
  };
  column("id", [](const CandidateRow& r) { return std::to_string(r.id); });
  column("family", [](const CandidateRow& r) { return r.family; });
  if (wide) column("setup", [](const CandidateRow& r) { return r.setup; });
  column("E_mean", [](const CandidateRow& r) { return g(r.E_mean); });
  column("hits", [](const CandidateRow& r) { return std::to_string(r.hits); });
  if (wide) {
    column("first",
           [](const CandidateRow& r) { return std::to_string(r.first_run) + ":" + std::to_string(r.first_start); });
  }
  column("dim", [](const CandidateRow& r) {
    return std::to_string(r.local_dimension) + "/" + std::to_string(r.free_parameters);
  });
  if (wide) {
    column("rigid_res", [](const CandidateRow& r) { return g(r.rigid_residual, 2); });
    column("family_res", [](const CandidateRow& r) { return g(r.family_residual, 2); });
  }
  column(wide ? "input range" : "input [deg]", [&](const CandidateRow& r) { return range_text(r, wide); });
  column("geometry (conventional form, L = 1; twists in deg)",
         [&](const CandidateRow& r) { return geometry_text(r, wide ? 6 : 3); });
  print_columns(columns, wide ? 0 : kTableColumns);
}

void print_markdown(const std::vector<CandidateRow>& rows) {
  std::printf(
      "| id | family | setup | E_mean | hits | first (run:start) | local dim | rigid residual | family residual "
      "| input range | a | alpha [deg] | d |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  for (const CandidateRow& stored : rows) {
    const CandidateRow r = conventional(stored);
    const double length = kRoundOff * scale_of(r);
    std::printf("| %lld | %s | %s | %s | %lld | %lld:%lld | %d/%d | %s | %s | %s | %s | %s | %s |\n", r.id,
                r.family.c_str(), r.setup.c_str(), g(r.E_mean).c_str(), r.hits, r.first_run, r.first_start,
                r.local_dimension, r.free_parameters, g(r.rigid_residual, 2).c_str(), g(r.family_residual, 2).c_str(),
                range_text(r, true).c_str(), shown_list(r.a, length, 6).c_str(),
                shown_list(r.alpha_deg, kAngleRoundOffDeg, 6).c_str(), shown_list(r.d, length, 6).c_str());
  }
}

// One value in every form: CSV and JSON at full precision (NaN/NULL empty in
// CSV, null in JSON), text for people (significant digits, round-off as 0).
struct Field {
  std::string name;
  std::string csv;
  nlohmann::ordered_json json;
  std::string text;
};

std::string csv_text(const std::string& v) {
  if (v.find_first_of(",\"\n") == std::string::npos) return v;
  std::string quoted = "\"";
  for (char ch : v) quoted += ch == '"' ? std::string("\"\"") : std::string(1, ch);
  return quoted + "\"";
}

class Fields {
 public:
  void number(const std::string& name, double v, double threshold = 0.0, int digits = 6) {
    f_.push_back({name, std::isfinite(v) ? format_double(v) : "",
                  std::isfinite(v) ? nlohmann::ordered_json(v) : nullptr, shown(v, threshold, digits)});
  }
  void integer(const std::string& name, long long v) { f_.push_back({name, std::to_string(v), v, std::to_string(v)}); }
  void text(const std::string& name, const std::string& v) { f_.push_back({name, csv_text(v), v, v}); }
  void flag(const std::string& name, bool v) { f_.push_back({name, v ? "1" : "0", v, v ? "yes" : "no"}); }
  void raw(Field field) { f_.push_back(std::move(field)); }
  std::vector<Field>& list() { return f_; }

 private:
  std::vector<Field> f_;
};

// Every stored column of a candidates row that CandidateRow holds, geometry
// as a1..aN, alpha1_deg.., d1.. (`joints` of each, empty past the row's own).
std::vector<Field> fields(const CandidateRow& r, int joints) {
  Fields f;
  f.integer("candidate_id", r.id);
  f.text("family", r.family);
  f.text("setup", r.setup);
  f.text("detail", r.detail);
  f.number("E_mean", r.E_mean, 0.0, 3);
  f.number("E_max", r.E_max, 0.0, 3);
  f.integer("hits", r.hits);
  f.integer("first_run", r.first_run);
  f.integer("first_start", r.first_start);
  f.integer("local_dimension", r.local_dimension);
  f.integer("free_parameters", r.free_parameters);
  f.number("rigid_residual", r.rigid_residual, 0.0, 2);
  f.number("family_residual", r.family_residual, 0.0, 2);
  f.number("bennett_residual", r.bennett_residual, 0.0, 2);
  f.number("planar_residual", r.planar_residual, 0.0, 2);
  f.number("spherical_residual", r.spherical_residual, 0.0, 2);
  f.number("trivial_residual", r.trivial_residual, 0.0, 2);
  f.flag("full_turn", r.full_turn);
  f.number("range_lo_deg", r.range_lo_deg, kAngleRoundOffDeg);
  f.number("range_hi_deg", r.range_hi_deg, kAngleRoundOffDeg);
  f.integer("joints", r.joints);
  const double length = kRoundOff * scale_of(r);
  const char* kinds[] = {"a%d", "alpha%d_deg", "d%d"};
  const std::vector<double>* values[] = {&r.a, &r.alpha_deg, &r.d};
  const double thresholds[] = {length, kAngleRoundOffDeg, length};
  for (int k = 0; k < 3; ++k) {
    for (int i = 0; i < joints; ++i) {
      char name[16];
      std::snprintf(name, sizeof name, kinds[k], i + 1);
      f.number(name, i < static_cast<int>(values[k]->size()) ? (*values[k])[static_cast<size_t>(i)] : NAN,
               thresholds[k]);
    }
  }
  return std::move(f.list());
}

void print_csv(const std::vector<CandidateRow>& rows) {
  int joints = 4;
  for (const CandidateRow& r : rows) joints = std::max(joints, stored_joints(r));
  const std::vector<Field> header = fields(CandidateRow{}, joints);
  for (size_t i = 0; i < header.size(); ++i) std::printf("%s%s", i ? "," : "", header[i].name.c_str());
  std::printf("\n");
  for (const CandidateRow& r : rows) {
    const std::vector<Field> f = fields(r, joints);
    for (size_t i = 0; i < f.size(); ++i) std::printf("%s%s", i ? "," : "", f[i].csv.c_str());
    std::printf("\n");
  }
}

nlohmann::ordered_json json_object(const std::vector<Field>& f) {
  nlohmann::ordered_json object = nlohmann::ordered_json::object();
  for (const Field& field : f) object[field.name] = field.json;
  return object;
}

// One JSON array, a candidate a line.
void print_json(const std::vector<CandidateRow>& rows) {
  std::printf("[");
  for (size_t k = 0; k < rows.size(); ++k) {
    std::printf("%s\n%s", k ? "," : "", json_object(fields(rows[k], stored_joints(rows[k]))).dump().c_str());
  }
  std::printf("%s]\n", rows.empty() ? "" : "\n");
}

// --- one candidate whole: --candidate ID ---------------------------------------

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
  std::vector<Field> f = fields(c.row, stored_joints(c.row));
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

void print_candidate_text(const CandidateDetails& c, const std::optional<CandidatePose>& pose,
                          const std::string& missing) {
  const CandidateRow& r = c.row;
  std::printf("candidate %lld\n", r.id);
  const std::vector<Field> f = detail_fields(c);
  size_t width = 0;
  for (const Field& x : f) width = std::max(width, x.name.size());
  // The geometry columns follow as a table, one row per joint.
  std::set<std::string> geometry;
  for (const Field& x : fields(CandidateRow{}, stored_joints(r))) geometry.insert(x.name);
  for (const Field& x : fields(CandidateRow{}, 0)) geometry.erase(x.name);
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

// --- the summary ----------------------------------------------------------------

struct SummaryData {
  std::vector<RunRow> runs;
  StartCounts starts;
  std::vector<StatusCount> statuses;
  std::vector<FamilyCount> families;
  EnergyHistogram histogram;
};

SummaryData read_summary(const ResultsDatabase& db, const std::optional<std::int64_t>& run) {
  return {db.runs(), db.start_counts(run), db.status_counts(run), db.family_counts(run), db.energy_histogram(run)};
}

std::string run_where(const RunRow& r) {
  // Where its starts were computed: ranks of the last session, or the databases it was merged from.
  return r.merged_inputs > 0 ? "merged from " + std::to_string(r.merged_inputs) + " databases"
                             : std::to_string(r.ranks) + (r.ranks == 1 ? " rank" : " ranks");
}

void print_summary(const ResultsDatabase& db, const SummaryData& s) {
  std::printf("database %s\n", db.path().c_str());
  std::printf("runs\n");
  for (const RunRow& r : s.runs) {
    const std::string slice = r.slice ? "  slice " + to_string(*r.slice) : "";
    std::printf("  run %lld  %s  seed %llu%s  %lld/%lld starts  %s  %s  %s .. %s\n", static_cast<long long>(r.run_id),
                r.job_path.c_str(), static_cast<unsigned long long>(r.seed), slice.c_str(),
                static_cast<long long>(r.starts_done), static_cast<long long>(r.starts), r.status.c_str(),
                run_where(r).c_str(), r.started_at.c_str(), r.updated_at.c_str());
  }
  const StartCounts& c = s.starts;
  std::printf("starts     %lld, zero minima %lld, verified %lld, mean %.4g s per start, %.4g core-seconds\n",
              static_cast<long long>(c.starts), static_cast<long long>(c.zeros), static_cast<long long>(c.verified),
              c.mean_seconds, c.total_seconds);
  std::printf("by status\n");
  for (const StatusCount& x : s.statuses) {
    std::printf("  %-18s %lld\n", x.status.c_str(), static_cast<long long>(x.starts));
  }
  std::printf("candidates by family (distinct linkages, starts that found them)\n");
  for (const FamilyCount& f : s.families) {
    std::printf("  %-23s %6lld %8lld\n", f.family.c_str(), static_cast<long long>(f.candidates),
                static_cast<long long>(f.hits));
  }
  const EnergyHistogram& h = s.histogram;
  std::int64_t most = 1;
  for (const auto& [decade, count] : h.decades) most = std::max(most, count);
  std::printf("histogram of log10(E_mean) over all starts\n");
  for (const auto& [decade, count] : h.decades) {
    const int width = static_cast<int>(std::lround(50.0 * static_cast<double>(count) / static_cast<double>(most)));
    std::printf("  [%4d, %4d) %7lld %s\n", decade, decade + 1, static_cast<long long>(count),
                std::string(static_cast<size_t>(width), '#').c_str());
  }
  if (h.zeros) std::printf("  exactly 0   %7lld\n", static_cast<long long>(h.zeros));
  if (h.missing) {
    std::printf("  no value    %7lld (the start could not be evaluated)\n", static_cast<long long>(h.missing));
  }
}

void print_summary_json(const ResultsDatabase& db, const SummaryData& s, const std::optional<std::int64_t>& run) {
  using nlohmann::ordered_json;
  ordered_json out;
  out["database"] = db.path();
  out["run"] = run ? ordered_json(*run) : ordered_json(nullptr);
  ordered_json runs = ordered_json::array();
  for (const RunRow& r : s.runs) {
    ordered_json row;
    row["run_id"] = r.run_id;
    row["job_path"] = r.job_path;
    row["seed"] = r.seed;
    row["slice"] = r.slice ? ordered_json(to_string(*r.slice)) : ordered_json(nullptr);
    row["joints"] = r.joints;
    row["starts"] = r.starts;
    row["starts_done"] = r.starts_done;
    row["status"] = r.status;
    row["ranks"] = r.ranks;
    row["merged_inputs"] = r.merged_inputs;
    row["started_at"] = r.started_at;
    row["updated_at"] = r.updated_at;
    runs.push_back(row);
  }
  out["runs"] = runs;
  const StartCounts& c = s.starts;
  ordered_json starts;
  starts["starts"] = c.starts;
  starts["zero_minima"] = c.zeros;
  starts["verified"] = c.verified;
  starts["mean_seconds"] = c.mean_seconds;
  starts["core_seconds"] = c.total_seconds;
  out["starts"] = starts;
  ordered_json statuses = ordered_json::array();
  for (const auto& status : s.statuses) statuses.push_back({{"status", status.status}, {"starts", status.starts}});
  out["by_status"] = statuses;
  ordered_json families = ordered_json::array();
  for (const auto& family : s.families) {
    families.push_back({{"family", family.family}, {"candidates", family.candidates}, {"hits", family.hits}});
  }
  out["families"] = families;
  ordered_json decades = ordered_json::array();
  for (const auto& [decade, count] : s.histogram.decades) {
    decades.push_back({{"log10_E_mean", decade}, {"starts", count}});
  }
  out["histogram"] = {{"decades", decades}, {"zeros", s.histogram.zeros}, {"missing", s.histogram.missing}};
  std::printf("%s\n", out.dump().c_str());
}

void print_summary_markdown(const ResultsDatabase& db, const SummaryData& s) {
  std::printf("Database `%s`\n\n", db.path().c_str());
  std::printf("| run | job | seed | slice | starts done | starts | status | where | started | updated |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|\n");
  for (const RunRow& r : s.runs) {
    std::printf("| %lld | `%s` | %llu | %s | %lld | %lld | %s | %s | %s | %s |\n", static_cast<long long>(r.run_id),
                r.job_path.c_str(), static_cast<unsigned long long>(r.seed), r.slice ? to_string(*r.slice).c_str() : "",
                static_cast<long long>(r.starts_done), static_cast<long long>(r.starts), r.status.c_str(),
                run_where(r).c_str(), r.started_at.c_str(), r.updated_at.c_str());
  }
  const StartCounts& c = s.starts;
  std::printf("\n| starts | zero minima | verified | mean seconds per start | core-seconds |\n|---|---|---|---|---|\n");
  std::printf("| %lld | %lld | %lld | %.4g | %.4g |\n", static_cast<long long>(c.starts),
              static_cast<long long>(c.zeros), static_cast<long long>(c.verified), c.mean_seconds, c.total_seconds);
  std::printf("\n| status | starts |\n|---|---|\n");
  for (const StatusCount& x : s.statuses)
    std::printf("| %s | %lld |\n", x.status.c_str(), static_cast<long long>(x.starts));
  std::printf("\n| family | candidates | hits |\n|---|---|---|\n");
  for (const FamilyCount& f : s.families) {
    std::printf("| %s | %lld | %lld |\n", f.family.c_str(), static_cast<long long>(f.candidates),
                static_cast<long long>(f.hits));
  }
  std::printf("\n| log10(E_mean) | starts |\n|---|---|\n");
  for (const auto& [decade, count] : s.histogram.decades) {
    std::printf("| [%d, %d) | %lld |\n", decade, decade + 1, static_cast<long long>(count));
  }
  if (s.histogram.zeros) std::printf("| exactly 0 | %lld |\n", static_cast<long long>(s.histogram.zeros));
  if (s.histogram.missing) std::printf("| no value | %lld |\n", static_cast<long long>(s.histogram.missing));
}

// --- what the selection names must exist -----------------------------------------

void check_run_exists(const ResultsDatabase& db, std::int64_t run) {
  std::string ids;
  for (const RunRow& r : db.runs()) {
    if (r.run_id == run) return;
    ids += (ids.empty() ? "" : ", ") + std::to_string(r.run_id);
  }
  throw UsageError("--run", "no run " + std::to_string(run) + " in " + db.path() + "; " +
                                (ids.empty() ? "it holds no run" : "its runs: " + ids));
}

void check_family_present(const ResultsDatabase& db, const std::string& family) {
  std::string present;
  for (const FamilyCount& f : db.family_counts()) {
    if (f.family == family) return;
    present += (present.empty() ? "" : ", ") + f.family + " (" + grouped(f.candidates) + ")";
  }
  throw UsageError("--family", "no " + family + " candidate in " + db.path() + "; " +
                                   (present.empty() ? "it holds no candidate" : "families present: " + present));
}

std::string candidate_ids_text(const ResultsDatabase& db) {
  const std::optional<CandidateIdRange> ids = db.candidate_id_range();
  if (!ids) return "it holds no candidate";
  return "candidate ids " + std::to_string(ids->first) + " to " + std::to_string(ids->last) + " (" +
         grouped(db.candidate_count()) + " candidates)";
}

// Each run's zero threshold, by run id.
std::map<std::int64_t, double> run_thresholds(const ResultsDatabase& db) {
  std::map<std::int64_t, double> thresholds;
  for (const RunRow& r : db.runs()) thresholds[r.run_id] = r.zero_threshold;
  return thresholds;
}

// The threshold the histogram marks: the run's, or the smallest of every
// run's (merged runs share theirs); 0 without runs.
double histogram_threshold(const ResultsDatabase& db, std::optional<std::int64_t> run) {
  double threshold = 0.0;
  for (const RunRow& r : db.runs()) {
    if (run && r.run_id != *run) continue;
    if (r.zero_threshold > 0.0 && (threshold == 0.0 || r.zero_threshold < threshold)) threshold = r.zero_threshold;
  }
  return threshold;
}

void plot_candidates(const std::filesystem::path& gnuplot, const std::vector<CandidateRow>& rows,
                     const std::map<std::int64_t, double>& thresholds, const std::filesystem::path& dir) {
  for (const CandidateRow& r : rows) {
    const LoopGeometry geometry = LoopGeometry::from_degrees(
        std::span<const double>(r.a), std::span<const double>(r.alpha_deg), std::span<const double>(r.d));
    const LoopModel model(geometry);
    EquilibriumWorkspace workspace(model);
    const EquilibriumSummary assembly = assemble(model, workspace, 0.0);
    CycleOptions options;
    options.samples = 360;
    CycleSummary cycle;
    cycle_energy(model, workspace, 0.0, assembly.state, options, cycle);
    EnergyPlotStyle style;
    style.title = "candidate " + std::to_string(r.id) + " (" + r.family + "): cycle energy of the canonical geometry";
    // The table's E_mean is the search's, stored with the candidate; this
    // curve is recomputed (another start pose and sample count), so its
    // mean differs by round-off or more: both are quoted, each named.
    style.notes = {
        "E_mean " + g(r.E_mean) + " as stored (the table's value)",
        "this curve: E_mean " + g(cycle.E_mean) + ", E_max " + g(cycle.E_max) + " over 360 samples from theta_1 = 0"};
    style.log_scale = true;
    const auto threshold = thresholds.find(r.first_run);
    if (threshold != thresholds.end() && threshold->second > 0.0) {
      style.zero_threshold = threshold->second;
      style.threshold_source = "run " + std::to_string(r.first_run) + "'s";
    }
    const std::filesystem::path png = dir / ("candidate_" + std::to_string(r.id) + "_cycle.png");
    style.format = plot_format(png, "--plot");
    plot_energy_curve(gnuplot, cycle, style, png);
    std::fprintf(stderr, "loopfarm report: wrote %s (E_mean %s stored, %s on the recomputed curve)\n",
                 png.string().c_str(), g(r.E_mean).c_str(), g(cycle.E_mean).c_str());
  }
}

// Markdown for the atlas: the database, the selection and its runs.
std::string atlas_header(const ResultsDatabase& db, const ReportArguments& args) {
  std::string out = "Database `" + db.path() + "`";
  if (!args.family.empty()) out += ", family " + args.family;
  if (!args.run.empty()) out += ", candidates run " + args.run + " found first";
  if (!args.max_energy.empty()) out += ", E_mean <= " + args.max_energy;
  out += ". Runs:\n\n";
  for (const RunRow& r : db.runs()) {
    out += "- run " + std::to_string(r.run_id) + ": `" + r.job_path + "`, " + std::to_string(r.joints) + "R, seed " +
           std::to_string(r.seed) + (r.slice ? ", slice " + to_string(*r.slice) : "") + ", " +
           std::to_string(r.starts_done) + " of " + std::to_string(r.starts) + " starts, " + r.status +
           (r.merged_inputs > 0 ? ", merged from " + std::to_string(r.merged_inputs) + " databases" : "") + "\n";
  }
  return out;
}

// The candidate's pose and axes; a note instead when none is found (a row
// that does not move, or a geometry that is not a loop: a stored row is data).
void show_candidate(const ResultsDatabase& db, const ReportArguments& args) {
  const long long id = parse_integer(args.candidate, "--candidate");
  const std::optional<CandidateDetails> details = db.candidate(id);
  if (!details) {
    throw UsageError("--candidate",
                     "no candidate " + std::to_string(id) + " in " + db.path() + "; " + candidate_ids_text(db));
  }
  const double input_deg = args.input_deg.empty() ? kDefaultInputDeg : parse_number(args.input_deg, "--input-deg");
  std::optional<CandidatePose> pose;
  std::string missing;
  try {
    pose = candidate_pose(candidate_geometry(details->row), input_deg);
    if (!pose) missing = "the rigid loop of the stored geometry does not move";
  } catch (const std::invalid_argument& error) {
    missing = std::string("the stored geometry is not a loop: ") + error.what();
  }
  if (pose && !args.input_deg.empty() &&
      std::abs(std::remainder(pose->input_deg - input_deg, 360.0)) > kAngleRoundOffDeg) {
    throw UsageError("--input-deg", "joint 1 of candidate " + std::to_string(id) + " rocks in [" +
                                        g(pose->range_lo_deg, 6) + ", " + g(pose->range_hi_deg, 6) +
                                        "] deg and does not reach " + args.input_deg + " deg");
  }
  if (!missing.empty()) std::fprintf(stderr, "loopfarm report: candidate %lld: no pose: %s\n", id, missing.c_str());
  if (args.format.format == OutputFormat::csv) {
    print_candidate_csv(*details, pose, missing);
  } else if (args.format.format == OutputFormat::json) {
    print_candidate_json(*details, pose, missing);
  } else if (args.format.format == OutputFormat::markdown) {
    print_candidate_markdown(*details, pose, missing);
  } else {
    print_candidate_text(*details, pose, missing);
  }
}

void list_candidates(const ResultsDatabase& db, const ReportArguments& args, const std::filesystem::path& gnuplot) {
  // Files and scripts get every row unless --limit says otherwise; the table
  // kTableDefaultLimit, and says how many it left out.
  const bool table = args.format.format == OutputFormat::text;
  const long long limit = !args.limit.empty() ? parse_integer(args.limit, "--limit") : (table ? kTableDefaultLimit : 0);
  const std::vector<CandidateRow> rows = read_candidates(db, args, limit);
  if (args.format.format == OutputFormat::csv) {
    print_csv(rows);
  } else if (args.format.format == OutputFormat::json) {
    print_json(rows);
  } else if (args.format.format == OutputFormat::markdown) {
    print_markdown(rows);
  } else {
    print_table(rows, args.wide);
    if (limit > 0 && static_cast<long long>(rows.size()) == limit) {
      const std::int64_t total = count_candidates(db, args);
      if (total > limit) {
        std::printf("showing %s of %s (use --limit 0 for all)\n", grouped(limit).c_str(), grouped(total).c_str());
      }
    }
  }
  if (!args.plot.empty()) {
    plot_candidates(gnuplot, std::vector<CandidateRow>(rows.begin(), rows.begin() + std::min<size_t>(rows.size(), 10)),
                    run_thresholds(db), args.plot);
  }
}

int run_report(const ReportArguments& args) {
  if (!args.limit.empty() && parse_integer(args.limit, "--limit") < 0) {
    throw UsageError("--limit", "got " + args.limit + "; must be >= 0 (0: every candidate)");
  }
  if (args.summary && args.format.format == OutputFormat::csv) {
    throw UsageError("--format",
                     "--summary has no csv form (its parts are tables of different columns); use text, "
                     "json or markdown");
  }
  if (args.wide && args.format.format != OutputFormat::text) {
    throw UsageError("--wide", std::string("widens the table only; --format ") + to_string(args.format.format) +
                                   " has every column already");
  }
  if (!args.max_energy.empty()) (void)parse_number(args.max_energy, "--max-energy");
  if (!args.run.empty()) (void)parse_integer(args.run, "--run");
  if (!args.candidate.empty()) (void)parse_integer(args.candidate, "--candidate");
  if (!args.input_deg.empty()) (void)parse_number(args.input_deg, "--input-deg");
  if (!args.family.empty()) {
    // Every family a classification can store (docs/guide/families.md for n = 5, 6).
    if (!family_from_string(args.family)) {
      throw UsageError("--family", "got " + quote_text(args.family) + "; expected one of " + family_names());
    }
  }
  std::filesystem::path gnuplot;
  if (!args.plot.empty()) {
    gnuplot = require_gnuplot("--plot");
    std::error_code ec;
    std::filesystem::create_directories(args.plot, ec);
    if (ec || !std::filesystem::is_directory(args.plot)) {
      throw UsageError("--plot", "cannot create directory " + quote_text(args.plot) + ": " + ec.message());
    }
  }
  std::filesystem::path atlas_dir;
  if (!args.atlas.empty()) {
    // Checked before the database is opened: a bad directory costs nothing.
    gnuplot = require_gnuplot("--atlas");
    atlas_dir = args.atlas;
    std::error_code ec;
    if (std::filesystem::exists(atlas_dir, ec) && !std::filesystem::is_directory(atlas_dir, ec)) {
      throw UsageError("--atlas", quote_text(args.atlas) + " exists and is not a directory");
    }
    std::filesystem::create_directories(atlas_dir, ec);
    if (ec || !std::filesystem::is_directory(atlas_dir)) {
      throw UsageError("--atlas", "cannot create directory " + quote_text(args.atlas) + ": " + ec.message());
    }
    if (::access(atlas_dir.c_str(), W_OK | X_OK) != 0) {
      throw UsageError("--atlas", "cannot write into directory " + quote_text(args.atlas));
    }
  }
  // Created before the database is opened: an unwritable path costs nothing.
  std::optional<PendingOutput> html;
  if (!args.html.empty()) html.emplace(args.html, "--html");
  std::optional<ResultsDatabase> db;
  try {
    db.emplace(ResultsDatabase::open(args.database, DatabaseMode::read));
  } catch (const DatabaseError& error) {
    throw UsageError("DB", error.what());
  }
  try {
    // One read transaction: the checks, the summary and the list see the
    // same state even while a run commits.
    const ResultsDatabase::Snapshot snapshot = db->snapshot();
    const std::optional<std::int64_t> run = run_filter(args);
    if (run) check_run_exists(*db, *run);
    if (!args.family.empty()) check_family_present(*db, args.family);
    if (!args.candidate.empty()) {
      show_candidate(*db, args);
    } else if (!args.atlas.empty()) {
      write_atlas(gnuplot, read_candidates(*db, args, 0), run_thresholds(*db), atlas_header(*db, args), atlas_dir);
    } else if (html) {
      write_html_atlas(*db, {args.family, run, args.max_energy}, read_candidates(*db, args, 0), *html);
      html->commit();
      if (!html->to_standard_output()) std::fprintf(stderr, "loopfarm report: wrote %s\n", args.html.c_str());
    } else if (args.summary) {
      const SummaryData summary = read_summary(*db, run);
      if (args.format.format == OutputFormat::json) {
        print_summary_json(*db, summary, run);
      } else if (args.format.format == OutputFormat::markdown) {
        print_summary_markdown(*db, summary);
      } else {
        print_summary(*db, summary);
      }
    } else {
      list_candidates(*db, args, gnuplot);
    }
    if (!args.plot.empty()) {
      const std::filesystem::path png = std::filesystem::path(args.plot) / "minima_histogram.png";
      const EnergyHistogram histogram = db->energy_histogram(run);
      plot_minima_histogram(gnuplot, histogram.decades, histogram.zeros, histogram_threshold(*db, run),
                            plot_format(png, "--plot"), png, "--plot");
      std::fprintf(stderr, "loopfarm report: wrote %s\n", png.string().c_str());
    }
  } catch (const DatabaseError& error) {
    rethrow_read_error(error);
  }
  return kExitSuccess;
}

}  // namespace

Subcommand add_report_command(CLI::App& parent) {
  auto args = std::make_shared<ReportArguments>();
  CLI::App* app = parent.add_subcommand(
      "report", "List the distinct zero-energy linkages of a results database, from zero energy upwards.");
  app->footer(
      "Examples:\n"
      "  loopfarm report default.sqlite\n"
      "  loopfarm report default.sqlite --family bennett --format csv > bennett.csv   # every Bennett row\n"
      "  loopfarm report default.sqlite --candidate 17 --format json   # one candidate and its joint axes\n"
      "  loopfarm report default.sqlite --summary --format json\n"
      "  loopfarm report default.sqlite --summary --plot docs/default\n"
      "  loopfarm report goldberg-5r.sqlite --atlas docs/research/atlas\n"
      "  loopfarm report default.sqlite --html atlas.html   # one page, opens offline in any browser\n"
      "Order: unclassified candidates (possible new families) first, then by E_mean from zero upwards, ties by id.\n"
      "The table fits 120 columns (--wide: every column) and prints geometry round-off as 0 (|x| < 1e-9 L for\n"
      "lengths, L the loop's length scale; |x| < 1e-9 rad for angles); csv and json keep every stored digit.\n"
      "Read-only; works while a run is writing.\n"
      "Exit codes: 0 done, 1 failure (gnuplot), 2 bad input (options; a run, family or candidate the database\n"
      "does not hold; a file that is not a loopfarm database or is damaged: checked with PRAGMA quick_check,\n"
      "about 2 s per million starts; the file is never changed).\n");
  app->add_option("DB", args->database, "results database (SQLite) written by loopfarm run")->required();
  CLI::Option* family = app->add_option("--family", args->family, "only this family: " + family_names());
  CLI::Option* max_energy =
      app->add_option("--max-energy", args->max_energy, "only candidates with E_mean at most this")->type_name("E");
  CLI::Option* limit =
      app->add_option("--limit", args->limit,
                      "at most this many candidates; 0: all (default: 50 in the table, all in csv, json, markdown)")
          ->type_name("N");
  CLI::Option* run =
      app->add_option("--run", args->run, "only what run ID found first (default: every run)")->type_name("ID");
  add_format_option(*app, args->format,
                    {OutputFormat::text, OutputFormat::csv, OutputFormat::json, OutputFormat::markdown},
                    "print the candidates (text: a table) as");
  app->add_flag("--wide", args->wide, "the table with every column, uncut (default: fits 120 columns)");
  CLI::Option* summary = app->add_flag(
      "--summary", args->summary,
      "runs, counts per family and status, and the histogram of log10 of all minima (text, json or markdown)");
  CLI::Option* candidate =
      app->add_option("--candidate", args->candidate,
                      "show candidate ID whole: every stored column and each joint's axis (a point and a unit "
                      "direction in the base frame) at a closed pose")
          ->type_name("ID");
  CLI::Option* input_deg =
      app->add_option("--input-deg", args->input_deg,
                      "with --candidate: the pose with joint 1 at this angle (default 90; a rocker that does not "
                      "reach 90: the middle of its range)")
          ->type_name("DEG");
  input_deg->needs(candidate);
  CLI::Option* plot =
      app->add_option("--plot", args->plot,
                      "write PNG charts into DIR: the histogram of minima and the cycle energy of the listed "
                      "candidates (at most 10)")
          ->type_name("DIR");
  CLI::Option* atlas =
      app->add_option("--atlas", args->atlas,
                      "write a family atlas into DIR: atlas.md with, per family, the counts, the spread of the "
                      "parameters, the local dimension against the known one, and a representative's cycle-energy "
                      "chart (PNG) and motion (SVG); --family, --run and --max-energy select, --limit does not apply")
          ->type_name("DIR");
  atlas->excludes(summary)
      ->excludes(plot)
      ->excludes(limit)
      ->excludes("--format")
      ->excludes("--json")
      ->excludes("--wide");
  CLI::Option* html =
      app->add_option("--html", args->html,
                      "write the atlas as one self-contained HTML page: the summary, the histogram of minima, the "
                      "family table and, per family, its representative moving in 3D (drag to turn; play, pause, a "
                      "slider for the input angle), its cycle energy and parameters; --family, --run and "
                      "--max-energy select, --limit does not apply")
          ->type_name("FILE");
  html->excludes(atlas)
      ->excludes(summary)
      ->excludes(plot)
      ->excludes(limit)
      ->excludes("--format")
      ->excludes("--json")
      ->excludes("--wide");
  candidate->excludes(family)
      ->excludes(max_energy)
      ->excludes(limit)
      ->excludes(run)
      ->excludes(summary)
      ->excludes(plot)
      ->excludes(atlas)
      ->excludes(html)
      ->excludes("--wide");
  summary->excludes(limit)->excludes("--wide");
  return {app, [args] { return run_report(*args); }};
}

}  // namespace loopfarm::cli
