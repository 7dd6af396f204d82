// Job files: parsing and validation (job.hpp, docs/job-file.md).
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

namespace loopfarm {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kRadiansPerDegree = kPi / 180.0;
// The largest magnitude of a length (a, d). Energies are divided by L^2, L the
// RMS of the lengths; beyond about 1e154 the squares overflow, L is inf and
// every energy NaN, and a range's width hi - lo can overflow too. 1e150 keeps
// the sum of 16 squares finite with room to spare.
constexpr double kMaxLength = 1e150;

std::string format(double value) {
  char buffer[40];
  std::snprintf(buffer, sizeof buffer, "%.10g", value);
  return buffer;
}

// The reader of one job file: where it is and how to complain.
struct Reader {
  std::string file;

  [[noreturn]] void fail(const toml::source_region& where, const std::string& key, const std::string& message) const {
    throw JobError(file, static_cast<int>(where.begin.line), key, message);
  }

  static std::string describe(const toml::node& node) {
    if (const auto* s = node.as_string()) return "the string \"" + s->get() + "\"";
    if (const auto* b = node.as_boolean()) return std::string("the boolean ") + (b->get() ? "true" : "false");
    if (const auto* i = node.as_integer()) return "the integer " + std::to_string(i->get());
    if (const auto* f = node.as_floating_point()) return "the number " + format(f->get());
    if (node.is_table()) return "a table";
    if (node.is_array()) return "an array";
    return "a date or time";
  }

  double number(const toml::node& node, const std::string& key) const {
    double value = 0.0;
    if (const auto* i = node.as_integer()) {
      value = static_cast<double>(i->get());
    } else if (const auto* f = node.as_floating_point()) {
      value = f->get();
    } else {
      fail(node.source(), key, "expected a number, got " + describe(node));
    }
    // TOML has nan and inf literals; no job setting has a use for them.
    if (!std::isfinite(value)) fail(node.source(), key, "got " + format(value) + "; must be a finite number");
    return value;
  }

  long long integer(const toml::node& node, const std::string& key) const {
    const auto* i = node.as_integer();
    if (i == nullptr) fail(node.source(), key, "expected an integer, got " + describe(node));
    return i->get();
  }

  bool boolean(const toml::node& node, const std::string& key) const {
    const auto* b = node.as_boolean();
    if (b == nullptr) fail(node.source(), key, "expected true or false, got " + describe(node));
    return b->get();
  }

  std::string string(const toml::node& node, const std::string& key) const {
    const auto* s = node.as_string();
    if (s == nullptr) fail(node.source(), key, "expected a string, got " + describe(node));
    return s->get();
  }

  const toml::table& table(const toml::node& node, const std::string& key) const {
    const toml::table* t = node.as_table();
    if (t == nullptr) fail(node.source(), key, "expected a table [" + key + "], got " + describe(node));
    return *t;
  }

  // number > 0 (strict) or >= 0.
  double positive(const toml::node& node, const std::string& key, bool strict) const {
    const double value = number(node, key);
    if (strict ? !(value > 0.0) : !(value >= 0.0)) {
      fail(node.source(), key, "got " + format(value) + "; must be " + (strict ? "> 0" : ">= 0"));
    }
    return value;
  }
};

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
};

// The settings tables and their keys; anything else is an error.
const std::set<std::string> kTables = {"loop", "space", "optimizer", "search", "steering", "output"};

// A parameter name in [space]: kind and 1-based joint, or a default ("a").
struct ParameterName {
  ParameterKind kind = ParameterKind::a;
  int joint = 0;  // 1-based; 0 for the default of the kind
};

