// The command line's output conventions: --format and --json parsed through
// CLI11, records rendered as json, csv and markdown (checked against
// nlohmann's own parser and against RFC 4180 quoting by hand), one output
// at most on standard output, and output files that refuse devices and
// follow links to regular files.
#include "output_format.hpp"

#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "cli_support.hpp"

namespace loopfarm::cli {
namespace {

using nlohmann::ordered_json;

// What `write` prints into a FILE*, as a string.
template <typename Write>
std::string written(Write write) {
  std::FILE* file = std::tmpfile();
  write(file);
  std::fflush(file);
  std::rewind(file);
  std::string text;
  char buffer[4096];
  for (size_t got; (got = std::fread(buffer, 1, sizeof buffer, file)) > 0;) text.append(buffer, got);
  std::fclose(file);
  return text;
}

std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

ordered_json sample_record() {
  ordered_json record;
  record["id"] = 7;
  record["family"] = "bennett";
  record["E_mean"] = 0.1;
  record["verified"] = true;
  record["note"] = "a, \"quoted\" note";
  record["range"] = nullptr;
  record["geometry"] = {{"a", {2.0, 4.0}}, {"alpha_deg", {30.5, -90.0}}};
  record["circuits"] = ordered_json::array({{{"end", "closed"}}});
  return record;
}

TEST(OutputFormat, CsvCellsQuoteAsRfc4180AndKeepEveryDigit) {
  EXPECT_EQ(csv_cell(ordered_json(0.1)), "0.10000000000000001");  // %.17g reads back exactly
  EXPECT_EQ(std::stod(csv_cell(ordered_json(1.0 / 3.0))), 1.0 / 3.0);
  EXPECT_EQ(csv_cell(ordered_json(42)), "42");
  EXPECT_EQ(csv_cell(ordered_json(true)), "1");
  EXPECT_EQ(csv_cell(ordered_json(false)), "0");
  EXPECT_EQ(csv_cell(ordered_json(nullptr)), "");
  EXPECT_EQ(csv_cell(ordered_json("plain")), "plain");
  EXPECT_EQ(csv_cell(ordered_json("a,b")), "\"a,b\"");
  EXPECT_EQ(csv_cell(ordered_json("say \"hi\"")), "\"say \"\"hi\"\"\"");
  EXPECT_EQ(csv_cell(ordered_json("two\nlines")), "\"two\nlines\"");
  EXPECT_EQ(csv_cell(ordered_json::array({1, 2.5, nullptr})), "1;2.5;");
  // Deeper structure: compact JSON, quoted since it holds commas.
  EXPECT_EQ(csv_cell(ordered_json::array({{{"a", 1}, {"b", 2}}})), "\"[{\"\"a\"\":1,\"\"b\"\":2}]\"");
  EXPECT_EQ(markdown_cell(ordered_json("x|y")), "x\\|y");
  EXPECT_EQ(markdown_cell(ordered_json(true)), "yes");
}

TEST(OutputFormat, FlattenNamesNestedFieldsWithDots) {
  const auto fields = flatten(sample_record());
  std::vector<std::string> names;
  for (const auto& [name, value] : fields) names.push_back(name);
  EXPECT_EQ(names, (std::vector<std::string>{"id", "family", "E_mean", "verified", "note", "range", "geometry.a",
                                             "geometry.alpha_deg", "circuits"}));
}

TEST(OutputFormat, RecordAsJsonParsesBackEqual) {
  const ordered_json record = sample_record();
  const std::string text = written([&](std::FILE* f) { write_record(f, record, OutputFormat::json); });
  EXPECT_EQ(lines_of(text).size(), 1u);
  EXPECT_EQ(ordered_json::parse(text), record);
}

TEST(OutputFormat, RecordAsCsvIsAHeaderAndOneRow) {
  const std::string text = written([&](std::FILE* f) { write_record(f, sample_record(), OutputFormat::csv); });
  const std::vector<std::string> lines = lines_of(text);
  ASSERT_EQ(lines.size(), 2u);
  EXPECT_EQ(lines[0], "id,family,E_mean,verified,note,range,geometry.a,geometry.alpha_deg,circuits");
  EXPECT_EQ(
      lines[1],
      "7,bennett,0.10000000000000001,1,\"a, \"\"quoted\"\" note\",,2;4,30.5;-90,\"[{\"\"end\"\":\"\"closed\"\"}]\"");
}

TEST(OutputFormat, RecordAsMarkdownIsAFieldValueTable) {
  const std::string text = written([&](std::FILE* f) { write_record(f, sample_record(), OutputFormat::markdown); });
  const std::vector<std::string> lines = lines_of(text);
  ASSERT_EQ(lines.size(), 2u + 9u);
  EXPECT_EQ(lines[0], "| field | value |");
  EXPECT_EQ(lines[1], "|---|---|");
  EXPECT_EQ(lines[2], "| id | 7 |");
  EXPECT_EQ(lines[5], "| verified | yes |");
  EXPECT_EQ(lines[8], "| geometry.a | 2;4 |");
}

TEST(OutputFormat, RecordsShareOneHeaderAndLineUpByName) {
  ordered_json first = {{"a", 1}, {"b", "x"}, {"c", true}};
  ordered_json second = {{"c", false}, {"a", 2}};  // another order, b missing
  const std::vector<ordered_json> records{first, second};
  const std::string csv = written([&](std::FILE* f) { write_records(f, records, OutputFormat::csv); });
  EXPECT_EQ(csv, "a,b,c\n1,x,1\n2,,0\n");
  const std::string markdown = written([&](std::FILE* f) { write_records(f, records, OutputFormat::markdown); });
  EXPECT_EQ(markdown, "| a | b | c |\n|---|---|---|\n| 1 | x | yes |\n| 2 |  | no |\n");
  const std::string json = written([&](std::FILE* f) { write_records(f, records, OutputFormat::json); });
  EXPECT_EQ(lines_of(json).size(), 4u);  // [, a record a line, ]
  EXPECT_EQ(ordered_json::parse(json), ordered_json(records));
  EXPECT_EQ(written([](std::FILE* f) { write_records(f, {}, OutputFormat::json); }), "[]\n");
}

TEST(OutputFormat, RecordStreamWritesTheHeaderOnce) {
  const std::string csv = written([](std::FILE* f) {
    RecordStream stream(f, OutputFormat::csv);
    for (int i = 0; i < 3; ++i) stream.write({{"index", i}, {"zero", i == 1}});
  });
  EXPECT_EQ(csv, "index,zero\n0,0\n1,1\n2,0\n");
  const std::string json = written([](std::FILE* f) {
    RecordStream stream(f, OutputFormat::json);
    for (int i = 0; i < 2; ++i) stream.write({{"index", i}});
  });
  EXPECT_EQ(json, "{\"index\":0}\n{\"index\":1}\n");  // JSON Lines
}

// Parses `args` (without the program name) with a --format option of `allowed`.
FormatChoice parsed(const std::vector<std::string>& args, const std::vector<OutputFormat>& allowed) {
  CLI::App app;
  FormatChoice choice;
  add_format_option(app, choice, allowed, "print as");
  std::vector<std::string> reversed(args.rbegin(), args.rend());
  app.parse(reversed);
  return choice;
}

TEST(OutputFormat, FormatOptionTakesItsNamesTheTableAliasAndJson) {
  const std::vector<OutputFormat> all{OutputFormat::text, OutputFormat::json, OutputFormat::csv,
                                      OutputFormat::markdown};
  EXPECT_EQ(parsed({}, all).format, OutputFormat::text);
  EXPECT_FALSE(parsed({}, all).given);
  EXPECT_EQ(parsed({"--format", "csv"}, all).format, OutputFormat::csv);
  EXPECT_TRUE(parsed({"--format", "csv"}, all).given);
  EXPECT_EQ(parsed({"--format", "markdown"}, all).format, OutputFormat::markdown);
  EXPECT_EQ(parsed({"--format", "table"}, all).format, OutputFormat::text);
  EXPECT_EQ(parsed({"--json"}, all).format, OutputFormat::json);
  EXPECT_TRUE(parsed({"--json"}, all).given);
  EXPECT_THROW(parsed({"--format", "xml"}, all), CLI::ValidationError);
  EXPECT_THROW(parsed({"--format", "json", "--json"}, all), CLI::ExcludesError);
  const std::vector<OutputFormat> text_and_json{OutputFormat::text, OutputFormat::json};
  EXPECT_THROW(parsed({"--format", "csv"}, text_and_json), CLI::ValidationError);
  // Without json among the choices there is no --json.
  EXPECT_THROW(parsed({"--json"}, {OutputFormat::text, OutputFormat::csv}), CLI::ExtrasError);
}

TEST(OutputFormat, AtMostOneOutputTakesStandardOutput) {
  FormatChoice text;
  EXPECT_FALSE(file_takes_standard_output({{"--csv", "a.csv"}, {"--plot", ""}}, text));
  EXPECT_TRUE(file_takes_standard_output({{"--csv", "-"}, {"--plot", "p.png"}}, text));
  EXPECT_THROW(file_takes_standard_output({{"--csv", "-"}, {"--plot", "-"}}, text), UsageError);
  FormatChoice json{OutputFormat::json, true};
  EXPECT_FALSE(file_takes_standard_output({{"--csv", "a.csv"}}, json));
  try {
    file_takes_standard_output({{"--csv", "-"}}, json);
    FAIL() << "--csv - with --format json was accepted";
  } catch (const UsageError& error) {
    EXPECT_EQ(std::string(error.what()).rfind("--csv: ", 0), 0u) << error.what();
  }
}

class PendingOutputTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() / ("loopfarm-output-" + std::to_string(::getpid()) + "-" +
                                                     ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::filesystem::path dir_;
};

TEST_F(PendingOutputTest, RefusesDevicesAndPipes) {
  for (const char* device : {"/dev/null", "/dev/stdout"}) {
    if (!std::filesystem::exists(device)) continue;
    try {
      PendingOutput output(device, "--csv");
      FAIL() << device << " was accepted";
    } catch (const UsageError& error) {
      EXPECT_NE(std::string(error.what()).find("not a regular file"), std::string::npos) << error.what();
    }
  }
  const std::filesystem::path fifo = dir_ / "fifo";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  EXPECT_THROW(PendingOutput(fifo, "--csv"), UsageError);
  EXPECT_TRUE(std::filesystem::is_fifo(fifo));
  EXPECT_TRUE(std::filesystem::exists("/dev/null"));
}

TEST_F(PendingOutputTest, FollowsALinkToARegularFile) {
  const std::filesystem::path file = dir_ / "data.csv";
  const std::filesystem::path link = dir_ / "link.csv";
  std::ofstream(file) << "old\n";
  std::filesystem::create_symlink(file, link);
  {
    PendingOutput output(link, "--csv");
    std::fputs("new\n", output.stream());
    output.commit();
  }
  EXPECT_TRUE(std::filesystem::is_symlink(link));
  std::ifstream in(file);
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line, "new");
}

TEST_F(PendingOutputTest, DashGoesToStandardOutputOnlyWhenCommitted) {
  ::testing::internal::CaptureStdout();
  {
    PendingOutput output("-", "--csv");
    EXPECT_TRUE(output.to_standard_output());
    std::fputs("never shown\n", output.stream());
    // Not committed: a command that fails prints nothing.
  }
  {
    PendingOutput output("-", "--csv");
    std::fputs("a,b\n1,2\n", output.stream());
    output.commit();
  }
  std::fflush(stdout);
  EXPECT_EQ(::testing::internal::GetCapturedStdout(), "a,b\n1,2\n");
}

}  // namespace
}  // namespace loopfarm::cli
