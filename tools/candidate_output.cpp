#include "candidate_output.hpp"

#include <cmath>
#include <cstdio>
#include <vector>

#include "cli_support.hpp"
#include "geometry_input.hpp"
#include "loopfarm/search/canonical.hpp"
#include "motion_output.hpp"

namespace loopfarm::cli {
namespace {

constexpr double kDegreesPerRadian = 180.0 / 3.14159265358979323846;

std::string readable(double value) {
  char buffer[40];
  std::snprintf(buffer, sizeof buffer, "%.6g", value);
  return buffer;
}

nlohmann::ordered_json json_array(const JointVector& values, double factor) {
  nlohmann::ordered_json out = nlohmann::ordered_json::array();
  for (int i = 0; i < values.size(); ++i) out.push_back(values[i] * factor);
  return out;
}

// Values times `factor` for people: 6 significant digits, and round-off of a
// zero (|v| < 1e-9 at length scale 1, or in radians) as 0.
std::string rounded_text(const JointVector& values, double factor) {
  std::string out;
  for (int i = 0; i < values.size(); ++i) {
    const double v = std::abs(values[i]) < 1e-9 ? 0.0 : values[i] * factor;
    out += (i ? ", " : "") + readable(v);
  }
  return out;
}

}  // namespace

std::string lengths_text(const JointVector& values) {
  return format_list(std::vector<double>(values.data(), values.data() + values.size()));
}

std::string degrees_text(const JointVector& radians) {
  // Round-off of a zero angle (below 1e-9 rad) reads as 0.
  std::vector<double> degrees;
  for (int i = 0; i < radians.size(); ++i) {
    degrees.push_back(std::abs(radians[i]) < 1e-9 ? 0.0 : radians[i] * kDegreesPerRadian);
  }
  return format_list(degrees);
}

nlohmann::ordered_json geometry_json(const LoopGeometry& g) {
  nlohmann::ordered_json geometry;
  geometry["a"] = json_array(g.a, 1.0);
  geometry["alpha_deg"] = json_array(g.alpha, kDegreesPerRadian);
  geometry["d"] = json_array(g.d, 1.0);
  return geometry;
}

nlohmann::ordered_json polish_json(const GeometryPolishSummary& p, bool ran) {
  const auto when = [&](const nlohmann::ordered_json& value) { return ran ? value : nlohmann::ordered_json(); };
  nlohmann::ordered_json polish;
  polish["converged"] = when(p.converged);
  polish["iterations"] = when(p.iterations);
  polish["poses"] = when(p.poses_used);
  polish["initial_residual"] = when(p.initial_residual);
  polish["final_residual"] = when(p.final_residual);
  polish["displacement"] = when(p.displacement);
  polish["message"] = when(p.message);
  return polish;
}

nlohmann::ordered_json degrees_json(const JointVector& radians) { return json_array(radians, kDegreesPerRadian); }

void print_candidate(const CandidateAnalysis& c) {
  const VerificationSummary& v = c.verification;
  const MotionAnalysis& m = v.motion;
  std::printf("rigid verification (the rigid loop's circuits, independent of the elastic model)\n");
  std::printf("  verified              %s\n", v.verified ? "yes" : "no");
  if (m.given_pose.size() > 0 || !m.given_pose_closes) {
    std::printf("  given pose            %s\n", m.given_pose.size() == 0 ? "none"
                                                : !v.assembled           ? "does not close the rigid loop"
                                                : v.on_motion            ? "closes, on the reported circuit"
                                                                         : "closes, not on a moving circuit");
  }
  if (v.circuit >= 0) {
    std::printf("  reported circuit      %d: ", v.circuit + 1);
    if (v.full_turn) {
      std::printf("input full turn");
    } else {
      std::printf("input [%s, %s] deg", readable(v.range_lo * kDegreesPerRadian).c_str(),
                  readable(v.range_hi * kDegreesPerRadian).c_str());
    }
    std::printf(", worst residual %s over %d poses\n", readable(v.worst_residual).c_str(), v.poses);
  } else {
    std::printf("  least residual        %s\n", readable(v.worst_residual).c_str());
  }
  if (!v.limit.empty()) std::printf("  note                  %s\n", v.limit.c_str());
  if (v.joint_travel.size() > 0) std::printf("  joint travel_deg      %s\n", degrees_text(v.joint_travel).c_str());
  print_circuits(m, m.input_joint, v.circuit);
  const Classification& k = c.classification;
  std::printf("classification\n");
  if (v.verified || k.family == Family::unclassified) {
    std::printf("  family                %s", to_string(k.family));
    if (k.family == Family::bennett) std::printf(" (%s setup)", to_string(k.setup));
    std::printf("\n");
  } else {
    // A family's conditions are no claim without a motion.
    std::printf("  family                none: the %s conditions hold, but no motion was found\n", to_string(k.family));
  }
  if (!k.detail.empty()) std::printf("  detail                %s\n", k.detail.c_str());
  for (const FamilyCheck& check : k.checks) {
    std::printf("  %-21s residual %s\n", to_string(check.family), readable(check.residual).c_str());
  }
  // The key is for de-duplication (radians, the smallest representation);
  // people read the same loop in its conventional form, in degrees.
  if (c.canonical.geometry.joints() > 0) {
    const LoopGeometry shown = conventional_form(c.canonical.geometry).geometry;
    std::printf("canonical form          a = %s; alpha_deg = %s; d = %s (length scale 1)\n",
                rounded_text(shown.a, 1.0).c_str(), rounded_text(shown.alpha, kDegreesPerRadian).c_str(),
                rounded_text(shown.d, 1.0).c_str());
  }
  std::printf("canonical key           %s\n", c.canonical.key.c_str());
}

void print_local_dimension(const LocalDimension& d) {
  if (!d.known()) {
    std::printf(
        "local dimension         unknown (the deformation Jacobian has an entry that is not finite; %d free "
        "parameters)\n",
        d.parameters);
    return;
  }
  std::printf("local dimension         %d of %d free parameters (rank %d; singular values", d.dimension, d.parameters,
              d.rank);
  for (int i = 0; i < d.singular_values.size(); ++i) std::printf(" %s", readable(d.singular_values[i]).c_str());
  std::printf(")\n");
}

void add_candidate_json(nlohmann::ordered_json& out, const CandidateAnalysis& c, bool analysed) {
  const char* fields[] = {"family",    "family_conditions_hold", "setup",         "verified",        "assembled",
                          "on_motion", "rigid_residual",         "full_turn",     "input_range_deg", "circuit",
                          "circuits",  "family_residuals",       "canonical_key", "local_dimension", "singular_values"};
  for (const char* field : fields) out[field] = nullptr;
  out["verified"] = false;
  if (!analysed) return;
  const VerificationSummary& v = c.verification;
  const Family family = c.classification.family;
  // A family is claimed only for a verified loop; otherwise its conditions
  // holding is said in a field of its own.
  const bool claimed = v.verified || family == Family::unclassified;
  if (claimed) {
    out["family"] = to_string(family);
  } else {
    out["family_conditions_hold"] = to_string(family);
  }
  out["setup"] = to_string(c.classification.setup);
  out["verified"] = v.verified;
  if (v.motion.given_pose.size() != 0) {
    out["assembled"] = v.assembled;
    out["on_motion"] = v.on_motion;
  }
  out["rigid_residual"] = v.worst_residual;
  if (v.circuit >= 0) {
    out["full_turn"] = v.full_turn;
    out["input_range_deg"] = {v.range_lo * kDegreesPerRadian, v.range_hi * kDegreesPerRadian};
    out["circuit"] = v.circuit + 1;
  }
  out["circuits"] = circuits_json(v.motion, v.motion.input_joint);
  nlohmann::ordered_json residuals = nlohmann::ordered_json::object();
  for (const FamilyCheck& check : c.classification.checks) residuals[to_string(check.family)] = check.residual;
  out["family_residuals"] = residuals;
  out["canonical_key"] = c.canonical.key;
  if (v.verified && c.local_dimension.parameters > 0 && c.local_dimension.known()) {
    out["local_dimension"] = c.local_dimension.dimension;
    const Eigen::VectorXd& values = c.local_dimension.singular_values;
    out["singular_values"] = std::vector<double>(values.data(), values.data() + values.size());
  }
}

}  // namespace loopfarm::cli