std::optional<ParameterName> parse_parameter_name(const std::string& name) {
  struct Prefix {
    const char* text;
    ParameterKind kind;
    bool degrees;
  };
  // Longest prefixes first: "alpha" before "a".
  static const Prefix prefixes[] = {{"alpha", ParameterKind::alpha, true},
                                    {"theta", ParameterKind::theta, true},
                                    {"a", ParameterKind::a, false},
                                    {"d", ParameterKind::d, false}};
  for (const Prefix& p : prefixes) {
    const std::string prefix = p.text;
    if (name.rfind(prefix, 0) != 0) continue;
    std::string rest = name.substr(prefix.size());
    if (p.degrees) {
      if (rest.size() < 4 || rest.substr(rest.size() - 4) != "_deg") return std::nullopt;
      rest = rest.substr(0, rest.size() - 4);
    }
    if (rest.empty()) return ParameterName{p.kind, 0};
    if (!std::all_of(rest.begin(), rest.end(), [](char c) { return c >= '0' && c <= '9'; })) return std::nullopt;
    if (rest.size() > 2 || rest[0] == '0') return std::nullopt;
    return ParameterName{p.kind, std::stoi(rest)};
  }
  return std::nullopt;
}

bool is_angle(ParameterKind kind) { return kind == ParameterKind::alpha || kind == ParameterKind::theta; }
bool is_length(ParameterKind kind) { return kind == ParameterKind::a || kind == ParameterKind::d; }

// What a tie may point at: lengths to lengths, twists to twists, angles to angles.
bool same_unit(ParameterKind a, ParameterKind b) {
  return (is_length(a) && is_length(b)) || a == b;
}

const char* unit_name(ParameterKind kind) {
  switch (kind) {
    case ParameterKind::a:
    case ParameterKind::d: return "a length (a or d)";
    case ParameterKind::alpha: return "a twist (alpha)";
    case ParameterKind::theta: return "an initial angle (theta)";
  }
  return "";
}

// A tie's text as written: "a1" or "-a1".
struct TieText {
  std::string source;
  double sign = 1.0;
};

ParameterSpec read_spec(const Reader& r, const toml::node& node, const std::string& key, ParameterKind kind,
                        bool allow_tie, std::optional<TieText>* tie) {
  const double unit = is_angle(kind) ? kRadiansPerDegree : 1.0;
  ParameterSpec spec;
  spec.line = static_cast<int>(node.source().begin.line);
  // Lengths beyond kMaxLength overflow the length scale; say so at the value.
  auto check_magnitude = [&](const toml::node& at, double value) {
    if (is_length(kind) && !(std::abs(value) <= kMaxLength)) {
      r.fail(at.source(), key, "got " + format(value) + "; a length must be in [-1e150, 1e150] (larger ones "
                               "overflow the length scale L)");
    }
  };
  if (node.is_integer() || node.is_floating_point()) {
    spec.mode = ParameterSpec::Mode::fixed;
    spec.value = r.number(node, key) * unit;
    check_magnitude(node, spec.value);
    return spec;
  }
  if (const toml::array* range = node.as_array()) {
    if (range->size() != 2) {
      r.fail(node.source(), key, "a range is [lo, hi]; got an array of " + std::to_string(range->size()) + " values");
    }
    const double lo = r.number(*range->get(0), key);
    const double hi = r.number(*range->get(1), key);
    check_magnitude(*range->get(0), lo);
    check_magnitude(*range->get(1), hi);
    if (lo > hi) r.fail(node.source(), key, "range [" + format(lo) + ", " + format(hi) + "] has lo > hi");
    if (lo == hi) {
      spec.mode = ParameterSpec::Mode::fixed;
      spec.value = lo * unit;
    } else {
      spec.mode = ParameterSpec::Mode::range;
      spec.lo = lo * unit;
      spec.hi = hi * unit;
    }
    return spec;
  }
  if (node.is_string()) {
    if (!allow_tie) r.fail(node.source(), key, "a default is a number or a range [lo, hi], not a tie");
    std::string text = r.string(node, key);
    TieText t;
    if (!text.empty() && text[0] == '-') {
      t.sign = -1.0;
      text = text.substr(1);
    }
    t.source = text;
    *tie = t;
    spec.mode = ParameterSpec::Mode::tied;
    spec.sign = t.sign;
    return spec;
  }
  r.fail(node.source(), key,
         "expected a number (fixed), a range [lo, hi] or the name of another parameter (tied), got " +
             Reader::describe(node));
}

