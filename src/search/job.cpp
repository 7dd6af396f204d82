// Job files: parsing and validation (job.hpp, docs/guide/job-file.md).
//
// Every check names the file, the line and the key ("FILE:LINE: KEY: what"),
// so that a mistake in a long job file is found at once.
#include "loopfarm/search/job.hpp"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <optional>
#include <set>

#include <toml++/toml.h>

#include "job_reader.hpp"
#include "loopfarm/search/classify.hpp"

namespace loopfarm {

using namespace detail;

namespace {

// The families [steering] deflate accepts: those family_distance
// (classify.hpp) measures, with the joint count each needs (0: any). Kept
// here rather than taken from classify, so that the parser stands alone (fuzz/);
// start.cpp maps the names to classify's families and a test checks both agree.
struct DeflatableFamily {
  const char* name;
  int joints;
  const char* why;
};
constexpr DeflatableFamily kDeflatable[] = {
    {"planar", 0, ""},
    {"spherical", 0, ""},
    {"trivial", 0, ""},
    {"bennett", 4, "Bennett loops have 4 joints"},
    {"goldberg", 5, "Goldberg loops have 5 joints"},
    {"myard", 5, "Myard loops have 5 joints"},
    {"goldberg_bent", 5, "Goldberg loops have 5 joints"},
    {"bricard_line_symmetric", 6, "Bricard loops have 6 joints"},
    {"bricard_plane_symmetric", 6, "Bricard loops have 6 joints"},
    {"bricard_trihedral", 6, "Bricard loops have 6 joints"},
    {"bennett_pair", 6, "Bennett pairs have 6 joints"},
    {"bennett_dyads", 6, "Bennett dyad loops have 6 joints"},
    {"bennett_triads", 6, "Bennett triad loops have 6 joints"},
    {"coupled_bennett_dyads", 6, "coupled Bennett dyad loops have 6 joints"},
    {"sarrus", 6, "Sarrus loops have 6 joints"},
    {"bricard_octahedral_plane", 6, "Bricard loops have 6 joints"},
    {"waldron_hybrid", 6, "Waldron's hybrid loops have 6 joints"},
    {"goldberg_6r", 6, "Goldberg's 6R loops have 6 joints"},
    {"double_goldberg", 6, "double-Goldberg loops have 6 joints"},
    {"hooke", 6, "Hooke's loops have 6 joints"},
    {"bricard_octahedral_collapsible", 6, "Bricard loops have 6 joints"},
    {"angle_symmetric_parallel", 6, "angle-symmetric loops with parallel axes have 6 joints"},
};

// The settings tables and their keys; anything else is an error.
const std::set<std::string> kTables = {"loop", "space", "optimizer", "search", "steering", "output"};

template <class Handler>
void for_each_key(const Reader& r, const toml::table& table, const std::string& name,
                  const std::set<std::string>& allowed, Handler handler) {
  for (const auto& [key, node] : table) {
    const std::string k(key.str());
    const std::string full = name + "." + k;
    if (!allowed.count(k)) {
      std::string list;
      for (const std::string& a : allowed) list += (list.empty() ? "" : ", ") + a;
      r.fail(key.source(), full, "unknown key; [" + name + "] has " + list);
    }
    handler(k, full, node);
  }
}

Job parse_table(const toml::table& root, const std::string& file) {
  const Reader r{file};
  Job job;
  job.path = file;
  for (const auto& [key, node] : root) {
    const std::string k(key.str());
    if (!kTables.count(k)) {
      r.fail(key.source(), k,
             "unknown table or key; a job has [loop], [space], [optimizer], [search], "
             "[steering] and [output]");
    }
    r.table(node, k);
  }
  auto section = [&](const char* name) -> const toml::table* {
    const toml::node* node = root.get(name);
    return node ? node->as_table() : nullptr;
  };

  if (const toml::table* t = section("loop")) {
    for_each_key(r, *t, "loop",
                 {"joints", "compliance", "stiffness_ratio", "samples", "range_deg", "closure_tolerance",
                  "stationarity_tolerance", "objective"},
                 [&](const std::string& k, const std::string& full, const toml::node& node) {
                   if (k == "joints") {
                     const long long n = r.integer(node, full);
                     if (n < kMinJoints || n > kMaxJoints) {
                       r.fail(node.source(), full, "got " + std::to_string(n) + "; a loop has 4 to 8 joints");
                     }
                     job.loop.joints = static_cast<int>(n);
                   } else if (k == "compliance") {
                     const std::string c = r.string(node, full);
                     if (c != "paper" && c != "full") {
                       r.fail(node.source(), full,
                              "got \"" + c +
                                  "\"; expected \"paper\" (a and alpha springy) or "
                                  "\"full\" (a, alpha and d)");
                     }
                     // Checked just above; not compliance_from_string, which lives in the
                     // equilibrium solver, so that the parser stands alone (fuzz/).
                     job.loop.compliance = c == "full" ? Compliance::full : Compliance::paper;
                   } else if (k == "stiffness_ratio") {
                     job.loop.stiffness_ratio = r.positive(node, full, true);
                   } else if (k == "samples") {
                     job.loop.samples = r.integer_in(node, full, 4, 100000, "in [4, 100000]");
                   } else if (k == "range_deg") {
                     const double range = r.number(node, full);
                     if (!(range > 0.0 && range <= 360.0)) {
                       r.fail(node.source(), full, "got " + format(range) + "; must be in (0, 360]");
                     }
                     // 360 must be exactly 2 pi: the library tests for a full turn.
                     job.loop.range = range / 360.0 * (2.0 * kPi);
                   } else if (k == "objective") {
                     const std::string o = r.string(node, full);
                     if (o != "mean" && o != "max") {
                       r.fail(node.source(), full, "got \"" + o + "\"; expected \"mean\" (E_mean) or \"max\" (E_max)");
                     }
                     job.loop.objective = o;
                   } else if (k == "closure_tolerance" || k == "stationarity_tolerance") {
                     // Tolerances of the equilibrium solve, dimensionless; above 1e-3
                     // a "converged" sample would not be an equilibrium at all.
                     const double tolerance = r.positive(node, full, true);
                     if (tolerance > 1e-3) {
                       r.fail(node.source(), full, "got " + format(tolerance) + "; must be in (0, 1e-3]");
                     }
                     (k == "closure_tolerance" ? job.loop.closure_tolerance : job.loop.stationarity_tolerance) =
                         tolerance;
                   }
                 });
  }
  const toml::node* space_node = root.get("space");
  job.space = read_space(r, space_node ? space_node->as_table() : nullptr, job.loop.joints);

  if (const toml::table* t = section("optimizer")) {
    for_each_key(
        r, *t, "optimizer",
        {"algorithm", "xtol_rel", "ftol_rel", "ftol_abs", "stopval", "max_evaluations", "progress_window",
         "progress_factor", "checkpoint_evaluations", "checkpoint_objective", "time_limit_s", "reuse_nearby_cycle"},
        [&](const std::string& k, const std::string& full, const toml::node& node) {
          if (k == "algorithm") {
            job.optimizer.algorithm = r.string(node, full);
            const std::string& a = job.optimizer.algorithm;
            if (a == "GD_STOGO" || a == "GD_STOGO_RAND" || a == "GN_AGS") {
              r.fail(node.source(), full, "\"" + a + "\" is not built into Debian's NLopt");
            }
            if (!is_known_algorithm(a)) {
              r.fail(node.source(), full,
                     "unknown algorithm \"" + a +
                         "\"; expected \"gauss-newton\" or an "
                         "NLopt name such as \"LD_LBFGS\" or \"LN_BOBYQA\"");
            }
          } else if (k == "xtol_rel") {
            job.optimizer.xtol_rel = r.positive(node, full, false);
          } else if (k == "ftol_rel") {
            job.optimizer.ftol_rel = r.positive(node, full, false);
          } else if (k == "ftol_abs") {
            job.optimizer.ftol_abs = r.positive(node, full, false);
          } else if (k == "stopval") {
            job.optimizer.stopval = r.number(node, full);
          } else if (k == "max_evaluations") {
            job.optimizer.max_evaluations = r.integer_in(node, full, 1, 100000000, "in [1, 1e8]");
          } else if (k == "progress_window") {
            job.optimizer.progress_window = r.integer_in(node, full, 0, 100000000, "in [0, 1e8] (0: not used)");
          } else if (k == "progress_factor") {
            const double f = r.number(node, full);
            if (!(f > 1.0)) r.fail(node.source(), full, "got " + format(f) + "; must be > 1");
            job.optimizer.progress_factor = f;
          } else if (k == "checkpoint_evaluations") {
            job.optimizer.checkpoint_evaluations = r.integer_in(node, full, 0, 100000000, "in [0, 1e8] (0: not used)");
          } else if (k == "checkpoint_objective") {
            job.optimizer.checkpoint_objective = r.positive(node, full, true);
          } else if (k == "time_limit_s") {
            job.optimizer.time_limit = r.positive(node, full, false);
          } else if (k == "reuse_nearby_cycle") {
            job.optimizer.reuse_nearby_cycle = r.boolean(node, full);
          }
        });
    if (job.optimizer.checkpoint_evaluations > 0 && !(job.optimizer.checkpoint_objective > 0.0)) {
      r.fail(t->get("checkpoint_evaluations")->source(), "optimizer.checkpoint_evaluations",
             "needs optimizer.checkpoint_objective, the objective a start must be below by then");
    }
  }
  if (const toml::table* t = section("search")) {
    for_each_key(r, *t, "search", {"starts", "seed", "zero_threshold"},
                 [&](const std::string& k, const std::string& full, const toml::node& node) {
                   if (k == "starts") {
                     const long long n = r.integer(node, full);
                     if (n <= 0) r.fail(node.source(), full, "got " + std::to_string(n) + "; must be > 0");
                     job.search.starts = static_cast<long>(n);
                   } else if (k == "seed") {
                     const long long s = r.integer(node, full);
                     if (s < 0) r.fail(node.source(), full, "got " + std::to_string(s) + "; must be >= 0");
                     job.search.seed = static_cast<std::uint64_t>(s);
                   } else if (k == "zero_threshold") {
                     job.search.zero_threshold = r.positive(node, full, true);
                   }
                 });
  }
  if (const toml::table* t = section("steering")) {
    for_each_key(
        r, *t, "steering", {"nontrivial", "min_travel_deg", "deflate", "deflation_power", "deflation_shift"},
        [&](const std::string& k, const std::string& full, const toml::node& node) {
          if (k == "nontrivial") {
            job.steering.nontrivial = r.boolean(node, full);
          } else if (k == "min_travel_deg") {
            job.steering.min_travel = r.positive(node, full, true) * kRadiansPerDegree;
          } else if (k == "deflation_power") {
            job.steering.deflation_power = r.positive(node, full, true);
          } else if (k == "deflation_shift") {
            job.steering.deflation_shift = r.positive(node, full, false);
          } else if (k == "deflate") {
            const toml::array* list = node.as_array();
            if (list == nullptr) {
              r.fail(node.source(), full,
                     "expected a list of families such as [\"planar\", \"trivial\"], got " + Reader::describe(node));
            }
            for (const toml::node& item : *list) {
              const std::string family = r.string(item, full);
              const DeflatableFamily* known = nullptr;
              std::string names;
              for (const DeflatableFamily& f : kDeflatable) {
                if (family == f.name) known = &f;
                names += std::string(names.empty() ? "" : ", ") + f.name;
              }
              if (known == nullptr && family_from_string(family).has_value()) {
                // degenerate and cubic_321: decided from the motion, with no distance to the geometry.
                r.fail(item.source(), full,
                       "\"" + family + "\" cannot be deflated: it is decided from the motion, not by a distance; " +
                           "expected one of " + names);
              }
              if (known == nullptr) {
                r.fail(item.source(), full, "unknown family \"" + family + "\"; expected one of " + names);
              }
              if (known->joints != 0 && known->joints != job.loop.joints) {
                r.fail(item.source(), full,
                       "\"" + family + "\" needs joints = " + std::to_string(known->joints) + " (" + known->why +
                           "), the job has " + std::to_string(job.loop.joints));
              }
              if (std::count(job.steering.deflate.begin(), job.steering.deflate.end(), family)) {
                r.fail(item.source(), full, "\"" + family + "\" is listed twice");
              }
              job.steering.deflate.push_back(family);
            }
          }
        });
  }
  if (const toml::table* t = section("output")) {
    for_each_key(r, *t, "output", {"database", "report_threshold"},
                 [&](const std::string& k, const std::string& full, const toml::node& node) {
                   if (k == "report_threshold") {
                     job.output.report_threshold = r.positive(node, full, true);
                     return;
                   }
                   const std::string path = r.string(node, full);
                   if (path.empty()) r.fail(node.source(), full, "empty path");
                   // As given: a relative path names a file where the user
                   // stands (the working directory), as on the command line.
                   job.output.database = path;
                 });
  }
  return job;
}

}  // namespace

namespace {

// Control characters as \xNN: a key or value may hold any (TOML's "\r" in a
// string, a quoted key with a newline), and the message must stay one line.
std::string printable(const std::string& text) {
  std::string out;
  for (const char c : text) {
    const auto u = static_cast<unsigned char>(c);
    if (u < 0x20 || u == 0x7F) {
      char buffer[8];
      std::snprintf(buffer, sizeof buffer, "\\x%02x", u);
      out += buffer;
    } else {
      out += c;
    }
  }
  return out;
}

}  // namespace

JobError::JobError(std::string file, int line, std::string key, const std::string& message)
    : std::runtime_error(printable(file + ":" + std::to_string(line) + ": " + key + ": " + message)),
      file_(std::move(file)),
      line_(line),
      key_(std::move(key)) {}

Job parse_job(std::string_view text, const std::string& source_name) {
  if (const std::optional<TomlHazard> hazard = find_toml_hazard(text)) {
    throw JobError(source_name, hazard->line, "(syntax)", "invalid TOML: " + hazard->message);
  }
  toml::table root;
  try {
    root = toml::parse(text, source_name);
  } catch (const toml::parse_error& error) {
    const auto& begin = error.source().begin;
    std::string description(error.description());
    std::replace(description.begin(), description.end(), '\n', ' ');
    throw JobError(source_name, static_cast<int>(begin.line), "(syntax)", "invalid TOML: " + description);
  }
  Job job = parse_table(root, source_name);
  job.text = std::string(text);
  return job;
}

Job read_job_file(const std::string& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) throw JobError(path, 0, "(file)", "is a directory, not a job file");
  std::ifstream stream(path, std::ios::binary);
  if (!stream) throw JobError(path, 0, "(file)", std::string("cannot read: ") + std::strerror(errno));
  const std::string text{std::istreambuf_iterator<char>(stream), std::istreambuf_iterator<char>()};
  if (stream.bad()) throw JobError(path, 0, "(file)", "read error");
  return parse_job(text, path);
}

}  // namespace loopfarm