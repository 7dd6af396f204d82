#include "atlas.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <optional>
#include <span>
#include <tuple>
#include <utility>

#include <Eigen/Geometry>

#include "candidate_display.hpp"
#include "cli_support.hpp"
#include "loopfarm/core/assembly.hpp"
#include "loopfarm/core/cycle.hpp"
#include "loopfarm/core/equilibrium.hpp"
#include "loopfarm/core/loop.hpp"
#include "loopfarm/search/classify.hpp"
#include "loopfarm/search/verify.hpp"
#include "plot.hpp"

namespace loopfarm::cli {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDegreesPerRadian = 180.0 / kPi;
constexpr int kFrames = 8;  // frames in the motion strip

std::string g(double v, int digits = 4) { return format_significant(v, digits); }

// A geometry as a fenced Markdown block, 9 significant digits, round-off of a zero as 0.
std::string parameter_block(const CandidateRow& r) {
  const double length = kRoundOff * scale_of(r);
  return "\n```\na     = " + shown_list(r.a, length, 9, ", ") +
         "\nalpha = " + shown_list(r.alpha_deg, kAngleRoundOffDeg, 9, ", ") +
         " deg\nd     = " + shown_list(r.d, length, 9, ", ") + "\n```\n";
}

struct Spread {
  double min = kNaN, median = kNaN, max = kNaN;
  int count = 0;
};

Spread spread(std::vector<double> values) {
  values.erase(std::remove_if(values.begin(), values.end(), [](double v) { return std::isnan(v); }), values.end());
  Spread s;
  s.count = static_cast<int>(values.size());
  if (values.empty()) return s;
  std::sort(values.begin(), values.end());
  const size_t n = values.size();
  s.min = values.front();
  s.max = values.back();
  s.median = n % 2 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
  return s;
}

// What a found local dimension says against the known one.
std::string dimension_reading(int found, std::optional<int> known, int free_parameters, int joints) {
  if (found < 0) return "unknown: the deformation Jacobian had an entry that is not finite";
  if (!known) return "no single known dimension to compare with";
  if (found == *known) return "as known";
  if (found > *known) {
    return "more than known: the point lies on a larger family of movable loops (or the zero set is not "
           "regular there)";
  }
  if (free_parameters < 3 * joints) {
    return "less than known: the search space (" + std::to_string(free_parameters) + " of " +
           std::to_string(3 * joints) + " parameters) may hold only part of the family at this point";
  }
  return "less than known";
}

// The joint a cycle drives and the circuit it runs on (an index into the
// motion's circuits), as compute_cycle chooses them.
struct Drive {
  int joint = 0;
  int circuit = -1;
};

// The first joint (canonical numbering) that turns fully on a moving
// circuit, on the first such circuit; else joint 1 on the moving circuit
// where it travels farthest, or, where joint 1 moves on none, the joint that
// travels farthest (the first of equals); nothing when no circuit moves.
std::optional<Drive> drive_of(const MotionAnalysis& motion, const VerificationOptions& options) {
  const std::vector<Circuit>& circuits = motion.circuits;
  const auto moves = [&](const Circuit& c, int joint) {
    return static_cast<int>(c.ranges.size()) > joint &&
           c.moves(joint, options.min_input_travel, options.residual_tolerance);
  };
  int n = 0;
  for (const Circuit& c : circuits) n = std::max(n, static_cast<int>(c.ranges.size()));
  for (int j = 0; j < n; ++j) {
    for (size_t c = 0; c < circuits.size(); ++c) {
      if (moves(circuits[c], j) && circuits[c].ranges[static_cast<size_t>(j)].crank()) {
        return Drive{j, static_cast<int>(c)};
      }
    }
  }
  // No joint turns fully: the farthest travel of joint j, and where.
  const auto farthest = [&](int j) {
    Drive best{j, -1};
    double travel = 0.0;
    for (size_t c = 0; c < circuits.size(); ++c) {
      if (!moves(circuits[c], j)) continue;
      const JointRange& r = circuits[c].ranges[static_cast<size_t>(j)];
      if (r.hi - r.lo >= options.min_input_travel && r.hi - r.lo > travel) {
        travel = r.hi - r.lo;
        best.circuit = static_cast<int>(c);
      }
    }
    return std::make_pair(best, travel);
  };
  if (const Drive first = farthest(0).first; first.circuit >= 0) return first;
  std::optional<Drive> out;
  double most = 0.0;
  for (int j = 1; j < n; ++j) {
    const auto [drive, travel] = farthest(j);
    if (drive.circuit >= 0 && travel > most) {
      most = travel;
      out = drive;
    }
  }
  return out;
}

void write_text(const std::filesystem::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
  out.close();
  if (!out) throw EnvironmentError("--atlas: cannot write " + path.string());
}

}  // namespace

