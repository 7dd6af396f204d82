// loopfarm report DB: the zero-minimum cases of a results database, sorted by
// energy from zero upwards (the paper's future-work plan), with family, key
// parameters in degrees and residuals; a summary with counts and the
// histogram of all minima; PNG charts. Read-only: it works while a run is
// writing (WAL) and never changes the file. A damaged file is refused (exit
// 2), not listed from whatever its pages happen to hold.
//
// Here: the command's arguments, their checks and the dispatch to the
// outputs, which live in candidate_list.hpp (the table, Markdown, CSV, JSON),
// candidate_detail.hpp (--candidate), report_summary.hpp (--summary),
// atlas.hpp (--atlas) and html_atlas.hpp (--html); the --plot charts; and the
// classes of stored bond fingerprints (--by-fingerprint).
#include "report_command.hpp"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "atlas.hpp"
#include "candidate_detail.hpp"
#include "candidate_display.hpp"
#include "candidate_list.hpp"
#include "cli_support.hpp"
#include "html_atlas.hpp"
#include "loopfarm/core/assembly.hpp"
#include "loopfarm/core/cycle.hpp"
#include "loopfarm/farm/candidate_pose.hpp"
#include "loopfarm/farm/results_database.hpp"
#include "loopfarm/search/classify.hpp"
#include "output_format.hpp"
#include "plot.hpp"
#include "report_summary.hpp"

