// loopfarm report DB: the zero-minimum cases of a results database, sorted by
// energy from zero upwards (the paper's future-work plan), with family, key
// parameters in degrees and residuals; a summary with counts and the
// histogram of all minima; PNG charts. Read-only: it works while a run is
// writing (WAL) and never changes the file. A damaged file is refused (exit
// 2), not listed from whatever its pages happen to hold.
#include "report_command.hpp"

#include <sqlite3.h>
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
#include "loopfarm/search/classify.hpp"
#include "loopfarm/core/cycle.hpp"
#include "loopfarm/farm/results_database.hpp"
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

// An SQLite failure while reading DB: damage the open-time check could not
// see (or that appeared since) is bad input, exit 2, like a file refused at
// open; anything else (out of memory, I/O) is a failure.
[[noreturn]] void throw_read_error(sqlite3* db, const std::string& path) {
  const int rc = sqlite3_errcode(db) & 0xff;
  const std::string message = sqlite3_errmsg(db);
  if (rc == SQLITE_CORRUPT || rc == SQLITE_NOTADB) {
    throw UsageError("DB", "results database " + path + ": damaged (" + message + ")");
  }
  throw EnvironmentError(path + ": " + message);
}

// A prepared statement that finalises itself; errors name the database.
class Query {
 public:
  Query(sqlite3* db, const std::string& path, const std::string& sql) : db_(db), path_(path) {
    if (sqlite3_prepare_v2(db, sql.c_str(), -1, &statement_, nullptr) != SQLITE_OK) throw_read_error(db, path);
  }
  ~Query() { sqlite3_finalize(statement_); }
  Query(const Query&) = delete;
  Query& operator=(const Query&) = delete;

  void bind(int i, double v) { sqlite3_bind_double(statement_, i, v); }
  void bind(int i, long long v) { sqlite3_bind_int64(statement_, i, v); }
  void bind(int i, const std::string& v) { sqlite3_bind_text(statement_, i, v.c_str(), -1, SQLITE_TRANSIENT); }
  bool step() {
    const int rc = sqlite3_step(statement_);
    if (rc == SQLITE_ROW) return true;
    if (rc == SQLITE_DONE) return false;
    throw_read_error(db_, path_);
  }
  bool null(int c) const { return sqlite3_column_type(statement_, c) == SQLITE_NULL; }
  double real(int c) const { return null(c) ? NAN : sqlite3_column_double(statement_, c); }
  long long integer(int c) const { return sqlite3_column_int64(statement_, c); }
  std::string text(int c) const {
    const unsigned char* t = sqlite3_column_text(statement_, c);
    return t ? reinterpret_cast<const char*>(t) : "";
  }

 private:
  sqlite3* db_;
  std::string path_;
  sqlite3_stmt* statement_ = nullptr;
};

std::string g(double v, int digits = 3) { return format_significant(v, digits); }

std::string list(const std::vector<double>& values, int digits) { return join_significant(values, digits, ","); }

std::string range_text(const CandidateRow& r) {
  return r.full_turn ? "full turn" : "[" + g(r.range_lo_deg, 4) + ", " + g(r.range_hi_deg, 4) + "] deg";
}