std::optional<int> known_family_dimension(const std::string& family, int joints) {
  const std::optional<Family> f = family_from_string(family);
  return f ? family_dimension(*f, joints) : std::nullopt;
}

std::string atlas_stem(const std::string& family, int joints) {
  std::string stem = std::to_string(joints) + "r_";
  for (char c : family) stem += (std::isalnum(static_cast<unsigned char>(c)) || c == '_') ? c : '-';
  return stem;
}

// Unclassified first (possible new families), then the most candidates, then by name.
std::vector<FamilyGroup> group_by_family(const std::vector<CandidateRow>& rows) {
  std::map<std::pair<int, std::string>, FamilyGroup> groups;
  for (const CandidateRow& r : rows) {
    FamilyGroup& group = groups[{r.joints, r.family}];
    group.joints = r.joints;
    group.family = r.family;
    group.rows.push_back(&r);
    group.hits += r.hits;
  }
  std::vector<FamilyGroup> out;
  for (auto& [key, group] : groups) out.push_back(std::move(group));
  std::stable_sort(out.begin(), out.end(), [](const FamilyGroup& x, const FamilyGroup& y) {
    const bool xu = x.family == "unclassified", yu = y.family == "unclassified";
    if (xu != yu) return xu;
    if (x.rows.size() != y.rows.size()) return x.rows.size() > y.rows.size();
    return std::make_pair(x.joints, x.family) < std::make_pair(y.joints, y.family);
  });
  return out;
}

// The representative: a full turn first (the whole motion can be shown), then
// the smallest rigid-closure residual along the verified motion, then the
// lowest energy, then the first committed.
const CandidateRow& representative(const FamilyGroup& group) {
  auto rank = [](const CandidateRow* r) {
    const double rigid = std::isnan(r->rigid_residual) ? 1e300 : r->rigid_residual;
    const double energy = std::isnan(r->E_mean) ? 1e300 : r->E_mean;
    return std::make_tuple(!r->full_turn, rigid, energy, r->id);
  };
  return **std::min_element(group.rows.begin(), group.rows.end(),
                            [&](const CandidateRow* x, const CandidateRow* y) { return rank(x) < rank(y); });
}

// "4 (572), 5 (7)": the local dimensions found and how many candidates each.
std::string dimension_counts(const FamilyGroup& group) {
  std::map<int, int> counts;
  for (const CandidateRow* r : group.rows) ++counts[r->local_dimension];
  std::string out;
  for (const auto& [dimension, count] : counts) {
    out += (out.empty() ? "" : ", ") + dimension_text(dimension) + " (" + std::to_string(count) + ")";
  }
  return out;
}

std::string free_parameter_counts(const FamilyGroup& group) {
  std::map<int, int> counts;
  for (const CandidateRow* r : group.rows) ++counts[r->free_parameters];
  std::string out;
  for (const auto& [free, count] : counts) out += (out.empty() ? "" : ", ") + std::to_string(free);
  return out;
}

