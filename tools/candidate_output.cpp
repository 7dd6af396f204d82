#include "candidate_output.hpp"

#include <cstdio>
#include <vector>

#include "cli_support.hpp"
#include "geometry_input.hpp"
#include "motion_output.hpp"

namespace loopfarm::cli {
namespace {

constexpr double kDegreesPerRadian = 180.0 / 3.14159265358979323846;

std::string readable(double value) {
  char buffer[40];
  std::snprintf(buffer, sizeof buffer, "%.6g", value);
  return buffer;
}

std::string json_array(const JointVector& values, double factor) {
  std::string out = "[";
  for (int i = 0; i < values.size(); ++i) {
    if (i) out += ',';
    out += json_number(values[i] * factor);
  }
  return out + "]";
}

}  // namespace

std::string lengths_text(const JointVector& values) {
  return format_list(std::vector<double>(values.data(), values.data() + values.size()));
}

std::string degrees_text(const JointVector& radians) {
  std::vector<double> degrees;
  for (int i = 0; i < radians.size(); ++i) degrees.push_back(radians[i] * kDegreesPerRadian);
  return format_list(degrees);
}

std::string geometry_json(const LoopGeometry& g) {
  return "{\"a\":" + json_array(g.a, 1.0) + ",\"alpha_deg\":" + json_array(g.alpha, kDegreesPerRadian) +
         ",\"d\":" + json_array(g.d, 1.0) + "}";
}

std::string degrees_json(const JointVector& radians) { return json_array(radians, kDegreesPerRadian); }

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
  std::printf("canonical key           %s\n", c.canonical.key.c_str());
}

void print_local_dimension(const LocalDimension& d) {
  std::printf("local dimension         %d of %d free parameters (rank %d; singular values", d.dimension, d.parameters,
              d.rank);
  for (int i = 0; i < d.singular_values.size(); ++i) std::printf(" %s", readable(d.singular_values[i]).c_str());
  std::printf(")\n");
}

std::string candidate_json_fields(const CandidateAnalysis& c, bool analysed) {
  std::string json;
  if (!analysed) {
    return ",\"family\":null,\"family_conditions_hold\":null,\"setup\":null,\"verified\":false,"
           "\"assembled\":null,\"on_motion\":null,\"rigid_residual\":null,\"full_turn\":null,"
           "\"input_range_deg\":null,\"circuit\":null,\"circuits\":null,\"family_residuals\":null,"
           "\"canonical_key\":null,\"local_dimension\":null,\"singular_values\":null";
  }
  const VerificationSummary& v = c.verification;
  const Family family = c.classification.family;
  // A family is claimed only for a verified loop; otherwise its conditions
  // holding is said in a field of its own.
  const bool claimed = v.verified || family == Family::unclassified;
  json += ",\"family\":" + (claimed ? json_string(to_string(family)) : std::string("null"));
  json += ",\"family_conditions_hold\":" + (claimed ? std::string("null") : json_string(to_string(family)));
  json += ",\"setup\":" + json_string(to_string(c.classification.setup));
  json += ",\"verified\":" + std::string(v.verified ? "true" : "false");
  json += ",\"assembled\":" + std::string(v.motion.given_pose.size() == 0 ? "null" : v.assembled ? "true" : "false");
  json += ",\"on_motion\":" + std::string(v.motion.given_pose.size() == 0 ? "null" : v.on_motion ? "true" : "false");
  json += ",\"rigid_residual\":" + json_number(v.worst_residual);
  if (v.circuit >= 0) {
    json += ",\"full_turn\":" + std::string(v.full_turn ? "true" : "false");
    json += ",\"input_range_deg\":[" + json_number(v.range_lo * kDegreesPerRadian) + "," +
            json_number(v.range_hi * kDegreesPerRadian) + "]";
    json += ",\"circuit\":" + std::to_string(v.circuit + 1);
  } else {
    json += ",\"full_turn\":null,\"input_range_deg\":null,\"circuit\":null";
  }
  json += ",\"circuits\":" + circuits_json(v.motion, v.motion.input_joint);
  json += ",\"family_residuals\":{";
  bool first = true;
  for (const FamilyCheck& check : c.classification.checks) {
    if (!first) json += ',';
    json += json_string(to_string(check.family)) + ":" + json_number(check.residual);
    first = false;
  }
  json += "}";
  json += ",\"canonical_key\":" + json_string(c.canonical.key);
  if (v.verified && c.local_dimension.parameters > 0) {
    json += ",\"local_dimension\":" + std::to_string(c.local_dimension.dimension);
    json += ",\"singular_values\":[";
    for (int i = 0; i < c.local_dimension.singular_values.size(); ++i) {
      if (i) json += ',';
      json += json_number(c.local_dimension.singular_values[i]);
    }
    json += "]";
  } else {
    json += ",\"local_dimension\":null,\"singular_values\":null";
  }
  return json;
}

}  // namespace loopfarm::cli
