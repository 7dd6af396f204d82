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
#include <string>
#include <vector>

#include "atlas.hpp"
#include "cli_support.hpp"
#include "loopfarm/core/assembly.hpp"
#include "loopfarm/core/cycle.hpp"
#include "loopfarm/farm/results_database.hpp"
#include "loopfarm/search/classify.hpp"
#include "plot.hpp"

namespace loopfarm::cli {
namespace {

constexpr double kPi = 3.14159265358979323846;

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
  std::string limit = "50";
  std::string format = "table";
  std::string run;
  std::string plot;
  std::string atlas;
  bool summary = false;
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

std::string list(const std::vector<double>& values, int digits) { return join_significant(values, digits, ","); }

std::string range_text(const CandidateRow& r) {
  return r.full_turn ? "full turn" : "[" + g(r.range_lo_deg, 4) + ", " + g(r.range_hi_deg, 4) + "] deg";
}

std::vector<CandidateRow> read_candidates(const ResultsDatabase& db, const ReportArguments& args, bool every) {
  CandidateFilter filter;
  filter.family = args.family;
  if (!args.max_energy.empty()) filter.max_energy = parse_number(args.max_energy, "--max-energy");
  filter.first_run = run_filter(args);
  filter.limit = every ? -1 : parse_integer(args.limit, "--limit");
  return db.candidates(filter);
}

void print_table(const std::vector<CandidateRow>& rows) {
  // The family column fits the longest name (bricard_plane_symmetric).
  std::printf("%-5s %-23s %-14s %-10s %-6s %-8s %-5s %-10s %-10s %-16s %s\n", "id", "family", "setup", "E_mean", "hits",
              "first", "dim", "rigid_res", "family_res", "input range", "geometry (canonical, L = 1; twists in deg)");
  for (const CandidateRow& r : rows) {
    std::printf("%-5lld %-23s %-14s %-10s %-6lld %-8s %-5s %-10s %-10s %-16s a=%s alpha=%s d=%s\n", r.id,
                r.family.c_str(), r.setup.c_str(), g(r.E_mean).c_str(), r.hits,
                (std::to_string(r.first_run) + ":" + std::to_string(r.first_start)).c_str(),
                (std::to_string(r.local_dimension) + "/" + std::to_string(r.free_parameters)).c_str(),
                g(r.rigid_residual, 2).c_str(), g(r.family_residual, 2).c_str(), range_text(r).c_str(),
                list(r.a, 6).c_str(), list(r.alpha_deg, 6).c_str(), list(r.d, 6).c_str());
  }
  if (rows.empty()) std::printf("(no candidates match)\n");
}

void print_markdown(const std::vector<CandidateRow>& rows) {
  std::printf(
      "| id | family | setup | E_mean | hits | first (run:start) | local dim | rigid residual | family residual "
      "| input range | a | alpha [deg] | d |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  for (const CandidateRow& r : rows) {
    std::printf("| %lld | %s | %s | %s | %lld | %lld:%lld | %d/%d | %s | %s | %s | %s | %s | %s |\n", r.id,
                r.family.c_str(), r.setup.c_str(), g(r.E_mean).c_str(), r.hits, r.first_run, r.first_start,
                r.local_dimension, r.free_parameters, g(r.rigid_residual, 2).c_str(), g(r.family_residual, 2).c_str(),
                range_text(r).c_str(), list(r.a, 6).c_str(), list(r.alpha_deg, 6).c_str(), list(r.d, 6).c_str());
  }
}

// CSV and JSON: every column, full precision; NaN/NULL empty in CSV, null in JSON.
struct Field {
  std::string name;
  std::string csv;
  std::string json;
};

std::vector<Field> fields(const CandidateRow& r, int joints) {
  std::vector<Field> f;
  auto number = [&](const std::string& name, double v) {
    f.push_back({name, std::isfinite(v) ? format_double(v) : "", json_number(v)});
  };
  auto integer = [&](const std::string& name, long long v) {
    f.push_back({name, std::to_string(v), std::to_string(v)});
  };
  auto text = [&](const std::string& name, const std::string& v) {
    std::string quoted = v;
    if (v.find_first_of(",\"\n") != std::string::npos) {
      quoted = "\"";
      for (char ch : v) quoted += ch == '"' ? std::string("\"\"") : std::string(1, ch);
      quoted += "\"";
    }
    f.push_back({name, quoted, json_string(v)});
  };
  integer("candidate_id", r.id);
  text("family", r.family);
  text("setup", r.setup);
  text("detail", r.detail);
  number("E_mean", r.E_mean);
  number("E_max", r.E_max);
  integer("hits", r.hits);
  integer("first_run", r.first_run);
  integer("first_start", r.first_start);
  integer("local_dimension", r.local_dimension);
  integer("free_parameters", r.free_parameters);
  number("rigid_residual", r.rigid_residual);
  number("family_residual", r.family_residual);
  number("bennett_residual", r.bennett_residual);
  number("planar_residual", r.planar_residual);
  number("spherical_residual", r.spherical_residual);
  number("trivial_residual", r.trivial_residual);
  f.push_back({"full_turn", r.full_turn ? "1" : "0", r.full_turn ? "true" : "false"});
  number("range_lo_deg", r.range_lo_deg);
  number("range_hi_deg", r.range_hi_deg);
  integer("joints", r.joints);
  const char* kinds[] = {"a%d", "alpha%d_deg", "d%d"};
  const std::vector<double>* values[] = {&r.a, &r.alpha_deg, &r.d};
  for (int k = 0; k < 3; ++k) {
    for (int i = 0; i < joints; ++i) {
      char name[16];
      std::snprintf(name, sizeof name, kinds[k], i + 1);
      number(name, i < static_cast<int>(values[k]->size()) ? (*values[k])[static_cast<size_t>(i)] : NAN);
    }
  }
  return f;
}

void print_csv(const std::vector<CandidateRow>& rows) {
  int joints = 4;
  for (const CandidateRow& r : rows) joints = std::max(joints, r.joints);
  const std::vector<Field> header = fields(CandidateRow{}, joints);
  for (size_t i = 0; i < header.size(); ++i) std::printf("%s%s", i ? "," : "", header[i].name.c_str());
  std::printf("\n");
  for (const CandidateRow& r : rows) {
    const std::vector<Field> f = fields(r, joints);
    for (size_t i = 0; i < f.size(); ++i) std::printf("%s%s", i ? "," : "", f[i].csv.c_str());
    std::printf("\n");
  }
}

void print_json(const std::vector<CandidateRow>& rows) {
  std::printf("[");
  for (size_t k = 0; k < rows.size(); ++k) {
    const std::vector<Field> f = fields(rows[k], rows[k].joints);
    std::printf("%s\n{", k ? "," : "");
    for (size_t i = 0; i < f.size(); ++i)
      std::printf("%s\"%s\":%s", i ? "," : "", f[i].name.c_str(), f[i].json.c_str());
    std::printf("}");
  }
  std::printf("%s]\n", rows.empty() ? "" : "\n");
}

void print_summary(const ResultsDatabase& db, const ReportArguments& args) {
  std::printf("database %s\n", db.path().c_str());
  std::printf("runs\n");
  for (const RunRow& r : db.runs()) {
    // Where its starts were computed: ranks of the last session, or the databases it was merged from.
    const std::string where = r.merged_inputs > 0 ? "merged from " + std::to_string(r.merged_inputs) + " databases"
                                                  : std::to_string(r.ranks) + " ranks";
    const std::string slice = r.slice ? "  slice " + to_string(*r.slice) : "";
    std::printf("  run %lld  %s  seed %llu%s  %lld/%lld starts  %s  %s  %s .. %s\n", static_cast<long long>(r.run_id),
                r.job_path.c_str(), static_cast<unsigned long long>(r.seed), slice.c_str(),
                static_cast<long long>(r.starts_done), static_cast<long long>(r.starts), r.status.c_str(),
                where.c_str(), r.started_at.c_str(), r.updated_at.c_str());
  }
  const std::optional<std::int64_t> run = run_filter(args);
  const StartCounts c = db.start_counts(run);
  std::printf("starts     %lld, zero minima %lld, verified %lld, mean %.4g s per start, %.4g core-seconds\n",
              static_cast<long long>(c.starts), static_cast<long long>(c.zeros), static_cast<long long>(c.verified),
              c.mean_seconds, c.total_seconds);
  std::printf("by status\n");
  for (const StatusCount& s : db.status_counts(run)) {
    std::printf("  %-18s %lld\n", s.status.c_str(), static_cast<long long>(s.starts));
  }
  std::printf("candidates by family (distinct linkages, starts that found them)\n");
  for (const FamilyCount& f : db.family_counts(run)) {
    std::printf("  %-23s %6lld %8lld\n", f.family.c_str(), static_cast<long long>(f.candidates),
                static_cast<long long>(f.hits));
  }
  const EnergyHistogram h = db.energy_histogram(run);
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

void plot_histogram(const std::filesystem::path& gnuplot, const EnergyHistogram& h, const std::filesystem::path& png) {
  ScratchFile data(".dat");
  for (const auto& [decade, count] : h.decades) {
    std::fprintf(data.stream(), "%d %lld\n", decade, static_cast<long long>(count));
  }
  data.close();
  ScratchFile script(".gp");
  std::fprintf(script.stream(),
               "set terminal pngcairo size 900,500\nset output '%s'\nset title 'log10 of the cycle energy minimum, all "
               "starts'\nset xlabel 'log10(E_mean), E / (k_a L^2)'\nset ylabel 'starts'\nset style fill solid 0.6\n"
               "set boxwidth 0.9\nset grid ytics\nplot '%s' using ($1 + 0.5):2 with boxes notitle\n",
               png.string().c_str(), data.path().string().c_str());
  script.close();
  const std::string command = "\"" + gnuplot.string() + "\" \"" + script.path().string() + "\" 2>/dev/null";
  if (std::system(command.c_str()) != 0 || !std::filesystem::exists(png)) {
    throw EnvironmentError("gnuplot failed to draw " + png.string());
  }
}

void plot_candidates(const std::filesystem::path& gnuplot, const std::vector<CandidateRow>& rows,
                     const std::filesystem::path& dir) {
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
    style.log_scale = true;
    const std::filesystem::path png = dir / ("candidate_" + std::to_string(r.id) + "_cycle.png");
    plot_energy_curve(gnuplot, cycle, style, png);
    std::fprintf(stderr, "loopfarm report: wrote %s (E_mean %s)\n", png.string().c_str(), g(cycle.E_mean).c_str());
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

int run_report(const ReportArguments& args) {
  if (args.format != "table" && args.format != "csv" && args.format != "json" && args.format != "markdown") {
    throw UsageError("--format", "got " + quote_text(args.format) + "; expected table, csv, json or markdown");
  }
  const long long limit = parse_integer(args.limit, "--limit");
  if (limit < 0) throw UsageError("--limit", "got " + args.limit + "; must be >= 0");
  if (!args.max_energy.empty()) (void)parse_number(args.max_energy, "--max-energy");
  if (!args.run.empty()) (void)parse_integer(args.run, "--run");
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
  std::optional<ResultsDatabase> db;
  try {
    db.emplace(ResultsDatabase::open(args.database, DatabaseMode::read));
  } catch (const DatabaseError& error) {
    throw UsageError("DB", error.what());
  }
  try {
    // One read transaction: the summary and the list see the same state even
    // while a run commits.
    const ResultsDatabase::Snapshot snapshot = db->snapshot();
    if (!args.atlas.empty()) {
      write_atlas(gnuplot, read_candidates(*db, args, true), atlas_header(*db, args), atlas_dir);
    } else if (args.summary) {
      print_summary(*db, args);
    } else {
      const std::vector<CandidateRow> rows = read_candidates(*db, args, false);
      if (args.format == "csv") {
        print_csv(rows);
      } else if (args.format == "json") {
        print_json(rows);
      } else if (args.format == "markdown") {
        print_markdown(rows);
      } else {
        print_table(rows);
      }
      if (!args.plot.empty()) {
        plot_candidates(gnuplot,
                        std::vector<CandidateRow>(rows.begin(), rows.begin() + std::min<size_t>(rows.size(), 10)),
                        args.plot);
      }
    }
    if (!args.plot.empty()) {
      const std::filesystem::path png = std::filesystem::path(args.plot) / "minima_histogram.png";
      plot_histogram(gnuplot, db->energy_histogram(run_filter(args)), png);
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
      "  loopfarm report jobs/default.sqlite\n"
      "  loopfarm report jobs/default.sqlite --family bennett --format csv > bennett.csv\n"
      "  loopfarm report jobs/default.sqlite --summary --plot docs/default\n"
      "  loopfarm report jobs/goldberg-5r.sqlite --atlas docs/research/atlas\n"
      "Read-only; works while a run is writing. Unclassified candidates (possible new families) come first.\n"
      "Exit codes: 0 done, 1 failure (gnuplot), 2 bad input (options, a file that is not a loopfarm database or\n"
      "is damaged: checked with PRAGMA quick_check, about 2 s per million starts; the file is never changed).\n");
  app->add_option("DB", args->database, "results database (SQLite) written by loopfarm run")->required();
  app->add_option("--family", args->family, "only this family: " + family_names());
  app->add_option("--max-energy", args->max_energy, "only candidates with E_mean at most this")->type_name("E");
  app->add_option("--limit", args->limit, "at most this many candidates")->type_name("N")->capture_default_str();
  app->add_option("--run", args->run, "only what run ID found first (default: every run)")->type_name("ID");
  app->add_option("--format", args->format, "table, csv, json or markdown")->type_name("FMT")->capture_default_str();
  app->add_flag("--summary", args->summary, "counts per family and status, and the histogram of log10 of all minima");
  app->add_option("--plot", args->plot,
                  "write PNG charts into DIR: the histogram of minima and the cycle energy of the listed candidates "
                  "(at most 10)")
      ->type_name("DIR");
  CLI::Option* atlas =
      app->add_option("--atlas", args->atlas,
                      "write a family atlas into DIR: atlas.md with, per family, the counts, the spread of the "
                      "parameters, the local dimension against the known one, and a representative's cycle-energy "
                      "chart (PNG) and motion (SVG); --family, --run and --max-energy select, --limit does not apply")
          ->type_name("DIR");
  atlas->excludes("--summary")->excludes("--plot")->excludes("--limit")->excludes("--format");
  return {app, [args] { return run_report(*args); }};
}

}  // namespace loopfarm::cli
