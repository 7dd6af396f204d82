#include "groundtruth_command.hpp"

#include <cmath>
#include <cstdio>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "candidate_output.hpp"
#include "cli_support.hpp"
#include "loopfarm/study/ground_truth.hpp"

namespace loopfarm::cli {
namespace {

constexpr double kDegreesPerRadian = 180.0 / 3.14159265358979323846;
constexpr long long kMaxCases = 1000000;  // per family and of generic loops (GroundTruthOptions)

struct GroundTruthArguments {
  std::string seed = "1";
  std::string per_family = "8";
  std::string generic = "8";
  std::string perturbations = "1e-2,1e-3,1e-4,1e-5,1e-6,1e-7,1e-8";
  std::string format = "csv";
  std::string out;
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

// One column: its name, its CSV text and its JSON text.
struct Field {
  std::string name;
  std::string csv;
  std::string json;
};

std::vector<Field> fields(const GroundTruthCase& c) {
  std::vector<Field> f;
  auto text = [&](const std::string& name, const std::string& value) {
    // Ids, families and parameter names never hold commas or quotes.
    f.push_back({name, value, json_string(value)});
  };
  auto flag = [&](const std::string& name, bool value) {
    f.push_back({name, value ? "1" : "0", value ? "true" : "false"});
  };
  auto number = [&](const std::string& name, double value) {
    f.push_back({name, std::isfinite(value) ? format_double(value) : "", json_number(value)});
  };
  text("id", c.id);
  text("family", to_string(c.family));
  text("setup", to_string(c.setup));
  flag("movable", c.movable);
  flag("full_turn", c.full_turn);
  // Empty (CSV) or null (JSON) for a case that is not a perturbation.
  const bool perturbed = !c.parent.empty();
  f.push_back({"parent", c.parent, perturbed ? json_string(c.parent) : "null"});
  f.push_back({"perturbed_parameter", c.perturbed_parameter, perturbed ? json_string(c.perturbed_parameter) : "null"});
  f.push_back({"relative_perturbation", perturbed ? format_double(c.relative_perturbation) : "",
               perturbed ? json_number(c.relative_perturbation) : "null"});
  number("pose_residual", c.pose_residual);
  return f;
}

// Per-joint columns a1..an, alpha1_deg.., d1.., theta1_deg.. (CSV only; JSON
// has them as arrays).
std::vector<Field> joint_columns(const GroundTruthCase& c) {
  std::vector<Field> f;
  const int n = c.geometry.joints();
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
    for (int i = 0; i < n; ++i) {
      char name[24];
      std::snprintf(name, sizeof name, kind.name, i + 1);
      f.push_back({name, format_double((*kind.values)[i] * kind.factor), ""});
    }
  }
  return f;
}

std::string csv_text(const std::vector<GroundTruthCase>& cases) {
  std::string out;
  // Every case has 4 joints; the header comes from an empty 4R case.
  GroundTruthCase header_case;
  header_case.geometry.a = header_case.geometry.alpha = header_case.geometry.d = header_case.pose =
      JointVector::Zero(4);
  std::vector<Field> header = fields(header_case);
  for (Field& column : joint_columns(header_case)) header.push_back(std::move(column));
  for (size_t i = 0; i < header.size(); ++i) out += (i ? "," : "") + header[i].name;
  out += '\n';
  for (const GroundTruthCase& c : cases) {
    std::vector<Field> row = fields(c);
    for (Field& column : joint_columns(c)) row.push_back(std::move(column));
    for (size_t i = 0; i < row.size(); ++i) out += (i ? "," : "") + row[i].csv;
    out += '\n';
  }
  return out;
}

std::string json_text(const std::vector<GroundTruthCase>& cases) {
  std::string out = "[";
  for (size_t k = 0; k < cases.size(); ++k) {
    const GroundTruthCase& c = cases[k];
    out += k ? ",\n{" : "\n{";
    const std::vector<Field> f = fields(c);
    for (size_t i = 0; i < f.size(); ++i) out += (i ? ",\"" : "\"") + f[i].name + "\":" + f[i].json;
    out += ",\"geometry\":" + geometry_json(c.geometry);
    out += ",\"theta_deg\":[";
    for (int i = 0; i < c.pose.size(); ++i) {
      // Appended piecewise: GCC 12 warns (-Wrestrict, falsely) on "," + string here.
      if (i > 0) out += ',';
      out += json_number(c.pose[i] * kDegreesPerRadian);
    }
    out += "]}";
  }
  out += cases.empty() ? "]\n" : "\n]\n";
  return out;
}

int run_groundtruth(const GroundTruthArguments& args) {
  if (args.format != "csv" && args.format != "json") {
    throw UsageError("--format", "got " + quote_text(args.format) + "; expected csv or json");
  }
  const GroundTruthOptions options = read_options(args);
  // Opened before the work: an unwritable target fails at once.
  std::optional<PendingOutput> output;
  if (!args.out.empty()) output.emplace(args.out, "--out");

  const std::vector<GroundTruthCase> cases = generate_ground_truth(options);
  const std::string text = args.format == "csv" ? csv_text(cases) : json_text(cases);
  if (output) {
    std::fputs(text.c_str(), output->stream());
    output->commit();
    int movable = 0;
    for (const GroundTruthCase& c : cases) movable += c.movable ? 1 : 0;
    std::fprintf(stderr, "loopfarm groundtruth: wrote %zu cases (%d movable, %zu rigid) to %s\n", cases.size(), movable,
                 cases.size() - static_cast<size_t>(movable), args.out.c_str());
  } else {
    std::fputs(text.c_str(), stdout);
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
      "  loopfarm groundtruth --out ground-truth.csv\n"
      "  loopfarm groundtruth --seed 7 --per-family 32 --generic 64 --format json --out gt.json\n"
      "  loopfarm groundtruth --per-family 2 --perturbations 1e-3,1e-6 --generic 0\n"
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
  app->add_option("--format", args->format, "csv or json")->type_name("FMT")->capture_default_str();
  app->add_option("--out", args->out, "write to FILE (atomically) instead of standard output")->type_name("FILE");
  return {app, [args] { return run_groundtruth(*args); }};
}

}  // namespace loopfarm::cli