// A symmetric sub-space ([space] symmetry, docs/job-file.md): for every
// geometric parameter that the symmetry makes an image of another, the
// source and the sign (image = sign * source); a source of -1 fixes the
// parameter at 0 (an offset on the plane of symmetry). Indices 0-based into
// ParameterSpace::specs; lower joints are the sources.
struct SymmetryTie {
  int image;
  int source;
  double sign;
};

std::vector<SymmetryTie> symmetry_ties(const std::string& symmetry, const ParameterSpace& space) {
  const int n = space.joints;
  std::vector<SymmetryTie> ties;
  auto at = [&](ParameterKind kind, int joint) { return space.index(kind, ((joint % n) + n) % n); };
  if (symmetry == "line") {
    // A half-turn about a line maps joint i to joint i + n/2 and link i to
    // link i + n/2, keeping every parameter (Bricard's line-symmetric 6R).
    for (int i = n / 2; i < n; ++i) {
      for (ParameterKind kind : {ParameterKind::a, ParameterKind::alpha, ParameterKind::d}) {
        ties.push_back({at(kind, i), at(kind, i - n / 2), 1.0});
      }
    }
  } else if (symmetry == "plane") {
    // A reflection in a plane through joints 1 and n/2 + 1 (1-based) maps
    // joint j to joint 2 - j and link i (joint i to i + 1) to link n + 1 - i,
    // run backwards: lengths equal, twists and offsets negated
    // (docs/families.md: the twist sums are 0 in this convention). The
    // offsets of the two joints on the plane are 0.
    for (int i = 0; i < n; ++i) {  // 0-based link i <-> link n - 1 - i
      const int mirror = n - 1 - i;
      if (mirror > i) {
        ties.push_back({at(ParameterKind::a, mirror), at(ParameterKind::a, i), 1.0});
        ties.push_back({at(ParameterKind::alpha, mirror), at(ParameterKind::alpha, i), -1.0});
      }
    }
    for (int j = 0; j < n; ++j) {  // 0-based joint j <-> joint -j
      const int mirror = (n - j) % n;
      if (mirror == j) ties.push_back({at(ParameterKind::d, j), -1, 0.0});
      if (mirror > j) ties.push_back({at(ParameterKind::d, mirror), at(ParameterKind::d, j), -1.0});
    }
  }
  return ties;
}

