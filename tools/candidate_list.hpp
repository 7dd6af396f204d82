// The selected candidates of `loopfarm report DB` as a list: a text table for
// people (the columns they scan first, or every one with --wide), Markdown,
// CSV and JSON; and the fields of one candidates row in every form, which the
// list and --candidate (candidate_detail.hpp) print.
#pragma once

#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "loopfarm/farm/results_database.hpp"

namespace loopfarm::cli {

// One value in every form: CSV and JSON at full precision (NaN/NULL empty in
// CSV, null in JSON), text for people (significant digits, round-off as 0).
struct Field {
  std::string name;
  std::string csv;
  nlohmann::ordered_json json;
  std::string text;
};

// Fields built one by one, each kind of value in its forms.
class Fields {
 public:
  // `threshold`: round-off below which the text shows 0; `digits` significant digits of the text.
  void number(const std::string& name, double v, double threshold = 0.0, int digits = 6);
  void integer(const std::string& name, long long v);
  void text(const std::string& name, const std::string& v);
  void flag(const std::string& name, bool v);
  void raw(Field field);
  std::vector<Field>& list() { return f_; }

 private:
  std::vector<Field> f_;
};

// A CSV cell: quoted (quotes doubled) when it holds a comma, a quote or a newline.
std::string csv_text(const std::string& v);

// Every stored column of a candidates row that CandidateRow holds, geometry
// as a1..aN, alpha1_deg.., d1.. (`joints` of each, empty past the row's own).
std::vector<Field> candidate_fields(const CandidateRow& r, int joints);

// The fields as one JSON object, in their order.
nlohmann::ordered_json json_object(const std::vector<Field>& f);

// The candidates as a text table: by default the columns people scan first,
// cut to 120 columns; `wide` every column at 6 digits, uncut. The geometry in
// its conventional form.
void print_candidate_table(const std::vector<CandidateRow>& rows, bool wide);
// A Markdown table of every column, the geometry in its conventional form.
void print_candidates_markdown(const std::vector<CandidateRow>& rows);
// A header line and a line per candidate, every stored value at full precision.
void print_candidates_csv(const std::vector<CandidateRow>& rows);
// One JSON array, a candidate a line, every stored value at full precision.
void print_candidates_json(const std::vector<CandidateRow>& rows);

}  // namespace loopfarm::cli