namespace loopfarm::cli {
namespace {

// The most rows the text table lists without --limit.
constexpr long long kTableDefaultLimit = 50;
// --family's name for every family.
constexpr const char* kEveryFamily = "all";
// The family --by-fingerprint groups without --family: the loops no known
// family names, which the fingerprints are for.
constexpr const char* kFingerprintFamily = "unclassified";
// --candidate's pose: joint 1 at 90 deg unless --input-deg says otherwise,
// away from the folded poses (every link on one line) a Bennett loop passes
// at 0 and 180 deg, which draw as a collapsed linkage.
constexpr double kDefaultInputDeg = 90.0;

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
  bool by_fingerprint = false;
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
    print_candidates_csv(rows);
  } else if (args.format.format == OutputFormat::json) {
    print_candidates_json(rows);
  } else if (args.format.format == OutputFormat::markdown) {
    print_candidates_markdown(rows);
  } else {
    print_candidate_table(rows, args.wide);
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

// --- the classes of stored bond fingerprints ---------------------------------------

// "not measured", "none" (measured: the stored geometry does not move) or the fingerprint.
std::string fingerprint_text(const std::optional<std::string>& fingerprint) {
  if (!fingerprint) return "(not measured)";
  return fingerprint->empty() ? "(none: the stored geometry does not move)" : *fingerprint;
}

void list_fingerprint_classes(const ResultsDatabase& db, const ReportArguments& args) {
  CandidateFilter filter;
  filter.family = args.family;
  if (!args.max_energy.empty()) filter.max_energy = parse_number(args.max_energy, "--max-energy");
  filter.first_run = run_filter(args);
  const std::vector<FingerprintClass> classes = db.fingerprint_classes(filter);
  const bool table = args.format.format == OutputFormat::text;
  const long long limit = !args.limit.empty() ? parse_integer(args.limit, "--limit") : (table ? kTableDefaultLimit : 0);
  const size_t shown_classes = limit > 0 ? std::min(classes.size(), static_cast<size_t>(limit)) : classes.size();
  if (!table) {
    std::vector<nlohmann::ordered_json> records;
    for (size_t k = 0; k < shown_classes; ++k) {
      const FingerprintClass& c = classes[k];
      nlohmann::ordered_json r;
      r["fingerprint"] = c.fingerprint ? nlohmann::ordered_json(*c.fingerprint) : nlohmann::ordered_json(nullptr);
      r["candidates"] = c.candidates;
      r["hits"] = c.hits;
      r["representative"] = c.representative;
      r["family"] = c.family;
      r["local_dimension"] =
          c.local_dimension >= 0 ? nlohmann::ordered_json(c.local_dimension) : nlohmann::ordered_json(nullptr);
      r["free_parameters"] = c.free_parameters;
      r["E_mean"] = std::isfinite(c.E_mean) ? nlohmann::ordered_json(c.E_mean) : nlohmann::ordered_json(nullptr);
      records.push_back(std::move(r));
    }
    write_records(stdout, records, args.format.format);
    return;
  }
  const std::string selection = args.family.empty() ? "every candidate" : "the " + args.family + " candidates";
  std::int64_t total = 0, measured = 0;
  for (const FingerprintClass& c : classes) {
    total += c.candidates;
    if (c.fingerprint) measured += c.candidates;
  }
  std::printf("bond fingerprints of %s (%s, %s measured)\n", selection.c_str(), grouped(total).c_str(),
              grouped(measured).c_str());
  if (classes.empty()) {
    std::printf("(no candidates match)\n");
    return;
  }
  std::vector<TextColumn> columns = {{"candidates", {}}, {"hits", {}}, {"id", {}}};
  if (args.family.empty()) columns.push_back({"family", {}});
  columns.push_back({"dim", {}});
  columns.push_back({"fingerprint (the table of bidegrees, docs/guide/bonds.md)", {}});
  for (size_t k = 0; k < shown_classes; ++k) {
    const FingerprintClass& c = classes[k];
    size_t i = 0;
    columns[i++].cells.push_back(grouped(c.candidates));
    columns[i++].cells.push_back(grouped(c.hits));
    columns[i++].cells.push_back(std::to_string(c.representative));
    if (args.family.empty()) columns[i++].cells.push_back(c.family);
    columns[i++].cells.push_back(dimension_of(c.local_dimension, c.free_parameters));
    columns[i++].cells.push_back(fingerprint_text(c.fingerprint));
  }
  print_columns(columns, 0);
  if (shown_classes < classes.size()) {
    std::printf("showing %s of %s classes (use --limit 0 for all)\n", grouped(shown_classes).c_str(),
                grouped(classes.size()).c_str());
  }
  if (measured < total) {
    std::printf("%s not measured: loopfarm bonds %s --store%s measures and stores their fingerprints\n",
                count_of(total - measured, "candidate").c_str(), db.path().c_str(),
                args.family == kFingerprintFamily ? ""
                : args.family.empty()             ? " --family all"
                                                  : (" --family " + args.family).c_str());
  }
}

int run_report(const ReportArguments& args_given) {
  // --family all is every family, as no --family is, except for
  // --by-fingerprint, which groups the unclassified candidates unless told.
  ReportArguments args = args_given;
  if (args.by_fingerprint && args.family.empty()) args.family = kFingerprintFamily;
  if (args.family == kEveryFamily) args.family.clear();
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
      throw UsageError("--family",
                       "got " + quote_text(args.family) + "; expected one of " + family_names() + ", or all");
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
    // A family named must be there; --by-fingerprint's own default need not.
    if (!args.family.empty() && !args_given.family.empty()) check_family_present(*db, args.family);
    if (!args.candidate.empty()) {
      show_candidate(*db, args);
    } else if (!args.atlas.empty()) {
      write_atlas(gnuplot, read_candidates(*db, args, 0), run_thresholds(*db), atlas_header(*db, args), atlas_dir);
    } else if (html) {
      write_html_atlas(*db, {args.family, run, args.max_energy}, read_candidates(*db, args, 0), *html);
      html->commit();
      if (!html->to_standard_output()) std::fprintf(stderr, "loopfarm report: wrote %s\n", args.html.c_str());
    } else if (args.by_fingerprint) {
      list_fingerprint_classes(*db, args);
    } else if (args.summary) {
      const SummaryData summary = read_summary(*db, run);
      if (args.format.format == OutputFormat::json) {
        print_summary_json(*db, summary, run);
      } else if (args.format.format == OutputFormat::markdown) {
        print_summary_markdown(*db, summary);
      } else {
        print_summary_text(*db, summary);
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
      "  loopfarm report generic-6r.sqlite --by-fingerprint   # unclassified loops by stored bond fingerprint\n"
      "Order: unclassified candidates (possible new families) first, then by E_mean from zero upwards, ties by id.\n"
      "The table fits 120 columns (--wide: every column) and prints geometry round-off as 0 (|x| < 1e-9 L for\n"
      "lengths, L the loop's length scale; |x| < 1e-9 rad for angles); csv and json keep every stored digit.\n"
      "Read-only; works while a run is writing.\n"
      "Exit codes: 0 done, 1 failure (gnuplot), 2 bad input (options; a run, family or candidate the database\n"
      "does not hold; a file that is not a loopfarm database or is damaged: checked with PRAGMA quick_check,\n"
      "about 2 s per million starts; the file is never changed).\n");
  app->add_option("DB", args->database, "results database (SQLite) written by loopfarm run")->required();
  CLI::Option* family =
      app->add_option("--family", args->family, "only this family (all: every family): " + family_names());
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
  CLI::Option* by_fingerprint = app->add_flag(
      "--by-fingerprint", args->by_fingerprint,
      "one row per bond fingerprint stored (loopfarm bonds DB --store) among the unclassified candidates (or "
      "--family's; all: every family): fingerprint, candidates, hits, a representative (the first in the list's "
      "order) and its local dimension; --limit: at most this many classes");
  by_fingerprint->excludes(candidate)->excludes(summary)->excludes(atlas)->excludes(html)->excludes(plot)->excludes(
      "--wide");
  return {app, [args] { return run_report(*args); }};
}

}  // namespace loopfarm::cli