// The cycle energy of the representative's canonical geometry along its
// rigid loop's motion (atlas.hpp says which joint drives it and where).
Representation compute_cycle(const CandidateRow& r) {
  const LoopGeometry geometry = LoopGeometry::from_degrees(
      std::span<const double>(r.a), std::span<const double>(r.alpha_deg), std::span<const double>(r.d));
  Representation out;
  CycleOptions cycle_options;
  cycle_options.samples = kAtlasCycleSamples;
  VerificationOptions options;
  std::optional<VerificationSummary> verification;
  try {
    verification = verify_motion(geometry, nullptr, options);
  } catch (const std::invalid_argument&) {
    // Not a loop the tracer takes: cycled as below, which says what it can.
  }
  const std::optional<Drive> drive = verification ? drive_of(verification->motion, options) : std::nullopt;
  if (drive) {
    // motion_window starts a cycle on the reported circuit, its input the
    // options' input joint: report the chosen circuit, driven by the chosen joint.
    verification->circuit = drive->circuit;
    verification->verified = true;
    verification->on_motion = false;
    options.input_joint = drive->joint;
    const std::optional<MotionWindow> window =
        motion_window(geometry, *verification, std::nullopt, options, kAtlasCycleSamples);
    if (window && window->range > 0.0) {
      // The driven joint as the model's joint 1 (its input).
      const LoopModel model(relabelled(geometry, drive->joint));
      EquilibriumWorkspace workspace(model);
      out.input_joint = drive->joint;
      out.theta0 = window->theta0;
      out.full_turn = window->range >= 2.0 * kPi;
      out.on_motion = true;
      out.circuit = std::move(verification->motion.circuits[static_cast<size_t>(drive->circuit)]);
      cycle_options.range = window->range;
      const EquilibriumSummary assembly =
          assemble_from_angles(model, workspace, relabelled_angles(window->pose, drive->joint));
      cycle_energy(model, workspace, out.theta0, assembly.state, cycle_options, out.cycle);
      return out;
    }
  }
  const LoopModel model(geometry);
  EquilibriumWorkspace workspace(model);
  const EquilibriumSummary assembly = assemble(model, workspace, out.theta0);
  cycle_energy(model, workspace, out.theta0, assembly.state, cycle_options, out.cycle);
  return out;
}

std::string input_name(const Representation& rep) { return "theta" + std::to_string(rep.input_joint + 1); }

void pick_frames(const Representation& rep, int count, std::vector<std::vector<double>>& theta,
                 std::vector<double>& input_deg) {
  std::vector<const CycleSample*> samples;
  for (const CycleSample& s : rep.cycle.samples) {
    if (s.status != SampleStatus::failed) samples.push_back(&s);
  }
  std::sort(samples.begin(), samples.end(),
            [](const CycleSample* x, const CycleSample* y) { return x->theta_in < y->theta_in; });
  if (samples.empty()) return;
  const int frames = std::min<int>(count, static_cast<int>(samples.size()));
  for (int k = 0; k < frames; ++k) {
    // A full turn: k/frames of the turn; a range: both ends included.
    const double position =
        rep.full_turn ? static_cast<double>(k) / frames : (frames > 1 ? static_cast<double>(k) / (frames - 1) : 0.0);
    const size_t index = std::min(samples.size() - 1, static_cast<size_t>(std::lround(position * samples.size())));
    // The cycle's model numbers the driven joint 1: back to the canonical numbering.
    const JointVector canonical = relabelled_angles(samples[index]->state.theta, -rep.input_joint);
    theta.emplace_back(canonical.data(), canonical.data() + canonical.size());
    input_deg.push_back(samples[index]->theta_in * kDegreesPerRadian);
  }
}

std::vector<JointPlacement> joint_placements(const LoopGeometry& geometry, const std::vector<double>& theta) {
  const int n = geometry.joints();
  JointVector t(n);
  for (int i = 0; i < n; ++i) t[i] = theta[static_cast<size_t>(i)];
  std::vector<JointPlacement> joints;
  for (int i = 0; i < n; ++i) {
    const Eigen::Isometry3d f = forward_transform(geometry, t, i);
    JointPlacement j;
    j.o = f.translation();
    j.z = f.linear().col(2);
    j.p = j.o + geometry.d[i] * j.z;
    joints.push_back(j);
  }
  return joints;
}