std::vector<CandidateRow> read_candidates(sqlite3* db, const std::string& path, const ReportArguments& args) {
  std::string sql =
      "SELECT candidate_id, family, setup, detail, E_mean, E_max, hits, first_run, first_start, local_dimension, "
      "free_parameters, rigid_residual, family_residual, bennett_residual, planar_residual, spherical_residual, "
      "trivial_residual, full_turn, range_lo_deg, range_hi_deg, joints";
  for (const char* kind : {"a%d", "alpha%d_deg", "d%d"}) {
    for (int i = 1; i <= 8; ++i) {
      char column[16];
      std::snprintf(column, sizeof column, kind, i);
      sql += std::string(", ") + column;
    }
  }
  sql += " FROM candidates WHERE 1";
  if (!args.family.empty()) sql += " AND family = ?1";
  if (!args.max_energy.empty()) sql += " AND E_mean <= ?2";
  if (!args.run.empty()) sql += " AND first_run = ?3";
  // Unclassified first (a possible new family, or a defect for 4R), then by
  // energy from zero upwards.
  sql += " ORDER BY family <> 'unclassified', E_mean, candidate_id LIMIT ?4";
  Query q(db, path, sql);
  if (!args.family.empty()) q.bind(1, args.family);
  if (!args.max_energy.empty()) q.bind(2, parse_number(args.max_energy, "--max-energy"));
  if (!args.run.empty()) q.bind(3, parse_integer(args.run, "--run"));
  q.bind(4, parse_integer(args.limit, "--limit"));
  std::vector<CandidateRow> rows;
  while (q.step()) {
    CandidateRow r;
    int c = 0;
    r.id = q.integer(c++);
    r.family = q.text(c++);
    r.setup = q.text(c++);
    r.detail = q.text(c++);
    r.E_mean = q.real(c++);
    r.E_max = q.real(c++);
    r.hits = q.integer(c++);
    r.first_run = q.integer(c++);
    r.first_start = q.integer(c++);
    r.local_dimension = static_cast<int>(q.integer(c++));
    r.free_parameters = static_cast<int>(q.integer(c++));
    r.rigid_residual = q.real(c++);
    r.family_residual = q.real(c++);
    r.bennett_residual = q.real(c++);
    r.planar_residual = q.real(c++);
    r.spherical_residual = q.real(c++);
    r.trivial_residual = q.real(c++);
    r.full_turn = q.integer(c++) != 0;
    r.range_lo_deg = q.real(c++);
    r.range_hi_deg = q.real(c++);
    r.joints = static_cast<int>(q.integer(c++));
    for (std::vector<double>* v : {&r.a, &r.alpha_deg, &r.d}) {
      for (int i = 0; i < 8; ++i, ++c) {
        if (i < r.joints) v->push_back(q.real(c));
      }
    }
    rows.push_back(std::move(r));
  }
  return rows;
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
  std::printf("| id | family | setup | E_mean | hits | first (run:start) | local dim | rigid residual | family residual "
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
    for (size_t i = 0; i < f.size(); ++i) std::printf("%s\"%s\":%s", i ? "," : "", f[i].name.c_str(), f[i].json.c_str());
    std::printf("}");
  }
  std::printf("%s]\n", rows.empty() ? "" : "\n");
}

// log10 of every start's E_mean, by decade; exact zeros and NaN counted apart.
struct Histogram {
  std::map<int, long> decades;  // floor(log10 E)
  long zeros = 0;               // E_mean exactly 0
  long missing = 0;             // NULL (could not be evaluated)
};

Histogram energy_histogram(sqlite3* db, const std::string& path, const ReportArguments& args) {
  Histogram h;
  Query q(db, path, std::string("SELECT E_mean FROM starts") + (args.run.empty() ? "" : " WHERE run_id = ?1"));
  if (!args.run.empty()) q.bind(1, parse_integer(args.run, "--run"));
  while (q.step()) {
    const double e = q.real(0);
    if (std::isnan(e)) {
      ++h.missing;
    } else if (e <= 0) {
      ++h.zeros;
    } else {
      ++h.decades[static_cast<int>(std::floor(std::log10(e)))];
    }
  }
  return h;
}

void print_summary(sqlite3* db, const std::string& path, const ReportArguments& args) {
  std::printf("database %s\n", path.c_str());
  {
    Query q(db, path,
            "SELECT run_id, job_path, seed, starts, starts_done, status, ranks, started_at, updated_at FROM runs ORDER BY "
            "run_id");
    std::printf("runs\n");
    while (q.step()) {
      std::printf("  run %lld  %s  seed %lld  %lld/%lld starts  %s  %lld ranks  %s .. %s\n", q.integer(0),
                  q.text(1).c_str(), q.integer(2), q.integer(4), q.integer(3), q.text(5).c_str(), q.integer(6),
                  q.text(7).c_str(), q.text(8).c_str());
    }
  }
  const std::string where = args.run.empty() ? "" : " WHERE run_id = ?1";
  auto bind_run = [&](Query& q) {
    if (!args.run.empty()) q.bind(1, parse_integer(args.run, "--run"));
  };
  {
    Query q(db, path,
            "SELECT COUNT(*), SUM(zero), SUM(verified), AVG(seconds), SUM(seconds) FROM starts" + where);
    bind_run(q);
    q.step();
    std::printf("starts     %lld, zero minima %lld, verified %lld, mean %.4g s per start, %.4g core-seconds\n",
                q.integer(0), q.integer(1), q.integer(2), q.real(3), q.real(4));
  }
  {
    Query q(db, path, "SELECT status, COUNT(*) FROM starts" + where + " GROUP BY status ORDER BY COUNT(*) DESC");
    bind_run(q);
    std::printf("by status\n");
    while (q.step()) std::printf("  %-18s %lld\n", q.text(0).c_str(), q.integer(1));
  }
  {
    Query q(db, path,
            "SELECT family, COUNT(*), SUM(hits) FROM candidates" +
                std::string(args.run.empty() ? "" : " WHERE first_run = ?1") + " GROUP BY family ORDER BY family");
    bind_run(q);
    std::printf("candidates by family (distinct linkages, starts that found them)\n");
    while (q.step()) std::printf("  %-23s %6lld %8lld\n", q.text(0).c_str(), q.integer(1), q.integer(2));
  }
  const Histogram h = energy_histogram(db, path, args);
  long most = 1;
  for (const auto& [decade, count] : h.decades) most = std::max(most, count);
  std::printf("histogram of log10(E_mean) over all starts\n");
  for (const auto& [decade, count] : h.decades) {
    const int width = static_cast<int>(std::lround(50.0 * static_cast<double>(count) / static_cast<double>(most)));
    std::printf("  [%4d, %4d) %7ld %s\n", decade, decade + 1, count, std::string(static_cast<size_t>(width), '#').c_str());
  }
  if (h.zeros) std::printf("  exactly 0   %7ld\n", h.zeros);
  if (h.missing) std::printf("  no value    %7ld (the start could not be evaluated)\n", h.missing);
}

