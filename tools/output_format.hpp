// What a command prints on standard output, chosen with --format (text,
// json, csv or markdown; --json is kept as the alias of --format json), and
// the writers that turn one JSON record, or a list of them, into json, csv or
// markdown, so that every command renders its data the same way. Text is each
// command's own readable summary.
#pragma once

#include <cstdio>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

namespace loopfarm::cli {

enum class OutputFormat { text, json, csv, markdown };

const char* to_string(OutputFormat format);

// The --format a command was given (text unless told), and whether the user
// chose it (so that a file sent to standard output with `-` can refuse a
// format that would share it).
struct FormatChoice {
  OutputFormat format = OutputFormat::text;
  bool given = false;
};

// Adds --format NAME, checked against `allowed` by CLI11 (a name outside it is
// a usage error that lists them), and --json as its alias for --format json
// (when json is allowed). "table" is accepted as another name of text.
// `what` ends the help line: "print the summary as".
void add_format_option(CLI::App& app, FormatChoice& choice, const std::vector<OutputFormat>& allowed,
                       const std::string& what);

// The output options whose value is "-" (pairs of flag and value) send their
// file to standard output in place of the command's summary. Throws
// UsageError when two of them do, or when one does and --format was given too
// (both would share standard output). Returns whether one does.
bool file_takes_standard_output(const std::vector<std::pair<std::string, std::string>>& outputs,
                                const FormatChoice& format);

// One record: json prints it on one line; csv prints a header row and one
// row; markdown prints a two-column table of field and value. Nested objects
// are flattened for csv and markdown with dotted names ("geometry.a"), arrays
// of numbers or strings are joined with ';' in one cell, and anything deeper
// (arrays of objects) is one cell of compact JSON. Not for OutputFormat::text.
void write_record(std::FILE* out, const nlohmann::ordered_json& record, OutputFormat format);

// Records with the same fields (the first record's names the columns): json
// prints one array with a record a line, csv a header and a row each,
// markdown one table.
void write_records(std::FILE* out, const std::vector<nlohmann::ordered_json>& records, OutputFormat format);

// Records written one at a time as they come (loopfarm start --count): json
// prints a line each (JSON Lines), csv a header before the first row,
// markdown a table head before the first row. The first record names the
// columns.
class RecordStream {
 public:
  RecordStream(std::FILE* out, OutputFormat format) : out_(out), format_(format) {}
  void write(const nlohmann::ordered_json& record);

 private:
  std::FILE* out_;
  OutputFormat format_;
  std::vector<std::string> names_;
  bool started_ = false;
};

// One CSV cell for a JSON value: numbers with %.17g (integers as integers),
// booleans as 1 and 0, null as an empty cell, strings quoted when they need it (RFC
// 4180), arrays of scalars joined by ';', anything else as compact JSON.
std::string csv_cell(const nlohmann::ordered_json& value);

// The value as a Markdown table cell: as csv_cell unquoted, booleans as yes
// and no, with '|' escaped.
std::string markdown_cell(const nlohmann::ordered_json& value);

// The record flattened to (dotted name, value) pairs, in order.
std::vector<std::pair<std::string, nlohmann::ordered_json>> flatten(const nlohmann::ordered_json& record);

}  // namespace loopfarm::cli
