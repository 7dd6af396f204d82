#include "output_format.hpp"

#include <algorithm>
#include <string>
#include <utility>

#include "cli_support.hpp"

namespace loopfarm::cli {
namespace {

using nlohmann::ordered_json;

bool is_scalar_array(const ordered_json& value) {
  if (!value.is_array()) return false;
  for (const ordered_json& element : value) {
    if (element.is_structured()) return false;
  }
  return true;
}

// A scalar's text in a cell (unquoted). Booleans are 1 and 0 in CSV (as
// spreadsheets and data frames read them), yes and no in Markdown.
std::string scalar_text(const ordered_json& value, OutputFormat format) {
  if (value.is_null()) return "";
  if (value.is_boolean()) {
    if (format == OutputFormat::markdown) return value.get<bool>() ? "yes" : "no";
    return value.get<bool>() ? "1" : "0";
  }
  if (value.is_number_integer()) return value.dump();
  if (value.is_number_float()) return format_double(value.get<double>());
  if (value.is_string()) return value.get<std::string>();
  return value.dump();
}

std::string plain_cell(const ordered_json& value, OutputFormat format) {
  if (is_scalar_array(value)) {
    std::string text;
    for (size_t i = 0; i < value.size(); ++i) text += (i ? ";" : "") + scalar_text(value[i], format);
    return text;
  }
  if (value.is_structured()) return value.dump();
  return scalar_text(value, format);
}

void flatten_into(const std::string& prefix, const ordered_json& value,
                  std::vector<std::pair<std::string, ordered_json>>& out) {
  if (value.is_object() && !value.empty()) {
    for (const auto& [name, element] : value.items()) {
      flatten_into(prefix.empty() ? name : prefix + "." + name, element, out);
    }
    return;
  }
  out.emplace_back(prefix, value);
}

void put(std::FILE* out, const std::string& text) { std::fwrite(text.data(), 1, text.size(), out); }

std::string csv_line(const std::vector<std::string>& cells) {
  std::string line;
  for (size_t i = 0; i < cells.size(); ++i) line += (i ? "," : "") + cells[i];
  return line + "\n";
}

std::string markdown_line(const std::vector<std::string>& cells) {
  std::string line = "|";
  for (const std::string& cell : cells) line += " " + cell + " |";
  return line + "\n";
}

std::string markdown_rule(size_t columns) {
  std::string line = "|";
  for (size_t i = 0; i < columns; ++i) line += "---|";
  return line + "\n";
}

}  // namespace

const char* to_string(OutputFormat format) {
  switch (format) {
    case OutputFormat::text:
      return "text";
    case OutputFormat::json:
      return "json";
    case OutputFormat::csv:
      return "csv";
    case OutputFormat::markdown:
      return "markdown";
  }
  return "text";
}

void add_format_option(CLI::App& app, FormatChoice& choice, const std::vector<OutputFormat>& allowed,
                       const std::string& what) {
  std::vector<std::string> names;
  bool json = false;
  for (OutputFormat format : allowed) {
    names.emplace_back(to_string(format));
    json = json || format == OutputFormat::json;
  }
  std::string listed;
  for (size_t i = 0; i < names.size(); ++i) listed += (i == 0 ? "" : i + 1 == names.size() ? " or " : ", ") + names[i];
  std::vector<std::string> accepted = names;
  if (std::find(names.begin(), names.end(), "text") != names.end()) accepted.emplace_back("table");

  FormatChoice* target = &choice;
  CLI::Option* format =
      app.add_option_function<std::string>(
             "--format",
             [target](const std::string& name) {
               target->given = true;
               target->format = OutputFormat::text;
               for (OutputFormat f : {OutputFormat::json, OutputFormat::csv, OutputFormat::markdown}) {
                 if (name == to_string(f)) target->format = f;
               }
             },
             what + " " + listed + " (default: " + to_string(choice.format) + ")")
          ->type_name("FMT")
          ->check(CLI::IsMember(accepted));
  if (json) {
    app.add_flag_callback(
           "--json",
           [target] {
             target->given = true;
             target->format = OutputFormat::json;
           },
           "the same as --format json")
        ->excludes(format);
  }
}

bool file_takes_standard_output(const std::vector<std::pair<std::string, std::string>>& outputs,
                                const FormatChoice& format) {
  std::string taken_by;
  for (const auto& [flag, path] : outputs) {
    if (!is_standard_output(path)) continue;
    if (!taken_by.empty()) {
      throw UsageError(flag, "'-' (standard output) is already taken by " + taken_by + "; give one of them a file");
    }
    taken_by = flag;
  }
  if (!taken_by.empty() && format.given) {
    throw UsageError(taken_by,
                     std::string("'-' sends the file to standard output in place of the summary, so it cannot "
                                 "go with --format ") +
                         to_string(format.format) + " (or --json); give a file");
  }
  return !taken_by.empty();
}

std::vector<std::pair<std::string, ordered_json>> flatten(const ordered_json& record) {
  std::vector<std::pair<std::string, ordered_json>> out;
  flatten_into("", record, out);
  return out;
}

std::string csv_cell(const ordered_json& value) {
  std::string text = plain_cell(value, OutputFormat::csv);
  if (text.find_first_of(",\"\n\r") == std::string::npos) return text;
  std::string quoted = "\"";
  for (char c : text) {
    if (c == '"') quoted += '"';
    quoted += c;
  }
  return quoted + "\"";
}

std::string markdown_cell(const ordered_json& value) {
  std::string cell;
  for (char c : plain_cell(value, OutputFormat::markdown)) {
    if (c == '|') cell += '\\';
    cell += (c == '\n' || c == '\r') ? ' ' : c;
  }
  return cell;
}

void write_record(std::FILE* out, const ordered_json& record, OutputFormat format) {
  if (format == OutputFormat::json || format == OutputFormat::text) {
    put(out, record.dump() + "\n");
    return;
  }
  const auto fields = flatten(record);
  if (format == OutputFormat::csv) {
    std::vector<std::string> names, values;
    for (const auto& [name, value] : fields) {
      names.push_back(csv_cell(name));
      values.push_back(csv_cell(value));
    }
    put(out, csv_line(names) + csv_line(values));
    return;
  }
  put(out, markdown_line({"field", "value"}) + markdown_rule(2));
  for (const auto& [name, value] : fields) put(out, markdown_line({markdown_cell(name), markdown_cell(value)}));
}

void RecordStream::write(const ordered_json& record) {
  if (format_ == OutputFormat::json || format_ == OutputFormat::text) {
    put(out_, record.dump() + "\n");
    return;
  }
  const auto fields = flatten(record);
  std::string text;
  if (!started_) {
    started_ = true;
    for (const auto& [name, value] : fields) names_.push_back(name);
    if (format_ == OutputFormat::csv) {
      std::vector<std::string> header;
      for (const std::string& name : names_) header.push_back(csv_cell(name));
      text += csv_line(header);
    } else {
      text += markdown_line(names_) + markdown_rule(names_.size());
    }
  }
  // Cells by name, so that a record with its fields in another order (or
  // some missing) still lines up under the header.
  std::vector<std::string> cells(names_.size());
  size_t next = 0;
  for (const auto& [name, value] : fields) {
    size_t at = next < names_.size() && names_[next] == name ? next : names_.size();
    if (at == names_.size()) at = static_cast<size_t>(std::find(names_.begin(), names_.end(), name) - names_.begin());
    if (at == names_.size()) continue;
    cells[at] = format_ == OutputFormat::csv ? csv_cell(value) : markdown_cell(value);
    next = at + 1;
  }
  text += format_ == OutputFormat::csv ? csv_line(cells) : markdown_line(cells);
  put(out_, text);
}

void write_records(std::FILE* out, const std::vector<ordered_json>& records, OutputFormat format) {
  if (format == OutputFormat::json || format == OutputFormat::text) {
    // One array, a record a line: still one JSON value, and greppable.
    std::string text = "[";
    for (size_t i = 0; i < records.size(); ++i) text += (i ? ",\n" : "\n") + records[i].dump();
    put(out, text + (records.empty() ? "]\n" : "\n]\n"));
    return;
  }
  RecordStream stream(out, format);
  for (const ordered_json& record : records) stream.write(record);
}

}  // namespace loopfarm::cli