void plot_histogram(const std::filesystem::path& gnuplot, const Histogram& h, const std::filesystem::path& png) {
  ScratchFile data(".dat");
  for (const auto& [decade, count] : h.decades) std::fprintf(data.stream(), "%d %ld\n", decade, count);
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
    const LoopGeometry geometry =
        LoopGeometry::from_degrees(std::span<const double>(r.a), std::span<const double>(r.alpha_deg),
                                   std::span<const double>(r.d));
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
std::string atlas_header(sqlite3* db, const std::string& path, const ReportArguments& args) {
  std::string out = "Database `" + path + "`";
  if (!args.family.empty()) out += ", family " + args.family;
  if (!args.run.empty()) out += ", candidates run " + args.run + " found first";
  if (!args.max_energy.empty()) out += ", E_mean <= " + args.max_energy;
  out += ". Runs:\n\n";
  Query q(db, path, "SELECT run_id, job_path, seed, starts_done, starts, status, joints FROM runs ORDER BY run_id");
  while (q.step()) {
    out += "- run " + std::to_string(q.integer(0)) + ": `" + q.text(1) + "`, " + std::to_string(q.integer(6)) +
           "R, seed " + std::to_string(q.integer(2)) + ", " + std::to_string(q.integer(3)) + " of " +
           std::to_string(q.integer(4)) + " starts, " + q.text(5) + "\n";
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
    // Every family a classification can store (docs/families.md for n = 5, 6).
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
  sqlite3* handle = db->handle();
  // One read transaction: the summary and the list see the same state even
  // while a run commits.
  sqlite3_exec(handle, "BEGIN", nullptr, nullptr, nullptr);
  if (!args.atlas.empty()) {
    ReportArguments every = args;
    every.limit = "-1";  // SQLite: no limit; the atlas counts every candidate selected
    write_atlas(gnuplot, read_candidates(handle, args.database, every), atlas_header(handle, args.database, args), atlas_dir);
  } else if (args.summary) {
    print_summary(handle, args.database, args);
  } else {
    const std::vector<CandidateRow> rows = read_candidates(handle, args.database, args);
    if (args.format == "csv") {
      print_csv(rows);
    } else if (args.format == "json") {
      print_json(rows);
    } else if (args.format == "markdown") {
      print_markdown(rows);
    } else {
      print_table(rows);
    }
    if (!args.plot.empty()) plot_candidates(gnuplot, std::vector<CandidateRow>(rows.begin(), rows.begin() + std::min<size_t>(rows.size(), 10)), args.plot);
  }
  if (!args.plot.empty()) {
    const std::filesystem::path png = std::filesystem::path(args.plot) / "minima_histogram.png";
    plot_histogram(gnuplot, energy_histogram(handle, args.database, args), png);
    std::fprintf(stderr, "loopfarm report: wrote %s\n", png.string().c_str());
  }
  sqlite3_exec(handle, "COMMIT", nullptr, nullptr, nullptr);
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
      "  loopfarm report jobs/goldberg-5r.sqlite --atlas docs/atlas\n"
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