ParameterSpace read_space(const Reader& r, const toml::table* table, int joints) {
  ParameterSpace space;
  space.joints = joints;
  space.specs.resize(static_cast<size_t>(kParameterKinds * joints));
  // Built-in defaults (docs/job-file.md).
  auto range = [](double lo, double hi) {
    ParameterSpec s;
    s.mode = ParameterSpec::Mode::range;
    s.lo = lo;
    s.hi = hi;
    return s;
  };
  std::array<ParameterSpec, kParameterKinds> defaults = {range(0.5, 5.0), range(0.0, kPi), range(-1.0, 1.0),
                                                         range(-kPi, kPi)};
  std::vector<std::optional<TieText>> ties(space.specs.size());
  std::vector<std::string> keys(space.specs.size());
  std::vector<toml::source_region> places(space.specs.size());
  std::vector<bool> named(space.specs.size(), false);
  std::string symmetry = "none";
  int symmetry_line = 0;

  if (table) {
    // Defaults first, whatever their place in the file.
    for (const auto& [key, node] : *table) {
      const std::string name(key.str());
      const std::string full = "space." + name;
      if (name == "symmetry") {
        symmetry = r.string(node, full);
        if (symmetry != "none" && symmetry != "line" && symmetry != "plane") {
          r.fail(node.source(), full, "got \"" + symmetry + "\"; expected \"none\", \"line\" (a_i = a_{i+n/2}, "
                                      "alpha and d likewise) or \"plane\" (mirror through joints 1 and n/2+1)");
        }
        if (symmetry != "none" && joints % 2 != 0) {
          r.fail(node.source(), full, "\"" + symmetry + "\" needs an even number of joints, the job has " +
                                          std::to_string(joints) + " (write the ties per parameter instead)");
        }
        symmetry_line = static_cast<int>(node.source().begin.line);
        continue;
      }
      const std::optional<ParameterName> p = parse_parameter_name(name);
      if (!p) {
        r.fail(key.source(), full,
               "unknown parameter; expected a1..a" + std::to_string(joints) + ", alpha1_deg.., d1.., theta1_deg.., "
               "a default a, alpha_deg, d, theta_deg, or symmetry");
      }
      if (p->joint > joints) {
        r.fail(key.source(), full, "joint " + std::to_string(p->joint) + " but [loop] joints = " + std::to_string(joints));
      }
      if (p->joint == 0) defaults[static_cast<size_t>(p->kind)] = read_spec(r, node, full, p->kind, false, nullptr);
    }
  }
  for (int kind = 0; kind < kParameterKinds; ++kind) {
    for (int j = 0; j < joints; ++j) {
      const int i = space.index(static_cast<ParameterKind>(kind), j);
      space.specs[static_cast<size_t>(i)] = defaults[static_cast<size_t>(kind)];
      keys[static_cast<size_t>(i)] = "space." + space.name(i);
    }
  }
  if (table) {
    for (const auto& [key, node] : *table) {
      const std::string name(key.str());
      if (name == "symmetry") continue;
      const ParameterName p = *parse_parameter_name(name);
      if (p.joint == 0) continue;
      const int i = space.index(p.kind, p.joint - 1);
      if (name != space.name(i)) {
        r.fail(key.source(), "space." + name, "write it " + space.name(i));  // e.g. a leading zero
      }
      // The symmetry decides its images; only their sources can be given.
      for (const SymmetryTie& t : symmetry_ties(symmetry, space)) {
        if (t.image != i) continue;
        r.fail(key.source(), keys[static_cast<size_t>(i)],
               "symmetry = \"" + symmetry + "\" " +
                   (t.source < 0 ? "fixes " + space.name(i) + " = 0"
                                 : "makes " + space.name(i) + " = " + (t.sign < 0 ? "-" : "") + space.name(t.source) +
                                       "; give " + space.name(t.source) + " instead"));
      }
      space.specs[static_cast<size_t>(i)] = read_spec(r, node, keys[static_cast<size_t>(i)], p.kind, true,
                                                      &ties[static_cast<size_t>(i)]);
      places[static_cast<size_t>(i)] = node.source();
      named[static_cast<size_t>(i)] = true;
    }
  }
  // The symmetry's images are ties (or zeros) too: mark them before the
  // user's ties are resolved, so that a tie to an image is refused as a tie
  // to a tied parameter. Their sources are filled in below.
  for (const SymmetryTie& t : symmetry_ties(symmetry, space)) {
    space.specs[static_cast<size_t>(t.image)].mode =
        t.source < 0 ? ParameterSpec::Mode::fixed : ParameterSpec::Mode::tied;
  }
  // Resolve the ties now that every parameter is known.
  for (size_t i = 0; i < space.specs.size(); ++i) {
    if (!ties[i]) continue;
    const std::string& key = keys[i];
    const std::optional<ParameterName> p = parse_parameter_name(ties[i]->source);
    if (!p || p->joint == 0 || p->joint > joints ||
        space.name(space.index(p->kind, p->joint - 1)) != ties[i]->source) {
      r.fail(places[i], key, "tied to \"" + ties[i]->source + "\", which is not a parameter of this " +
                                 std::to_string(joints) + "-joint loop");
    }
    const int source = space.index(p->kind, p->joint - 1);
    const ParameterKind kind = static_cast<ParameterKind>(static_cast<int>(i) / joints);
    if (source == static_cast<int>(i)) r.fail(places[i], key, "tied to itself");
    if (!same_unit(kind, p->kind)) {
      r.fail(places[i], key, "tied to " + ties[i]->source + ", " + unit_name(p->kind) + "; " + space.name(static_cast<int>(i)) +
                                 " is " + unit_name(kind));
    }
    if (space.specs[static_cast<size_t>(source)].mode == ParameterSpec::Mode::tied) {
      r.fail(places[i], key, "tied to " + ties[i]->source + ", which is itself tied; tie to its source instead");
    }
    space.specs[i].source = source;
  }
  // The symmetry's images follow their sources: tied to the source, or to
  // the source's own source where the user tied it (ties never chain).
  for (const SymmetryTie& t : symmetry_ties(symmetry, space)) {
    ParameterSpec& image = space.specs[static_cast<size_t>(t.image)];
    image = ParameterSpec{};
    image.line = symmetry_line;
    if (t.source < 0) {
      image.mode = ParameterSpec::Mode::fixed;
      image.value = 0.0;
      continue;
    }
    const ParameterSpec& source = space.specs[static_cast<size_t>(t.source)];
    image.mode = ParameterSpec::Mode::tied;
    image.source = source.mode == ParameterSpec::Mode::tied ? source.source : t.source;
    image.sign = source.mode == ParameterSpec::Mode::tied ? t.sign * source.sign : t.sign;
  }
  // Link lengths must stay >= 0 whatever the search does.
  for (int j = 0; j < joints; ++j) {
    const size_t i = static_cast<size_t>(space.index(ParameterKind::a, j));
    const ParameterSpec& s = space.specs[i];
    double lo = 0.0;
    switch (s.mode) {
      case ParameterSpec::Mode::fixed: lo = s.value; break;
      case ParameterSpec::Mode::range: lo = s.lo; break;
      case ParameterSpec::Mode::tied: {
        const ParameterSpec& src = space.specs[static_cast<size_t>(s.source)];
        const double src_lo = src.mode == ParameterSpec::Mode::fixed ? src.value : src.lo;
        const double src_hi = src.mode == ParameterSpec::Mode::fixed ? src.value : src.hi;
        lo = s.sign > 0 ? src_lo : -src_hi;
        break;
      }
    }
    if (lo < 0.0) {
      const std::string why = s.mode == ParameterSpec::Mode::tied ? "the tie can make it " + format(lo)
                                                                   : "it can be " + format(lo);
      const toml::source_region where = named[i] ? places[i] : toml::source_region{};
      r.fail(where, keys[i], "a link length must be >= 0, but " + why);
    }
  }
  return space;
}

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
      r.fail(key.source(), k, "unknown table or key; a job has [loop], [space], [optimizer], [search], "
                              "[steering] and [output]");
    }
    r.table(node, k);
  }
  auto section = [&](const char* name) -> const toml::table* {
    const toml::node* node = root.get(name);
    return node ? node->as_table() : nullptr;
  };

  if (const toml::table* t = section("loop")) {
    for_each_key(r, *t, "loop", {"joints", "compliance", "stiffness_ratio", "samples", "range_deg", "closure_tolerance",
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
                       r.fail(node.source(), full, "got \"" + c + "\"; expected \"paper\" (a and alpha springy) or "
                                                   "\"full\" (a, alpha and d)");
                     }
                     // Checked just above; not compliance_from_string, which lives in the
                     // equilibrium solver, so that the parser stands alone (fuzz/).
                     job.loop.compliance = c == "full" ? Compliance::full : Compliance::paper;
                   } else if (k == "stiffness_ratio") {
                     job.loop.stiffness_ratio = r.positive(node, full, true);
                   } else if (k == "samples") {
                     const long long n = r.integer(node, full);
                     if (n < 4 || n > 100000) r.fail(node.source(), full, "got " + std::to_string(n) + "; must be in [4, 100000]");
                     job.loop.samples = static_cast<int>(n);
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
    for_each_key(r, *t, "optimizer",
                 {"algorithm", "xtol_rel", "ftol_rel", "ftol_abs", "stopval", "max_evaluations", "time_limit_s",
                  "reuse_nearby_cycle"},
                 [&](const std::string& k, const std::string& full, const toml::node& node) {
                   if (k == "algorithm") {
                     job.optimizer.algorithm = r.string(node, full);
                     const std::string& a = job.optimizer.algorithm;
                     if (a == "GD_STOGO" || a == "GD_STOGO_RAND" || a == "GN_AGS") {
                       r.fail(node.source(), full, "\"" + a + "\" is not built into Debian's NLopt");
                     }
                     if (!is_known_algorithm(a)) {
                       r.fail(node.source(), full, "unknown algorithm \"" + a + "\"; expected \"gauss-newton\" or an "
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
                     const long long n = r.integer(node, full);
                     if (n <= 0 || n > 100000000) r.fail(node.source(), full, "got " + std::to_string(n) + "; must be in [1, 1e8]");
                     job.optimizer.max_evaluations = static_cast<int>(n);
                   } else if (k == "time_limit_s") {
                     job.optimizer.time_limit = r.positive(node, full, false);
                   } else if (k == "reuse_nearby_cycle") {
                     job.optimizer.reuse_nearby_cycle = r.boolean(node, full);
                   }
                 });
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
    for_each_key(r, *t, "steering", {"nontrivial", "min_travel_deg", "deflate", "deflation_power", "deflation_shift"},
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
                       r.fail(node.source(), full, "expected a list of families such as [\"planar\", \"trivial\"], got " +
                                                       Reader::describe(node));
                     }
                     for (const toml::node& item : *list) {
                       const std::string family = r.string(item, full);
                       const DeflatableFamily* known = nullptr;
                       std::string names;
                       for (const DeflatableFamily& f : kDeflatable) {
                         if (family == f.name) known = &f;
                         names += std::string(names.empty() ? "" : ", ") + f.name;
                       }
                       if (known == nullptr) {
                         r.fail(item.source(), full, "unknown family \"" + family + "\"; expected one of " + names);
                       }
                       if (known->joints != 0 && known->joints != job.loop.joints) {
                         r.fail(item.source(), full, "\"" + family + "\" needs joints = " +
                                                         std::to_string(known->joints) + " (" + known->why +
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
      // Relative to the job file, so that a job runs the same from anywhere.
      const std::filesystem::path p(path);
      job.output.database = p.is_absolute() || file.empty()
                                ? path
                                : (std::filesystem::path(file).parent_path() / p).lexically_normal().string();
    });
    if (!t->contains("database")) {
      job.output.database =
          (std::filesystem::path(file).parent_path() / job.output.database).lexically_normal().string();
    }
  } else {
    job.output.database =
        (std::filesystem::path(file).parent_path() / job.output.database).lexically_normal().string();
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


// ---------------------------------------------------------------------------
// find_toml_hazard: a small lexer that knows just enough TOML (comments, the
// four kinds of string, table headers, arrays and inline tables) to find the
// two constructs toml++ 3.3 mishandles (job.hpp).

namespace {

bool is_bare_key_char(unsigned char c) {
  return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_' || c == '-';
}

// "U+02DE" for a valid UTF-8 sequence at `at`, else "byte 0xCB".
std::string describe_non_ascii(std::string_view text, size_t at) {
  const auto byte = [&](size_t i) { return i < text.size() ? static_cast<unsigned char>(text[i]) : 0u; };
  const unsigned lead = byte(at);
  int length = 0;
  unsigned code = 0;
  if ((lead & 0xE0) == 0xC0) {
    length = 2;
    code = lead & 0x1F;
  } else if ((lead & 0xF0) == 0xE0) {
    length = 3;
    code = lead & 0x0F;
  } else if ((lead & 0xF8) == 0xF0) {
    length = 4;
    code = lead & 0x07;
  }
  bool valid = length > 0;
  for (int k = 1; valid && k < length; ++k) {
    const unsigned next = byte(at + static_cast<size_t>(k));
    valid = (next & 0xC0) == 0x80;
    code = (code << 6) | (next & 0x3F);
  }
  char buffer[32];
  if (valid) {
    std::snprintf(buffer, sizeof buffer, "U+%04X", code);
  } else {
    std::snprintf(buffer, sizeof buffer, "byte 0x%02X", lead);
  }
  return buffer;
}

}  // namespace

std::optional<TomlHazard> find_toml_hazard(std::string_view text) {
  size_t i = 0;
  int line = 1;
  size_t line_start = 0;
  const auto at = [&](size_t k) -> unsigned char { return k < text.size() ? static_cast<unsigned char>(text[k]) : 0; };
  const auto hazard = [&](size_t k, std::string message) {
    return TomlHazard{line, static_cast<int>(k - line_start) + 1, std::move(message)};
  };
  const auto newline = [&](size_t k) {  // `k` is the '\n'
    ++line;
    line_start = k + 1;
  };
  // A UTF-8 byte order mark is allowed at the very start.
  if (text.substr(0, 3) == "\xEF\xBB\xBF") i = 3;
  std::string open;           // the [ of arrays and { of inline tables now open, innermost last
  bool statement_start = true;  // at the start of a line outside any value
  bool in_header = false;     // inside [table] or [[array.of.tables]]
  unsigned char prev = '\n';  // the last character outside strings, blanks and comments
  while (i < text.size()) {
    const unsigned char c = at(i);
    if (c == '\n') {
      newline(i);
      ++i;
      // Inside an array a newline is only a blank: "[1,\n0a='x'" still has a
      // value after the comma, which toml++ scans as such.
      if (open.empty()) prev = '\n';
      in_header = false;
      statement_start = open.empty();
      continue;
    }
    if (c == ' ' || c == '\t' || c == '\r') {
      ++i;
      continue;
    }
    if (c == '#') {  // a comment: anything up to the end of the line
      while (i < text.size() && at(i) != '\n') ++i;
      continue;
    }
    if (c >= 0x80) {
      return hazard(i, "non-ASCII character " + describe_non_ascii(text, i) +
                           " outside a string or comment (TOML allows it only inside quotes or after #)");
    }
    if (statement_start && c == '[') {
      // A table header: the name must begin with a bare-key character or a quote.
      statement_start = false;
      in_header = true;
      size_t k = i + 1;
      if (at(k) == '[') ++k;
      while (at(k) == ' ' || at(k) == '\t') ++k;
      const unsigned char first = at(k);
      // At the end of the text toml++ reports the error itself; "[ [" too.
      if (k < text.size() && first != ']' && first != '[' && !is_bare_key_char(first) && first != '"' &&
          first != '\'') {
        std::string what;
        if (first >= 0x80) {
          what = "non-ASCII character " + describe_non_ascii(text, k);
        } else if (first < 0x20 || first == 0x7F) {
          char buffer[16];  // a control character or newline: named, so the message stays one line
          std::snprintf(buffer, sizeof buffer, "byte 0x%02X", first);
          what = buffer;
        } else {
          what = std::string("'") + static_cast<char>(first) + "'";
        }
        return hazard(k, "a table header must begin with a name, not " + what);
      }
      if (first == '[' && at(i + 1) == '[') {
        return hazard(k, "a table header must begin with a name, not '['");
      }
      i = k;
      prev = '[';
      continue;
    }
    statement_start = false;
    // A value that starts with neither a quote, [ nor {: toml++ scans it up
    // to the next blank, ], }, ',' or # (quotes and brackets inside belong to
    // it: "0xfl['x"), testing every character for whitespace.
    const bool value_may_begin = prev == '=' || ((prev == '[' || prev == ',') && !open.empty() && open.back() == '[');
    if (value_may_begin && !in_header && c != '"' && c != '\'' && c != '[' && c != '{' && c != ']' && c != '}' &&
        c != ',') {
      size_t k = i;
      while (k < text.size() && at(k) != ' ' && at(k) != '\t' && at(k) != '\n' && at(k) != '\r' && at(k) != '\v' &&
             at(k) != '\f' && at(k) != ']' && at(k) != '}' && at(k) != ',' && at(k) != '#') {
        if (at(k) >= 0x80) {
          return hazard(k, "non-ASCII character " + describe_non_ascii(text, k) +
                               " outside a string or comment (TOML allows it only inside quotes or after #)");
        }
        ++k;
      }
      if (k > i) {  // else c is a terminator itself (\v, \f): taken below like any other character
        prev = at(k - 1);
        i = k;
        continue;
      }
    }
    // A quote opens a string only where TOML lets one begin: a key or a
    // value. Elsewhere ("0'x'") toml++ reads it as part of a bare value and
    // tests the characters after it, so this lexer must not skip them either.
    const bool string_may_begin =
        prev == '\n' || prev == '=' || prev == '[' || prev == ',' || prev == '{' || prev == '.';
    if ((c == '"' || c == '\'') && string_may_begin) {
      const bool multi = at(i + 1) == c && at(i + 2) == c;
      if (multi) {
        i += 3;
        while (i < text.size() && !(at(i) == c && at(i + 1) == c && at(i + 2) == c)) {
          if (at(i) == '\n') newline(i);
          if (c == '"' && at(i) == '\\') {
            // toml++ tests what follows a backslash here for whitespace: the
            // escaped character itself, the blanks after it, and after a
            // line-ending backslash the first character of the next text.
            const auto refuse = [&](size_t where, const char* context) {
              return hazard(where, "non-ASCII character " + describe_non_ascii(text, where) + " " + context +
                                       " in a multi-line string (toml++ 3.3 cannot read it; escape it as \\uXXXX)");
            };
            size_t k = i + 1;
            if (at(k) >= 0x80) return refuse(k, "right after a backslash");
            bool blank = false;
            while (at(k) == ' ' || at(k) == '\t') {
              ++k;
              blank = true;
            }
            if (blank && at(k) >= 0x80) return refuse(k, "after a backslash and blanks");
            if (at(k) == '\n' || (at(k) == '\r' && at(k + 1) == '\n')) {
              while (k < text.size() && (at(k) == ' ' || at(k) == '\t' || at(k) == '\r' || at(k) == '\n')) {
                if (at(k) == '\n') newline(k);
                ++k;
              }
              if (at(k) >= 0x80) return refuse(k, "right after a line-ending backslash");
              i = k;
              continue;
            }
            i += 2;  // an escape: skip the escaped character (a quote, say)
            continue;
          }
          ++i;
        }
        i += 3;
        prev = c;
        continue;
      }
      ++i;
      while (i < text.size() && at(i) != c && at(i) != '\n') {
        i += c == '"' && at(i) == '\\' && at(i + 1) != '\n' ? 2 : 1;
      }
      if (at(i) == c) ++i;
      prev = c;
      continue;
    }
    prev = c;
    if (!in_header) {
      if (c == '[' || c == '{') open += static_cast<char>(c);
      if ((c == ']' || c == '}') && !open.empty()) open.pop_back();
    }
    ++i;
  }
  return std::nullopt;
}

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
