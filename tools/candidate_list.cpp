#include "candidate_list.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "candidate_display.hpp"
#include "cli_support.hpp"

namespace loopfarm::cli {
namespace {

// The text table's width without --wide.
constexpr size_t kTableColumns = 120;

std::string g(double v, int digits = 3) { return format_significant(v, digits); }

std::string geometry_text(const CandidateRow& stored, int digits) {
  const CandidateRow r = conventional(stored);
  const double length = kRoundOff * scale_of(r);
  return "a=" + shown_list(r.a, length, digits) + " alpha=" + shown_list(r.alpha_deg, kAngleRoundOffDeg, digits) +
         " d=" + shown_list(r.d, length, digits);
}

std::string range_text(const CandidateRow& r, bool unit) {
  if (r.full_turn) return "full turn";
  std::string text = "[";
  text += shown(r.range_lo_deg, kAngleRoundOffDeg, 4);
  text += ", ";
  text += shown(r.range_hi_deg, kAngleRoundOffDeg, 4);
  text += unit ? "] deg" : "]";
  return text;
}

}  // namespace

void Fields::number(const std::string& name, double v, double threshold, int digits) {
  f_.push_back({name, std::isfinite(v) ? format_double(v) : "", std::isfinite(v) ? nlohmann::ordered_json(v) : nullptr,
                shown(v, threshold, digits)});
}
void Fields::integer(const std::string& name, long long v) {
  f_.push_back({name, std::to_string(v), v, std::to_string(v)});
}
void Fields::text(const std::string& name, const std::string& v) { f_.push_back({name, csv_text(v), v, v}); }
void Fields::flag(const std::string& name, bool v) { f_.push_back({name, v ? "1" : "0", v, v ? "yes" : "no"}); }
void Fields::raw(Field field) { f_.push_back(std::move(field)); }

std::string csv_text(const std::string& v) {
  if (v.find_first_of(",\"\n") == std::string::npos) return v;
  std::string quoted = "\"";
  for (char ch : v) quoted += ch == '"' ? std::string("\"\"") : std::string(1, ch);
  return quoted + "\"";
}

std::vector<Field> candidate_fields(const CandidateRow& r, int joints) {
  Fields f;
  f.integer("candidate_id", r.id);
  f.text("family", r.family);
  // Every family whose conditions hold, ';'-separated in CSV and Markdown as
  // lists are; null when the row predates their recording (schema version 4).
  if (r.families) {
    std::string joined = *r.families;
    std::replace(joined.begin(), joined.end(), ',', ';');
    nlohmann::ordered_json names = nlohmann::ordered_json::array();
    std::string name;
    for (char ch : *r.families + ",") {
      if (ch != ',') {
        name.push_back(ch);
      } else if (!name.empty()) {
        names.push_back(name);
        name.clear();
      }
    }
    f.raw({"families", joined, names, joined.empty() ? "none" : joined});
  } else {
    f.raw({"families", "", nullptr, "not recorded"});
  }
  f.text("setup", r.setup);
  f.text("detail", r.detail);
  f.number("E_mean", r.E_mean, 0.0, 3);
  f.number("E_max", r.E_max, 0.0, 3);
  f.integer("hits", r.hits);
  f.integer("first_run", r.first_run);
  f.integer("first_start", r.first_start);
  // Empty and null when unknown (stored as -1).
  if (r.local_dimension >= 0) {
    f.integer("local_dimension", r.local_dimension);
  } else {
    f.raw({"local_dimension", "", nullptr, dimension_text(r.local_dimension)});
  }
  f.integer("free_parameters", r.free_parameters);
  // Null when not measured (loopfarm bonds --store), empty when measured and
  // none (the stored geometry does not move).
  if (r.bond_fingerprint) {
    f.raw({"bond_fingerprint", csv_text(*r.bond_fingerprint), *r.bond_fingerprint,
           r.bond_fingerprint->empty() ? "none (does not move)" : *r.bond_fingerprint});
  } else {
    f.raw({"bond_fingerprint", "", nullptr, "not measured"});
  }
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

nlohmann::ordered_json json_object(const std::vector<Field>& f) {
  nlohmann::ordered_json object = nlohmann::ordered_json::object();
  for (const Field& field : f) object[field.name] = field.json;
  return object;
}

void print_candidate_table(const std::vector<CandidateRow>& rows, bool wide) {
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
  column("dim", [](const CandidateRow& r) { return dimension_of(r.local_dimension, r.free_parameters); });
  if (wide) {
    column("rigid_res", [](const CandidateRow& r) { return g(r.rigid_residual, 2); });
    column("family_res", [](const CandidateRow& r) { return g(r.family_residual, 2); });
  }
  column(wide ? "input range" : "input [deg]", [&](const CandidateRow& r) { return range_text(r, wide); });
  column("geometry (conventional form, L = 1; twists in deg)",
         [&](const CandidateRow& r) { return geometry_text(r, wide ? 6 : 3); });
  print_columns(columns, wide ? 0 : kTableColumns);
}

void print_candidates_markdown(const std::vector<CandidateRow>& rows) {
  std::printf(
      "| id | family | setup | E_mean | hits | first (run:start) | local dim | rigid residual | family residual "
      "| input range | a | alpha [deg] | d |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  for (const CandidateRow& stored : rows) {
    const CandidateRow r = conventional(stored);
    const double length = kRoundOff * scale_of(r);
    std::printf("| %lld | %s | %s | %s | %lld | %lld:%lld | %s | %s | %s | %s | %s | %s | %s |\n", r.id,
                r.family.c_str(), r.setup.c_str(), g(r.E_mean).c_str(), r.hits, r.first_run, r.first_start,
                dimension_of(r.local_dimension, r.free_parameters).c_str(), g(r.rigid_residual, 2).c_str(),
                g(r.family_residual, 2).c_str(), range_text(r, true).c_str(), shown_list(r.a, length, 6).c_str(),
                shown_list(r.alpha_deg, kAngleRoundOffDeg, 6).c_str(), shown_list(r.d, length, 6).c_str());
  }
}

void print_candidates_csv(const std::vector<CandidateRow>& rows) {
  int joints = 4;
  for (const CandidateRow& r : rows) joints = std::max(joints, stored_joints(r));
  const std::vector<Field> header = candidate_fields(CandidateRow{}, joints);
  for (size_t i = 0; i < header.size(); ++i) std::printf("%s%s", i ? "," : "", header[i].name.c_str());
  std::printf("\n");
  for (const CandidateRow& r : rows) {
    const std::vector<Field> f = candidate_fields(r, joints);
    for (size_t i = 0; i < f.size(); ++i) std::printf("%s%s", i ? "," : "", f[i].csv.c_str());
    std::printf("\n");
  }
}

void print_candidates_json(const std::vector<CandidateRow>& rows) {
  std::printf("[");
  for (size_t k = 0; k < rows.size(); ++k) {
    std::printf("%s\n%s", k ? "," : "", json_object(candidate_fields(rows[k], stored_joints(rows[k]))).dump().c_str());
  }
  std::printf("%s]\n", rows.empty() ? "" : "\n");
}

}  // namespace loopfarm::cli
