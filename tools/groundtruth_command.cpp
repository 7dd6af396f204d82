#include "groundtruth_command.hpp"

#include <array>
#include <cmath>
#include <cstdio>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "candidate_output.hpp"
#include "cli_support.hpp"
#include "loopfarm/study/ground_truth.hpp"
#include "output_format.hpp"

namespace loopfarm::cli {
namespace {

constexpr double kDegreesPerRadian = 180.0 / 3.14159265358979323846;
constexpr long long kMaxCases = 1000000;  // per family and of generic loops (GroundTruthOptions)

struct GroundTruthArguments {
  std::string seed = "1";
  std::string per_family = "8";
  std::string generic = "8";
  std::string perturbations = "1e-2,1e-3,1e-4,1e-5,1e-6,1e-7,1e-8";
  FormatChoice format;
  std::string csv;
  std::string out;  // replaced by --csv; refused with a message that says so
};

long long count_option(const std::string& text, const std::string& flag) {
  const long long value = parse_integer(text, flag);
  if (value < 0 || value > kMaxCases) {
    throw UsageError(flag, "got " + std::to_string(value) + "; must be in [0, " + std::to_string(kMaxCases) + "]");
  }
  return value;
}

// The options, every flag checked here so that a message names its flag;
// GroundTruthOptions::validate stays the library's own check.
GroundTruthOptions read_options(const GroundTruthArguments& args) {
  GroundTruthOptions options;
  const long long seed = parse_integer(args.seed, "--seed");
  if (seed < 0) throw UsageError("--seed", "got " + std::to_string(seed) + "; must be >= 0");
  options.seed = static_cast<std::uint64_t>(seed);
  options.cases_per_family = static_cast<int>(count_option(args.per_family, "--per-family"));
  options.generic_loops = static_cast<int>(count_option(args.generic, "--generic"));
  options.relative_perturbations.clear();
  if (args.perturbations != "none") {
    const std::vector<double> sizes = parse_number_list(args.perturbations, "--perturbations");
    std::set<double> seen;
    for (size_t i = 0; i < sizes.size(); ++i) {
      const std::string element = "element " + std::to_string(i + 1) + " of " + quote_text(args.perturbations);
      if (!(sizes[i] > 0.0 && sizes[i] < 1.0)) {
        throw UsageError("--perturbations", element + " is " + format_double(sizes[i]) + ": must be in (0, 1)");
      }
      if (!seen.insert(sizes[i]).second) {
        throw UsageError("--perturbations", element + " is " + format_double(sizes[i]) + ": given twice");
      }
    }
    options.relative_perturbations = sizes;
  }
  try {
    options.validate();
  } catch (const std::invalid_argument& error) {
    // Two sizes that agree to the 7 digits an id carries.
    throw UsageError("--perturbations", error.what());
  }
  return options;
}

// The case's own columns, the same in every format: null for a case that is
// not a perturbation.
nlohmann::ordered_json case_fields(const GroundTruthCase& c) {
  nlohmann::ordered_json f;
  f["id"] = c.id;
  f["family"] = to_string(c.family);
  f["setup"] = to_string(c.setup);
  f["movable"] = c.movable;
  f["full_turn"] = c.full_turn;
  const bool perturbed = !c.parent.empty();
  f["parent"] = perturbed ? nlohmann::ordered_json(c.parent) : nullptr;
  f["perturbed_parameter"] = perturbed ? nlohmann::ordered_json(c.perturbed_parameter) : nullptr;
  f["relative_perturbation"] = perturbed ? nlohmann::ordered_json(c.relative_perturbation) : nullptr;
  f["pose_residual"] = c.pose_residual;
  return f;
}

// For tables (csv, markdown): the geometry and pose as columns a1..an,
// alpha1_deg.., d1.., theta1_deg...
nlohmann::ordered_json table_record(const GroundTruthCase& c) {
  nlohmann::ordered_json f = case_fields(c);
  struct Kind {
    const char* name;
    const JointVector* values;
    double factor;
  };
  const Kind kinds[] = {{"a%d", &c.geometry.a, 1.0},
                        {"alpha%d_deg", &c.geometry.alpha, kDegreesPerRadian},
                        {"d%d", &c.geometry.d, 1.0},
                        {"theta%d_deg", &c.pose, kDegreesPerRadian}};
  for (const Kind& kind : kinds) {
    for (int i = 0; i < c.geometry.joints(); ++i) {
      char name[24];
      std::snprintf(name, sizeof name, kind.name, i + 1);
      f[name] = (*kind.values)[i] * kind.factor;
    }
  }
  return f;
}

// For JSON: the geometry as an object of arrays and the pose as an array.
nlohmann::ordered_json json_record(const GroundTruthCase& c) {
  nlohmann::ordered_json f = case_fields(c);
  f["geometry"] = geometry_json(c.geometry);
  f["theta_deg"] = degrees_json(c.pose);
  return f;
}

// --format text: what the set holds, per family and setup.
void print_counts(const std::vector<GroundTruthCase>& cases) {
  std::map<std::pair<std::string, std::string>, std::array<int, 2>> counts;  // [rigid, movable]
  for (const GroundTruthCase& c : cases) ++counts[{to_string(c.family), to_string(c.setup)}][c.movable ? 1 : 0];
  int movable = 0;
  for (const GroundTruthCase& c : cases) movable += c.movable ? 1 : 0;
  std::printf("ground truth: %zu cases, %d movable, %zu rigid\n", cases.size(), movable,
              cases.size() - static_cast<size_t>(movable));
  std::printf("  %-14s %-14s %8s %8s\n", "family", "setup", "movable", "rigid");
  for (const auto& [key, count] : counts) {
    std::printf("  %-14s %-14s %8d %8d\n", key.first.c_str(), key.second.c_str(), count[1], count[0]);
  }
  std::printf("(--format csv, json or markdown prints every case; --csv FILE writes them as CSV)\n");
}

int run_groundtruth(const GroundTruthArguments& args) {
  if (!args.out.empty()) {
    throw UsageError("--out", "was replaced: --csv FILE writes the CSV file, --format json prints JSON");
  }
  const GroundTruthOptions options = read_options(args);
  const bool file_on_stdout = file_takes_standard_output({{"--csv", args.csv}}, args.format);
  // Opened before the work: an unwritable target fails at once.
  std::optional<PendingOutput> csv;
  if (!args.csv.empty()) csv.emplace(args.csv, "--csv");

  const std::vector<GroundTruthCase> cases = generate_ground_truth(options);
  std::vector<nlohmann::ordered_json> table;
  for (const GroundTruthCase& c : cases) table.push_back(table_record(c));
  if (csv) {
    write_records(csv->stream(), table, OutputFormat::csv);
    csv->commit();
    if (!file_on_stdout) {
      int movable = 0;
      for (const GroundTruthCase& c : cases) movable += c.movable ? 1 : 0;
      std::fprintf(stderr, "loopfarm groundtruth: wrote %zu cases (%d movable, %zu rigid) to %s\n", cases.size(),
                   movable, cases.size() - static_cast<size_t>(movable), args.csv.c_str());
    }
  }
  if (file_on_stdout) return kExitSuccess;
  switch (args.format.format) {
    case OutputFormat::text:
      if (!csv) print_counts(cases);
      break;
    case OutputFormat::json: {
      std::vector<nlohmann::ordered_json> records;
      for (const GroundTruthCase& c : cases) records.push_back(json_record(c));
      write_records(stdout, records, OutputFormat::json);
      break;
    }
    case OutputFormat::csv:
    case OutputFormat::markdown:
      write_records(stdout, table, args.format.format);
      break;
  }
  return kExitSuccess;
}

}  // namespace

Subcommand add_groundtruth_command(CLI::App& parent) {
  auto args = std::make_shared<GroundTruthArguments>();
  CLI::App* app = parent.add_subcommand(
      "groundtruth",
      "Write the ground-truth set of 4R loops: known movable ones (Bennett in both setups, planar cranks, spherical, "
      "trivial coaxial) with closed poses, and known rigid ones (each movable one perturbed in one parameter, and "
      "random loops), labelled. docs/quality/ground-truth.md describes it.");
  app->footer(
      "Examples:\n"
      "  loopfarm groundtruth --csv ground-truth.csv\n"
      "  loopfarm groundtruth --seed 7 --per-family 32 --generic 64 --format json > gt.json\n"
      "  loopfarm groundtruth --per-family 2 --perturbations 1e-3,1e-6 --generic 0 --format markdown\n"
      "The same options always give the same set, bit for bit.\n"
      "Exit codes: 0 done, 1 failure, 2 bad input.\n");
  app->add_option("--seed", args->seed, "seed of the random draws (>= 0)")->type_name("S")->capture_default_str();
  app->add_option("--per-family", args->per_family,
                  "movable cases per family (Bennett: per setup; planar, spherical, trivial)")
      ->type_name("N")
      ->capture_default_str();
  app->add_option("--generic", args->generic, "generic random (rigid) loops")->type_name("N")->capture_default_str();
  app->add_option("--perturbations", args->perturbations,
                  "relative sizes each movable case is perturbed by, each in (0, 1), or none")
      ->type_name("LIST")
      ->capture_default_str();
  add_format_option(*app, args->format,
                    {OutputFormat::text, OutputFormat::csv, OutputFormat::json, OutputFormat::markdown},
                    "print the set (text: its counts; the others: every case) as");
  app->add_option("--csv", args->csv, "write every case to FILE as CSV, whole or not at all ('-': stdout)")
      ->type_name("FILE");
  app->add_option("--out", args->out, "replaced by --csv FILE")->group("");
  return {app, [args] { return run_groundtruth(*args); }};
}

}  // namespace loopfarm::cli
