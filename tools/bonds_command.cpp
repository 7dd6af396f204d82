#include "bonds_command.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "candidate_display.hpp"
#include "candidate_output.hpp"
#include "cli_support.hpp"
#include "geometry_options.hpp"
#include "loopfarm/farm/candidate_pose.hpp"
#include "loopfarm/farm/results_database.hpp"
#include "loopfarm/farm/stop_flag.hpp"
#include "loopfarm/search/bond_relations.hpp"
#include "loopfarm/search/classify.hpp"
#include "loopfarm/search/verify.hpp"
#include "output_format.hpp"

namespace loopfarm::cli {
namespace {

constexpr double kDegreesPerRadian = 180.0 / 3.14159265358979323846;
constexpr const char* kDefaultFamily = "unclassified";
// --family's name for every family.
constexpr const char* kEveryFamily = "all";

// Set by SIGINT and SIGTERM while --store measures: it stops before the next
// candidate and writes nothing.
StopFlag g_stop;

extern "C" void on_bonds_stop_signal(int signal) {
  g_stop.request(signal);
  // A second signal ends the process at once (nothing is written before the
  // measuring ends, so nothing is lost either).
  std::signal(signal, SIG_DFL);
}

void install_stop_handlers() {
  struct sigaction action {};
  action.sa_handler = on_bonds_stop_signal;
  sigemptyset(&action.sa_mask);
  for (int signal : {SIGINT, SIGTERM}) sigaction(signal, &action, nullptr);
}

struct BondsArguments {
  std::string database;
  GeometryOptions geometry;
  std::string theta0_deg;
  std::string steps = "720";
  std::string max_degree = "4";
  std::string tolerance = "1e-9";
  std::string rows = "0";
  std::string frozen_travel_deg;
  std::string family;
  std::string limit = "0";
  bool store = false;
  bool recompute = false;
  FormatChoice format;
  CLI::Option* family_option = nullptr;
  CLI::Option* limit_option = nullptr;
  CLI::Option* theta0_option = nullptr;
  CLI::Option* store_option = nullptr;
  CLI::Option* recompute_option = nullptr;
  // The measuring options --store keeps at their defaults.
  std::vector<CLI::Option*> measuring_options;
};

std::string g(double value, int digits = 3) {
  if (std::isnan(value)) return "-";
  return format_significant(value, digits);
}

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// The options' texts, checked: each bad value names its flag.
struct Settings {
  BondOptions bonds;
  VerificationOptions verification;
};

Settings read_settings(const BondsArguments& args) {
  Settings s;
  const long long degree = parse_integer(args.max_degree, "--max-degree");
  if (degree < 1 || degree > 8) {
    throw UsageError("--max-degree", "got " + args.max_degree + "; must be in [1, 8]");
  }
  s.bonds.max_degree = static_cast<int>(degree);
  s.bonds.tolerance = parse_number(args.tolerance, "--tolerance");
  if (!(s.bonds.tolerance > 0.0 && s.bonds.tolerance < 1.0)) {
    throw UsageError("--tolerance", "got " + args.tolerance + "; must be in (0, 1)");
  }
  const long long rows = parse_integer(args.rows, "--rows");
  if (rows != 0 && (rows < s.bonds.minimum_rows() || rows > 100000)) {
    throw UsageError("--rows", "got " + args.rows + "; must be 0 (automatic) or in [" +
                                   std::to_string(s.bonds.minimum_rows()) + ", 100000] for --max-degree " +
                                   std::to_string(degree) + " (three rows per column of the largest candidate)");
  }
  s.bonds.rows = static_cast<int>(rows);
  if (!args.frozen_travel_deg.empty()) {
    const double travel = parse_number(args.frozen_travel_deg, "--frozen-travel-deg");
    if (travel < 0.0) throw UsageError("--frozen-travel-deg", "got " + args.frozen_travel_deg + "; must be >= 0");
    s.bonds.frozen_travel = travel / kDegreesPerRadian;
  }
  const long long steps = parse_integer(args.steps, "--steps");
  if (steps < 64 || steps > 1000000) {
    throw UsageError("--steps", "got " + std::to_string(steps) + "; must be in [64, 1000000]");
  }
  s.verification.steps_per_turn = static_cast<int>(steps);
  if (!args.theta0_deg.empty()) {
    s.verification.theta0 = parse_number(args.theta0_deg, "--theta0-deg") / kDegreesPerRadian;
  }
  return s;
}

// --- one geometry ------------------------------------------------------------------

nlohmann::ordered_json pair_json(const BondPair& p) {
  nlohmann::ordered_json out;
  out["joints"] = {p.i + 1, p.j + 1};
  out["status"] = to_string(p.status);
  const bool fitted = p.status == BondStatus::related || p.status == BondStatus::ambiguous;
  out["p"] = fitted ? nlohmann::ordered_json(p.p) : nlohmann::ordered_json(nullptr);
  out["q"] = fitted ? nlohmann::ordered_json(p.q) : nlohmann::ordered_json(nullptr);
  out["ratio"] = p.ratio;
  out["gap"] = p.gap;
  out["closest_rejected"] = p.closest_rejected;
  out["coefficients"] = p.coefficients;
  return out;
}

void print_bonds_text(const LoopGeometry& geometry, const VerificationSummary& v, const BondSummary& b,
                      double trace_seconds) {
  const int n = geometry.joints();
  std::printf("loop (%dR)\n", n);
  std::printf("  a                     %s\n", lengths_text(geometry.a).c_str());
  std::printf("  alpha_deg             %s\n", degrees_text(geometry.alpha).c_str());
  std::printf("  d                     %s\n", lengths_text(geometry.d).c_str());
  std::printf("motion                  verified; circuit %d of %zu, %d poses, input %s, worst residual %s\n",
              v.circuit + 1, v.motion.circuits.size(), v.poses,
              v.full_turn
                  ? "full turn"
                  : ("[" + g(v.range_lo * kDegreesPerRadian, 6) + ", " + g(v.range_hi * kDegreesPerRadian, 6) + "] deg")
                        .c_str(),
              g(v.worst_residual, 2).c_str());
  std::printf("relations               %d poses spread by arclength, closing to %s (lengths / L)\n", b.rows,
              g(b.worst_closure, 2).c_str());
  std::printf("  candidates            (p, q), 1 <= p, q <= %d, by p + q, then max(p, q), then p;\n", b.max_degree);
  std::printf("                        p the degree in the first joint's half-angle tangent\n");
  std::printf("  relation              sigma_min / sigma_max <= %s; gap: the next singular value / sigma_max\n",
              g(b.tolerance, 2).c_str());
  std::printf("joint  travel_deg  \n");
  for (int k = 0; k < n; ++k) {
    std::printf("%5d  %-10s%s\n", k + 1, g(b.travel[static_cast<size_t>(k)] * kDegreesPerRadian, 6).c_str(),
                b.frozen[static_cast<size_t>(k)] ? "  frozen" : "");
  }
  std::printf("pair  status     bidegree  ratio     gap       closest_rejected\n");
  for (const BondPair& p : b.pairs) {
    const bool fitted = p.status == BondStatus::related || p.status == BondStatus::ambiguous;
    const std::string bidegree = fitted ? "(" + std::to_string(p.p) + ", " + std::to_string(p.q) + ")" : "-";
    std::printf("%-5s %-10s %-9s %-9s %-9s %s\n", (std::to_string(p.i + 1) + "-" + std::to_string(p.j + 1)).c_str(),
                to_string(p.status), bidegree.c_str(), g(p.ratio, 2).c_str(), g(p.gap, 2).c_str(),
                g(p.closest_rejected, 2).c_str());
  }
  std::printf("fingerprint             %s\n", b.fingerprint.c_str());
  std::printf("time                    %s s to trace the motion, %s s for the relations\n", g(trace_seconds, 2).c_str(),
              g(b.seconds, 2).c_str());
}

int run_geometry(const BondsArguments& args, const Settings& settings) {
  const GeometryRequest request = read_geometry(args.geometry);
  const LoopGeometry& geometry = request.geometry;
  VerificationOptions verification = settings.verification;
  if (!verification.theta0 && request.theta0_deg) verification.theta0 = *request.theta0_deg / kDegreesPerRadian;
  const JointVector* pose = request.theta ? &*request.theta : nullptr;

  const auto traced = std::chrono::steady_clock::now();
  const VerificationSummary v = verify_motion(geometry, pose, verification);
  const double trace_seconds = seconds_since(traced);
  const bool json = args.format.format == OutputFormat::json;
  if (!v.verified) {
    if (json) {
      nlohmann::ordered_json record;
      record["geometry"] = geometry_json(geometry);
      record["verified"] = false;
      record["limit"] = v.limit;
      write_record(stdout, record, OutputFormat::json);
    } else {
      std::printf("not verified: no circuit of the rigid loop moves%s%s; no relations to measure\n",
                  v.limit.empty() ? "" : ": ", v.limit.c_str());
    }
    return kExitNotVerified;
  }
  if (static_cast<int>(v.joint_angles.size()) < settings.bonds.minimum_rows()) {
    throw UsageError("--steps", "the reported circuit has " + std::to_string(v.joint_angles.size()) +
                                    " poses, fewer than the " + std::to_string(settings.bonds.minimum_rows()) +
                                    " that --max-degree " + args.max_degree + " needs; give a larger --steps");
  }
  const BondSummary b = bond_relations(geometry, v.joint_angles, settings.bonds);

  if (!json) {
    print_bonds_text(geometry, v, b, trace_seconds);
    return kExitSuccess;
  }
  nlohmann::ordered_json record;
  record["geometry"] = geometry_json(geometry);
  record["verified"] = true;
  record["circuit"] = v.circuit + 1;
  record["poses"] = b.poses;
  record["rows"] = b.rows;
  record["max_degree"] = b.max_degree;
  record["tolerance"] = b.tolerance;
  record["frozen_travel_deg"] = settings.bonds.frozen_travel * kDegreesPerRadian;
  record["worst_closure"] = b.worst_closure;
  nlohmann::ordered_json joints = nlohmann::ordered_json::array();
  for (int k = 0; k < b.joints; ++k) {
    joints.push_back({{"joint", k + 1},
                      {"travel_deg", b.travel[static_cast<size_t>(k)] * kDegreesPerRadian},
                      {"frozen", static_cast<bool>(b.frozen[static_cast<size_t>(k)])}});
  }
  record["joints"] = joints;
  nlohmann::ordered_json pairs = nlohmann::ordered_json::array();
  for (const BondPair& p : b.pairs) pairs.push_back(pair_json(p));
  record["pairs"] = pairs;
  record["fingerprint"] = b.fingerprint;
  record["trace_seconds"] = trace_seconds;
  record["bond_seconds"] = b.seconds;
  write_record(stdout, record, OutputFormat::json);
  return kExitSuccess;
}

// --- the candidates of a database ----------------------------------------------------

struct CandidateBonds {
  long long id = 0;
  long long first_run = 0, first_start = 0;  // the representative measured
  std::string family;
  std::optional<std::string> stored;  // the fingerprint the database holds
  bool verified = false;
  std::string fingerprint;  // empty when not measured
  std::string note;         // why not
  int rows = 0;
  double worst_closure = 0.0;
  // How clearly the relations are told: the largest ratio of a relation
  // found, and the least ratio of a candidate bidegree rejected (NaN: none).
  double largest_related = std::numeric_limits<double>::quiet_NaN();
  double least_rejected = std::numeric_limits<double>::quiet_NaN();
  double trace_seconds = 0.0;
  double bond_seconds = 0.0;
};

CandidateBonds measure(const CandidateRow& row, const Settings& settings) {
  CandidateBonds out;
  out.id = row.id;
  out.first_run = row.first_run;
  out.first_start = row.first_start;
  out.family = row.family;
  out.stored = row.bond_fingerprint;
  LoopGeometry geometry;
  try {
    geometry = candidate_geometry(row);
    validate_geometry(geometry);
  } catch (const std::invalid_argument& error) {
    out.note = std::string("the stored geometry is not a loop: ") + error.what();
    return out;
  }
  const auto traced = std::chrono::steady_clock::now();
  const VerificationSummary v = verify_motion(geometry, nullptr, settings.verification);
  out.trace_seconds = seconds_since(traced);
  out.verified = v.verified;
  if (!v.verified) {
    out.note = "the rigid loop of the stored geometry does not move";
    return out;
  }
  if (static_cast<int>(v.joint_angles.size()) < settings.bonds.minimum_rows()) {
    out.note = "the circuit has " + std::to_string(v.joint_angles.size()) + " poses, fewer than " +
               std::to_string(settings.bonds.minimum_rows()) + "; give a larger --steps";
    return out;
  }
  const BondSummary b = bond_relations(geometry, v.joint_angles, settings.bonds);
  out.fingerprint = b.fingerprint;
  out.rows = b.rows;
  out.worst_closure = b.worst_closure;
  out.bond_seconds = b.seconds;
  for (const BondPair& p : b.pairs) {
    if (p.status == BondStatus::related || p.status == BondStatus::ambiguous) {
      if (!(out.largest_related >= p.ratio)) out.largest_related = p.ratio;
    }
    if (!std::isnan(p.closest_rejected) && !(out.least_rejected <= p.closest_rejected)) {
      out.least_rejected = p.closest_rejected;
    }
  }
  return out;
}

[[noreturn]] void rethrow_read_error(const DatabaseError& error) {
  if (error.cause() == DatabaseError::Cause::refused) throw UsageError("DB", error.what());
  throw EnvironmentError(error.what());
}

// "the unclassified candidates", "every candidate".
std::string selection_text(const std::string& family) {
  return family.empty() ? "every candidate" : "the " + family + " candidates";
}

// The text line of a measured candidate: the stored fingerprint too when it
// differs from the one just measured.
void print_candidate_line(const CandidateBonds& m) {
  std::string result = m.fingerprint.empty() ? "(" + m.note + ")" : m.fingerprint;
  if (m.stored && *m.stored != m.fingerprint) {
    result += "  (stored: " + (m.stored->empty() ? std::string("none") : *m.stored) + ")";
  }
  std::printf("%-7lld %-22s %-9s %-9s %-9s %s\n", m.id, m.family.c_str(),
              g(m.trace_seconds + m.bond_seconds, 2).c_str(), g(m.largest_related, 2).c_str(),
              g(m.least_rejected, 2).c_str(), result.c_str());
  std::fflush(stdout);
}

nlohmann::ordered_json text_or_null(const std::optional<std::string>& text) {
  return text ? nlohmann::ordered_json(*text) : nlohmann::ordered_json(nullptr);
}

int run_database(const BondsArguments& args, const Settings& settings) {
  // Empty: every family.
  const std::string family =
      args.family.empty() ? kDefaultFamily : (args.family == kEveryFamily ? std::string() : args.family);
  if (!family.empty() && !family_from_string(family)) {
    std::string names;
    for (Family f : kAllFamilies) names += (names.empty() ? "" : ", ") + std::string(to_string(f));
    throw UsageError("--family", "got " + quote_text(family) + "; expected one of " + names + ", or " + kEveryFamily);
  }
  const long long limit = parse_integer(args.limit, "--limit");
  if (limit < 0) throw UsageError("--limit", "got " + args.limit + "; must be >= 0 (0: every candidate)");

  // --store opens the file for writing first, so that a file it would refuse
  // (read-only, a newer schema) costs no measuring.
  std::optional<ResultsDatabase> db;
  try {
    db.emplace(ResultsDatabase::open(args.database, args.store ? DatabaseMode::update : DatabaseMode::read));
  } catch (const DatabaseError& error) {
    throw UsageError("DB", error.what());
  }
  std::vector<CandidateRow> rows;
  std::string present;
  std::int64_t selected = 0;
  try {
    const ResultsDatabase::Snapshot snapshot = db->snapshot();
    bool held = family.empty();
    for (const FamilyCount& f : db->family_counts()) {
      held = held || f.family == family;
      present += (present.empty() ? "" : ", ") + f.family + " (" + grouped(f.candidates) + ")";
    }
    if (!held && !args.family.empty()) {
      throw UsageError("--family", "no " + family + " candidate in " + db->path() + "; " +
                                       (present.empty() ? "it holds no candidate" : "families present: " + present));
    }
    CandidateFilter filter;
    filter.family = family;
    selected = db->candidate_count(filter);
    // --store measures only what is not stored yet, unless told to measure again.
    filter.without_fingerprint = args.store && !args.recompute;
    filter.limit = limit > 0 ? limit : -1;
    rows = db->candidates(filter);
  } catch (const DatabaseError& error) {
    rethrow_read_error(error);
  }

  const bool json = args.format.format == OutputFormat::json;
  if (!json) {
    if (selected == 0) {
      std::printf("no %s in %s (%s)\n", family.empty() ? "candidate" : (family + " candidate").c_str(),
                  args.database.c_str(),
                  present.empty() ? "it holds no candidate" : ("families present: " + present).c_str());
      return kExitSuccess;
    }
    if (rows.empty()) {
      std::printf(
          "%s of %s (%s) have their bond fingerprints stored already; nothing to measure (--recompute "
          "measures them again)\n",
          selection_text(family).c_str(), args.database.c_str(), grouped(selected).c_str());
      return kExitSuccess;
    }
    std::printf("%-7s %-22s %-9s %-9s %-9s %s\n", "id", "family", "seconds", "related", "rejected", "fingerprint");
  }
  if (args.store) install_stop_handlers();
  // Each candidate traced and measured in turn; the text lists it at once.
  std::vector<CandidateBonds> measured;
  for (const CandidateRow& row : rows) {
    if (g_stop.requested()) break;
    measured.push_back(measure(row, settings));
    if (!json) print_candidate_line(measured.back());
  }
  if (g_stop.requested()) {
    std::fprintf(stderr,
                 "loopfarm bonds: stopped by %s after %zu of %zu candidates; nothing was written to %s (run the "
                 "command again to measure them)\n",
                 signal_name(g_stop.signal()).c_str(), measured.size(), rows.size(), args.database.c_str());
    return kExitStopped;
  }

  std::optional<FingerprintStoreSummary> stored;
  if (args.store) {
    // One transaction: every fingerprint measured, or none.
    std::vector<BondFingerprint> fingerprints;
    for (const CandidateBonds& m : measured) fingerprints.push_back({m.id, m.first_run, m.first_start, m.fingerprint});
    try {
      stored = db->store_bond_fingerprints(fingerprints);
    } catch (const DatabaseError& error) {
      rethrow_read_error(error);
    }
  }

  // Classes: candidates of equal fingerprint, the largest first.
  std::map<std::string, std::vector<long long>> classes;
  for (const CandidateBonds& m : measured) {
    if (!m.fingerprint.empty()) classes[m.fingerprint].push_back(m.id);
  }
  std::vector<std::pair<std::string, std::vector<long long>>> ordered(classes.begin(), classes.end());
  std::stable_sort(ordered.begin(), ordered.end(),
                   [](const auto& x, const auto& y) { return x.second.size() > y.second.size(); });

  if (json) {
    nlohmann::ordered_json record;
    record["database"] = args.database;
    record["family"] = family.empty() ? std::string(kEveryFamily) : family;
    record["max_degree"] = settings.bonds.max_degree;
    record["tolerance"] = settings.bonds.tolerance;
    nlohmann::ordered_json candidates = nlohmann::ordered_json::array();
    for (const CandidateBonds& m : measured) {
      nlohmann::ordered_json c;
      c["id"] = m.id;
      c["family"] = m.family;
      c["verified"] = m.verified;
      c["fingerprint"] =
          m.fingerprint.empty() ? nlohmann::ordered_json(nullptr) : nlohmann::ordered_json(m.fingerprint);
      c["stored_fingerprint"] = text_or_null(m.stored);
      c["note"] = m.note.empty() ? nlohmann::ordered_json(nullptr) : nlohmann::ordered_json(m.note);
      c["rows"] = m.rows;
      c["worst_closure"] = m.worst_closure;
      c["largest_related_ratio"] = m.largest_related;
      c["least_rejected_ratio"] = m.least_rejected;
      c["trace_seconds"] = m.trace_seconds;
      c["bond_seconds"] = m.bond_seconds;
      candidates.push_back(c);
    }
    record["candidates"] = candidates;
    nlohmann::ordered_json list = nlohmann::ordered_json::array();
    for (const auto& [fingerprint, ids] : ordered) {
      list.push_back({{"fingerprint", fingerprint}, {"count", ids.size()}, {"candidates", ids}});
    }
    record["classes"] = list;
    if (stored) {
      record["stored"] = {{"written", stored->stored}, {"skipped", stored->skipped}, {"upgraded", stored->upgraded}};
    } else {
      record["stored"] = nullptr;
    }
    write_record(stdout, record, OutputFormat::json);
    return kExitSuccess;
  }
  std::printf("classes by fingerprint (%zu of %zu candidates measured)\n",
              static_cast<size_t>(std::count_if(measured.begin(), measured.end(),
                                                [](const CandidateBonds& m) { return !m.fingerprint.empty(); })),
              measured.size());
  for (const auto& [fingerprint, ids] : ordered) {
    std::string list;
    for (const long long id : ids) list += (list.empty() ? "" : ", ") + std::to_string(id);
    std::printf("  %-5zu %s\n        candidates %s\n", ids.size(), fingerprint.c_str(), list.c_str());
  }
  if (stored) {
    std::printf(
        "stored %s in %s%s%s\n", count_of(stored->stored, "bond fingerprint").c_str(), args.database.c_str(),
        stored->skipped > 0
            ? ("; " + grouped(stored->skipped) +
               " left as they were (their representative changed or they are gone since they were read)")
                  .c_str()
            : "",
        stored->upgraded ? ("; schema upgraded to version " + std::to_string(kDatabaseSchemaVersion)).c_str() : "");
  }
  return kExitSuccess;
}

int run_bonds(const BondsArguments& args) {
  const GeometryOptions& o = args.geometry;
  const bool geometry_given =
      given(o.a_option) || given(o.alpha_option) || given(o.d_option) || given(o.geometry_option);
  const bool database_given = !args.database.empty();
  if (database_given && (geometry_given || given(o.theta_option) || given(args.theta0_option))) {
    throw UsageError("DB",
                     "give either a results database or one geometry (--a, --alpha-deg, --d, --geometry, "
                     "--theta-deg, --theta0-deg), not both");
  }
  if (!database_given && (given(args.family_option) || given(args.limit_option))) {
    throw UsageError(given(args.family_option) ? "--family" : "--limit",
                     "selects candidates of a results database: give its file as DB");
  }
  if (!database_given && given(args.store_option)) {
    throw UsageError("--store", "stores the fingerprints of a results database's candidates: give its file as DB");
  }
  if (given(args.recompute_option) && !args.store) {
    throw UsageError("--recompute", "measures again the fingerprints --store would skip: give --store too");
  }
  if (args.store) {
    // One measure for every stored fingerprint, so that equal ones compare
    // alike; the degree bound is part of the fingerprint's text.
    for (const CLI::Option* option : args.measuring_options) {
      if (given(option)) {
        throw UsageError(option->get_name(),
                         "--store stores fingerprints measured with the default --tolerance, --rows, "
                         "--frozen-travel-deg and --steps only, so that the stored ones compare alike; measure "
                         "without --store to try other values");
      }
    }
  }
  if (!database_given && !geometry_given) {
    throw UsageError("--a",
                     "missing: give a geometry (--a and --alpha-deg, e.g. --a 2,4,2,4 --alpha-deg 30,90,30,90, or "
                     "--geometry FILE.toml) or a results database DB");
  }
  const Settings settings = read_settings(args);
  return database_given ? run_database(args, settings) : run_geometry(args, settings);
}

}  // namespace

Subcommand add_bonds_command(CLI::App& parent) {
  auto args = std::make_shared<BondsArguments>();
  CLI::App* app = parent.add_subcommand(
      "bonds",
      "For every pair of joints, the smallest bidegree of a polynomial relation between their half-angle tangents "
      "along the traced motion, and the loop's fingerprint (the table in its least labelling); for a results "
      "database, one line per candidate and the classes of equal fingerprint.");
  app->footer(
      "Examples:\n"
      "  loopfarm bonds --a 2,4,2,4 --alpha-deg 30,90,30,90\n"
      "  loopfarm bonds --geometry loop.toml --json\n"
      "  loopfarm bonds generic-6r.sqlite                      # every unclassified candidate, and the classes\n"
      "  loopfarm bonds generic-6r.sqlite --family bennett_dyads --limit 10\n"
      "  loopfarm bonds generic-6r.sqlite --store              # measure and store the unclassified ones' "
      "fingerprints\n"
      "Candidates (p, q) are tried by p + q, then max(p, q), then p; a relation holds when the smallest singular\n"
      "value of the monomials at poses spread along the circuit is at most --tolerance of the largest\n"
      "(docs/guide/bonds.md). The database is opened read-only, except with --store: the fingerprints of the\n"
      "candidates not stored yet (all with --recompute) are written in one transaction at the end, so that an\n"
      "error, SIGINT or SIGTERM leaves the file as it was (`loopfarm report DB --by-fingerprint` lists them).\n"
      "Exit codes: 0 done, 4 the geometry does not move (not verified), 3 --store stopped by a signal (nothing\n"
      "written), 1 failure, 2 bad input.\n");
  app->add_option("DB", args->database, "results database (SQLite) written by loopfarm run, instead of a geometry");
  add_geometry_options(*app, args->geometry);
  args->theta0_option =
      app->add_option("--theta0-deg", args->theta0_deg,
                      "input angle theta0 [deg]: measure on the circuit whose input reaches it (default: from "
                      "--theta-deg, else the circuit loopfarm verify reports)")
          ->type_name("DEG");
  args->geometry.theta_option->excludes(args->theta0_option);
  CLI::Option* steps =
      app->add_option("--steps", args->steps, "tracing: the largest step along a circuit is 360/S deg (>= 64)")
          ->type_name("S")
          ->capture_default_str();
  app->add_option("--max-degree", args->max_degree, "the largest degree tried in either joint, 1 to 8")
      ->type_name("N")
      ->capture_default_str();
  CLI::Option* tolerance =
      app->add_option("--tolerance", args->tolerance, "a relation: smallest singular value / largest at most this")
          ->type_name("X")
          ->capture_default_str();
  CLI::Option* rows =
      app->add_option("--rows", args->rows,
                      "poses used, spread by arclength; 0: 5 (max-degree + 1)^2, at least 3 (max-degree + 1)^2")
          ->type_name("N")
          ->capture_default_str();
  CLI::Option* frozen =
      app->add_option("--frozen-travel-deg", args->frozen_travel_deg,
                      "a joint turning less than this is frozen and not fitted (default 1e-6 rad, 5.7e-05 deg)")
          ->type_name("DEG");
  args->measuring_options = {tolerance, rows, frozen, steps};
  args->family_option =
      app->add_option("--family", args->family, "with DB: only this family, or all (default: unclassified)")
          ->type_name("NAME");
  args->limit_option =
      app->add_option("--limit", args->limit, "with DB: at most this many candidates, in the report's order; 0: all")
          ->type_name("N")
          ->capture_default_str();
  args->store_option = app->add_flag(
      "--store", args->store,
      "with DB: store each measured fingerprint with its candidate (those not stored yet), in one transaction "
      "at the end; upgrades an older database to the current schema version");
  args->recompute_option = app->add_flag("--recompute", args->recompute,
                                         "with --store: measure and store again the fingerprints stored already");
  add_format_option(*app, args->format, {OutputFormat::text, OutputFormat::json}, "print the relations as");
  return {app, [args] { return run_bonds(*args); }};
}

}  // namespace loopfarm::cli