std::string motion_strip_svg(const CandidateRow& row, const std::vector<std::vector<double>>& theta,
                             const std::vector<double>& input_deg, const std::string& input, const std::string& title) {
  const LoopGeometry geometry = LoopGeometry::from_degrees(
      std::span<const double>(row.a), std::span<const double>(row.alpha_deg), std::span<const double>(row.d));
  const int n = geometry.joints();
  // A fixed oblique view: azimuth 35 deg, elevation 25 deg, orthographic.
  const double az = 35.0 / kDegreesPerRadian, el = 25.0 / kDegreesPerRadian;
  const Eigen::Vector3d right(-std::sin(az), std::cos(az), 0.0);
  const Eigen::Vector3d up(-std::sin(el) * std::cos(az), -std::sin(el) * std::sin(az), std::cos(el));
  using Joint = JointPlacement;
  std::vector<std::vector<Joint>> frames;
  double xmin = 1e300, xmax = -1e300, ymin = 1e300, ymax = -1e300;
  auto project = [&](const Eigen::Vector3d& v) { return std::make_pair(v.dot(right), -v.dot(up)); };
  for (const std::vector<double>& angles : theta) {
    std::vector<Joint> joints = joint_placements(geometry, angles);
    for (int i = 0; i < n; ++i) {
      const Joint& j = joints[static_cast<size_t>(i)];
      const double lo = std::min(0.0, geometry.d[i]) - kAxisHalf, hi = std::max(0.0, geometry.d[i]) + kAxisHalf;
      for (const Eigen::Vector3d& v : {Eigen::Vector3d(j.o + lo * j.z), Eigen::Vector3d(j.o + hi * j.z)}) {
        const auto [x, y] = project(v);
        xmin = std::min(xmin, x), xmax = std::max(xmax, x), ymin = std::min(ymin, y), ymax = std::max(ymax, y);
      }
    }
    frames.push_back(std::move(joints));
  }
  constexpr double kPanel = 240.0, kMargin = 16.0, kTop = 34.0, kBottom = 26.0;
  const double extent = std::max({xmax - xmin, ymax - ymin, 1e-9});
  const double scale = (kPanel - 2 * kMargin) / extent;
  const double width = kPanel * static_cast<double>(std::max<size_t>(frames.size(), 1));
  const double height = kTop + kPanel + kBottom;
  char buffer[512];
  std::string svg;
  std::snprintf(
      buffer, sizeof buffer,
      "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%.0f\" height=\"%.0f\" viewBox=\"0 0 %.0f %.0f\" "
      "font-family=\"sans-serif\" font-size=\"12\">\n<rect width=\"100%%\" height=\"100%%\" fill=\"white\"/>\n",
      width, height, width, height);
  svg += buffer;
  std::string escaped;
  for (char c : title) escaped += c == '<' ? "&lt;" : c == '>' ? "&gt;" : c == '&' ? "&amp;" : std::string(1, c);
  svg += "<text x=\"8\" y=\"20\" font-size=\"14\">" + escaped + "</text>\n";
  const char* colours[] = {"#d62728", "#1f77b4", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b", "#e377c2", "#17becf"};
  for (size_t k = 0; k < frames.size(); ++k) {
    const double x0 =
        kPanel * static_cast<double>(k) + kMargin - xmin * scale + 0.5 * (kPanel - 2 * kMargin - (xmax - xmin) * scale);
    const double y0 = kTop + kMargin - ymin * scale + 0.5 * (kPanel - 2 * kMargin - (ymax - ymin) * scale);
    auto screen = [&](const Eigen::Vector3d& v) {
      const auto [x, y] = project(v);
      return std::make_pair(x0 + x * scale, y0 + y * scale);
    };
    std::snprintf(buffer, sizeof buffer,
                  "<g><rect x=\"%.1f\" y=\"%.1f\" width=\"%.1f\" height=\"%.1f\" fill=\"none\" stroke=\"#ccc\"/>\n",
                  kPanel * static_cast<double>(k) + 2, kTop, kPanel - 4, kPanel);
    svg += buffer;
    const std::vector<Joint>& joints = frames[k];
    // Joint axes, dashed, in the joint's colour.
    for (int i = 0; i < n; ++i) {
      const Joint& j = joints[static_cast<size_t>(i)];
      const double lo = std::min(0.0, geometry.d[i]) - kAxisHalf, hi = std::max(0.0, geometry.d[i]) + kAxisHalf;
      const auto [ax, ay] = screen(j.o + lo * j.z);
      const auto [bx, by] = screen(j.o + hi * j.z);
      std::snprintf(buffer, sizeof buffer,
                    "<line x1=\"%.2f\" y1=\"%.2f\" x2=\"%.2f\" y2=\"%.2f\" stroke=\"%s\" stroke-width=\"1.5\" "
                    "stroke-dasharray=\"5,3\"/>\n",
                    ax, ay, bx, by, colours[i % 8]);
      svg += buffer;
    }
    // Links: along axis i by the offset (O_i to P_i), then the common normal to O_{i+1}.
    std::string points;
    for (int i = 0; i <= n; ++i) {
      const Joint& j = joints[static_cast<size_t>(i % n)];
      const auto [ox, oy] = screen(j.o);
      std::snprintf(buffer, sizeof buffer, "%.2f,%.2f ", ox, oy);
      points += buffer;
      if (i == n) break;
      const auto [px, py] = screen(j.p);
      std::snprintf(buffer, sizeof buffer, "%.2f,%.2f ", px, py);
      points += buffer;
    }
    svg += "<polyline points=\"" + points +
           "\" fill=\"none\" stroke=\"black\" stroke-width=\"2.5\" "
           "stroke-linejoin=\"round\"/>\n";
    // Joints: a dot where each link meets its axis, numbered 1..n.
    for (int i = 0; i < n; ++i) {
      const Joint& j = joints[static_cast<size_t>(i)];
      const auto [px, py] = screen(j.p);
      std::snprintf(buffer, sizeof buffer,
                    "<circle cx=\"%.2f\" cy=\"%.2f\" r=\"4\" fill=\"%s\"/><text x=\"%.2f\" y=\"%.2f\" fill=\"%s\">%d"
                    "</text>\n",
                    px, py, colours[i % 8], px + 5, py - 5, colours[i % 8], i + 1);
      svg += buffer;
    }
    std::snprintf(buffer, sizeof buffer,
                  "<text x=\"%.1f\" y=\"%.1f\" text-anchor=\"middle\">%s = %.0f deg</text></g>\n",
                  kPanel * (static_cast<double>(k) + 0.5), kTop + kPanel + 18, input.c_str(), input_deg[k]);
    svg += buffer;
  }
  svg += "</svg>\n";
  return svg;
}

std::string representative_sentence(const CandidateRow& r) {
  return "Representative: candidate " + std::to_string(r.id) + " (first found by run " + std::to_string(r.first_run) +
         ", start " + std::to_string(r.first_start) + "; " + count_of(r.hits, "hit") + "), E_mean " + g(r.E_mean, 3) +
         ", rigid residual " + g(r.rigid_residual, 2) + ", family residual " + g(r.family_residual, 2) +
         ", local dimension " + dimension_text(r.local_dimension) + (r.local_dimension >= 0 ? " of " : " among ") +
         std::to_string(r.free_parameters) + (r.local_dimension >= 0 ? ", " : " free parameters, ") +
         (r.full_turn ? std::string("full turn")
                      : "input range [" + g(r.range_lo_deg) + ", " + g(r.range_hi_deg) + "] deg") +
         (r.setup != "none" && !r.setup.empty() ? ", setup " + r.setup : "") + ".";
}

std::string chart_joints_sentence(const CandidateRow& r, const Representation& rep, const std::string& drawings) {
  const size_t driven = static_cast<size_t>(rep.input_joint);
  const std::string joint = std::to_string(rep.input_joint + 1), angle = input_name(rep);
  std::string out = drawings +
                    " are drawn from the canonical form (as stored; the representation that gives the canonical key), "
                    "driven by its joint " +
                    joint + " (" + angle + ")";
  if (!rep.on_motion) {
    out += " over a full turn from the assembly at 0 (no motion of the rigid loop was found)";
  } else if (rep.full_turn) {
    out += driven == 0 ? ", which turns fully on a circuit of the rigid loop"
                       : ", the first of its joints that turns fully on a circuit of the rigid loop (joint 1 does not)";
  } else {
    out += " over a window of its range on a circuit of the rigid loop (no joint turns fully" +
           std::string(driven == 0 ? ")" : ", and joint 1 does not move)");
  }
  const ConventionalJoints map = conventional_joints(r);
  if (map.joint.size() <= driven) return out + ".";
  bool numbered_alike = true, negated = false;
  std::string from, to;
  for (size_t i = 0; i < map.joint.size(); ++i) {
    numbered_alike = numbered_alike && map.joint[i] == static_cast<int>(i);
    negated = negated || map.negated[i];
    from += (i ? ", " : "") + std::to_string(i + 1);
    to += (i ? ", " : "") + std::to_string(map.joint[i] + 1);
  }
  // Numbered alike with no angle negated: the same representation.
  if (numbered_alike && !negated) return out + "; here the canonical form is the conventional form.";
  const std::string input = std::to_string(map.joint[driven] + 1);
  out += numbered_alike
             ? "; its joints are numbered as the conventional form's, and " + angle + " is the angle of joint " + joint
             : ": its joints " + from + " are joints " + to + " of the conventional form, and " + angle +
                   " is the angle of joint " + input;
  return out + (map.negated[driven] ? " there measured the other way (joint " + input +
                                          " of the conventional form is at -" + angle + ")."
                                    : " there.");
}

int write_atlas(const std::filesystem::path& gnuplot, const std::vector<CandidateRow>& rows,
                const std::map<std::int64_t, double>& zero_thresholds, const std::string& header,
                const std::filesystem::path& dir) {
  const std::vector<FamilyGroup> groups = group_by_family(rows);
  std::string md = "# Family atlas\n\n" + header + "\n";
  md +=
      "Per family: the candidates (distinct verified movable linkages) and the starts that found them (hits); "
      "the spread of their parameters in the conventional form (length scale L = 1, twists in degrees, positive "
      "where the loop allows, as the report's table shows them; the canonical form, which gives the de-duplication "
      "key, may have them negative); the local dimension found and the family's known dimension. Both count free real "
      "parameters **including the scale**: the known one in the full 3n-parameter space (docs/guide/families.md, "
      "docs/guide/classification.md), the found one (`candidates.local_dimension`) among the search's free "
      "parameters, so a sub-space search (ties, zero offsets, symmetry) can find less than the family has and a "
      "point on a larger family more. The representative is a full-turn candidate (its input turned fully on the "
      "motion the search verified) if there is one, with the smallest rigid-closure residual. Its cycle energy is "
      "recomputed from its stored canonical form along the motion of its rigid loop, every circuit of which is "
      "traced here: driven by the first of its joints that turns fully on a circuit, over a full turn, or, when no "
      "joint does, by joint 1 over a window of its range on a circuit (" +
      std::to_string(kAtlasCycleSamples) +
      " samples, log axis; energies below the zero threshold of the run that found it "
      "are round-off of a zero and are drawn on the threshold's dashed line); its motion is drawn at " +
      std::to_string(kFrames) +
      " input angles of that cycle (oblique view; dashed: joint axes, black: links, dots: joints). The joint "
      "driven is not always joint 1, and the canonical form may number the joints otherwise than the conventional "
      "one, reverse the loop or flip axes: each family says which joint its charts drive, in both forms. Unclassified "
      "candidates come first: a possible new family.\n\n";
  md +=
      "| family | joints | candidates | hits | local dimension found (candidates) | free parameters | known dimension "
      "|\n";
  md += "|---|---|---|---|---|---|---|\n";
  for (const FamilyGroup& group : groups) {
    const std::optional<int> known = known_family_dimension(group.family, group.joints);
    md += "| [" + group.family + "](#" + atlas_stem(group.family, group.joints) + ") | " +
          std::to_string(group.joints) + " | " + std::to_string(group.rows.size()) + " | " +
          std::to_string(group.hits) + " | " + dimension_counts(group) + " | " + free_parameter_counts(group) + " | " +
          (known ? std::to_string(*known) : "-") + " |\n";
  }
  if (groups.empty()) md += "\n(no candidates)\n";

  for (const FamilyGroup& group : groups) {
    const std::string stem = atlas_stem(group.family, group.joints);
    const std::optional<int> known = known_family_dimension(group.family, group.joints);
    md += "\n<a id=\"" + stem + "\"></a>\n## " + group.family + " (" + std::to_string(group.joints) +
          "R): " + count_of(static_cast<long long>(group.rows.size()), "candidate") + ", " +
          count_of(group.hits, "hit") + "\n\n";
    if (group.family == "unclassified")
      md +=
          "Fits no known family: a possible new family (or a known one whose conditions `classify` does not write, "
          "docs/guide/families.md).\n\n";

    // Local dimension.
    std::map<int, std::pair<int, int>> found;  // dimension -> (candidates, free parameters of the first)
    for (const CandidateRow* r : group.rows) {
      auto& entry = found[r->local_dimension];
      if (entry.first++ == 0) entry.second = r->free_parameters;
    }
    md += "Local dimension (scale included): known **" + (known ? std::to_string(*known) : std::string("-")) +
          "** in the full " + std::to_string(3 * group.joints) + "-parameter space.\n\n";
    md += "| found | candidates | free parameters | reading |\n|---|---|---|---|\n";
    for (const auto& [dimension, entry] : found) {
      md += "| " + dimension_text(dimension) + " | " + std::to_string(entry.first) + " | " +
            std::to_string(entry.second) + " | " + dimension_reading(dimension, known, entry.second, group.joints) +
            " |\n";
    }

    // Parameter spread, in the form people read (round-off of a zero as 0).
    std::vector<CandidateRow> shown_rows;
    for (const CandidateRow* r : group.rows) shown_rows.push_back(conventional(*r));
    md +=
        "\nParameters (conventional form, L = 1, twists in degrees):\n\n| parameter | min | median | max "
        "|\n|---|---|---|---|\n";
    for (int kind = 0; kind < 3; ++kind) {
      for (int i = 0; i < group.joints; ++i) {
        std::vector<double> values;
        for (const CandidateRow& r : shown_rows) {
          const std::vector<double>& v = kind == 0 ? r.a : kind == 1 ? r.alpha_deg : r.d;
          if (i < static_cast<int>(v.size())) values.push_back(v[static_cast<size_t>(i)]);
        }
        const Spread s = spread(values);
        const std::string name = (kind == 0   ? "a"
                                  : kind == 1 ? "alpha"
                                              : "d") +
                                 std::to_string(i + 1) + (kind == 1 ? " [deg]" : "");
        const double threshold = kind == 1 ? kAngleRoundOffDeg : kRoundOff;
        md += "| " + name + " | " + shown(s.min, threshold, 4) + " | " + shown(s.median, threshold, 4) + " | " +
              shown(s.max, threshold, 4) + " |\n";
      }
    }

    // The representative.
    const CandidateRow& r = representative(group);
    const Representation rep = compute_cycle(r);
    const std::filesystem::path png = dir / (stem + "_cycle.png");
    EnergyPlotStyle style;
    style.title = group.family + " (" + std::to_string(group.joints) + "R), candidate " + std::to_string(r.id) +
                  ": cycle energy of the canonical geometry driven by joint " + std::to_string(rep.input_joint + 1) +
                  (rep.full_turn ? "" : " over a window of its range");
    style.log_scale = true;
    style.theta0 = rep.theta0;
    style.theta0_deg = rep.theta0 * kDegreesPerRadian;
    style.input_joint = rep.input_joint;
    const auto threshold = zero_thresholds.find(r.first_run);
    if (threshold != zero_thresholds.end() && threshold->second > 0.0) {
      style.zero_threshold = threshold->second;
      style.threshold_source = "run " + std::to_string(r.first_run) + "'s";
    }
    // The stored E_mean (what the report's table prints) and this curve's
    // own, each named: the curve is recomputed from another pose.
    style.notes = {"E_mean " + g(r.E_mean, 3) + " as stored (the report's value)",
                   "this curve: E_mean " + g(rep.cycle.E_mean, 3) + ", E_max " + g(rep.cycle.E_max, 3) + " over " +
                       std::to_string(kAtlasCycleSamples) + " samples"};
    style.format = plot_format(png, "--atlas");
    plot_energy_curve(gnuplot, rep.cycle, style, png);
    std::vector<std::vector<double>> theta;
    std::vector<double> input_deg;
    pick_frames(rep, kFrames, theta, input_deg);
    const std::filesystem::path svg = dir / (stem + "_motion.svg");
    write_text(svg, motion_strip_svg(r, theta, input_deg, input_name(rep),
                                     group.family + " (" + std::to_string(group.joints) + "R), candidate " +
                                         std::to_string(r.id) + ": the loop at " + std::to_string(theta.size()) +
                                         " input angles"));
    md += "\n" + representative_sentence(r) + "\n";
    if (!r.detail.empty()) md += "Classification: " + r.detail + ".\n";
    md += "\nThe representative's parameters (conventional form, L = 1, twists in degrees):\n" +
          parameter_block(conventional(r)) + "\nIts canonical form (L = 1, twists in degrees):\n" + parameter_block(r) +
          "\n" + chart_joints_sentence(r, rep, "The cycle-energy chart and the motion drawing") + "\n\n";
    md += "Cycle energy recomputed here: E_mean " + g(rep.cycle.E_mean, 3) + ", E_max " + g(rep.cycle.E_max, 3) + ", " +
          std::to_string(rep.cycle.failed_samples) + " failed samples.\n\n";
    md += "![cycle energy of candidate " + std::to_string(r.id) + "](" + png.filename().string() + ")\n\n";
    md += "![motion of candidate " + std::to_string(r.id) + "](" + svg.filename().string() + ")\n";
    std::fprintf(stderr, "loopfarm report: wrote %s and %s\n", png.string().c_str(), svg.string().c_str());
  }
  const std::filesystem::path index = dir / "atlas.md";
  write_text(index, md);
  std::fprintf(stderr, "loopfarm report: wrote %s (%zu families, %zu candidates)\n", index.string().c_str(),
               groups.size(), rows.size());
  return static_cast<int>(groups.size());
}

}  // namespace loopfarm::cli
