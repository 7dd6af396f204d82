// The [space] table of a job file (job.hpp, docs/guide/job-file.md): parameter
// ranges and fixed values, ties between parameters and symmetric sub-spaces.
#include <array>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "job_reader.hpp"

namespace loopfarm::detail {
namespace {

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
bool same_unit(ParameterKind a, ParameterKind b) { return (is_length(a) && is_length(b)) || a == b; }

const char* unit_name(ParameterKind kind) {
  switch (kind) {
    case ParameterKind::a:
    case ParameterKind::d:
      return "a length (a or d)";
    case ParameterKind::alpha:
      return "a twist (alpha)";
    case ParameterKind::theta:
      return "an initial angle (theta)";
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
      r.fail(at.source(), key,
             "got " + format(value) +
                 "; a length must be in [-1e150, 1e150] (larger ones "
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

// A symmetric sub-space ([space] symmetry, docs/guide/job-file.md): for every
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
    // (docs/guide/families.md: the twist sums are 0 in this convention). The
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

}  // namespace

ParameterSpace read_space(const Reader& r, const toml::table* table, int joints) {
  ParameterSpace space;
  space.joints = joints;
  space.specs.resize(static_cast<size_t>(kParameterKinds * joints));
  // Built-in defaults (docs/guide/job-file.md).
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
          r.fail(node.source(), full,
                 "got \"" + symmetry +
                     "\"; expected \"none\", \"line\" (a_i = a_{i+n/2}, "
                     "alpha and d likewise) or \"plane\" (mirror through joints 1 and n/2+1)");
        }
        if (symmetry != "none" && joints % 2 != 0) {
          r.fail(node.source(), full,
                 "\"" + symmetry + "\" needs an even number of joints, the job has " + std::to_string(joints) +
                     " (write the ties per parameter instead)");
        }
        symmetry_line = static_cast<int>(node.source().begin.line);
        continue;
      }
      const std::optional<ParameterName> p = parse_parameter_name(name);
      if (!p) {
        r.fail(key.source(), full,
               "unknown parameter; expected a1..a" + std::to_string(joints) +
                   ", alpha1_deg.., d1.., theta1_deg.., "
                   "a default a, alpha_deg, d, theta_deg, or symmetry");
      }
      if (p->joint > joints) {
        r.fail(key.source(), full,
               "joint " + std::to_string(p->joint) + " but [loop] joints = " + std::to_string(joints));
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
      space.specs[static_cast<size_t>(i)] =
          read_spec(r, node, keys[static_cast<size_t>(i)], p.kind, true, &ties[static_cast<size_t>(i)]);
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
    if (!p || p->joint == 0 || p->joint > joints || space.name(space.index(p->kind, p->joint - 1)) != ties[i]->source) {
      r.fail(places[i], key,
             "tied to \"" + ties[i]->source + "\", which is not a parameter of this " + std::to_string(joints) +
                 "-joint loop");
    }
    const int source = space.index(p->kind, p->joint - 1);
    const ParameterKind kind = static_cast<ParameterKind>(static_cast<int>(i) / joints);
    if (source == static_cast<int>(i)) r.fail(places[i], key, "tied to itself");
    if (!same_unit(kind, p->kind)) {
      r.fail(places[i], key,
             "tied to " + ties[i]->source + ", " + unit_name(p->kind) + "; " + space.name(static_cast<int>(i)) +
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
      case ParameterSpec::Mode::fixed:
        lo = s.value;
        break;
      case ParameterSpec::Mode::range:
        lo = s.lo;
        break;
      case ParameterSpec::Mode::tied: {
        const ParameterSpec& src = space.specs[static_cast<size_t>(s.source)];
        const double src_lo = src.mode == ParameterSpec::Mode::fixed ? src.value : src.lo;
        const double src_hi = src.mode == ParameterSpec::Mode::fixed ? src.value : src.hi;
        lo = s.sign > 0 ? src_lo : -src_hi;
        break;
      }
    }
    if (lo < 0.0) {
      const std::string why =
          s.mode == ParameterSpec::Mode::tied ? "the tie can make it " + format(lo) : "it can be " + format(lo);
      const toml::source_region where = named[i] ? places[i] : toml::source_region{};
      r.fail(where, keys[i], "a link length must be >= 0, but " + why);
    }
  }
  return space;
}

}  // namespace loopfarm::detail
