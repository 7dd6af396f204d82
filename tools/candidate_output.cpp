#include "candidate_output.hpp"

#include <cstdio>
#include <vector>

#include "cli_support.hpp"
#include "geometry_input.hpp"

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

void print_candidate(const CandidateAnalysis& c) {
  const VerificationSummary& v = c.verification;
  std::printf("rigid verification (closure solved along the motion, independent of the elastic model)\n");
  std::printf("  verified              %s\n", v.verified ? "yes" : "no");
  std::printf("  assembled             %s\n", v.assembled ? "yes" : "no");
  std::printf("  worst residual        %s over %d poses\n", readable(v.worst_residual).c_str(), v.poses);
  if (v.full_turn) {
    std::printf("  input range           full turn\n");
  } else {
    std::printf("  input range           [%s, %s] deg%s%s\n", readable(v.range_lo * kDegreesPerRadian).c_str(),
                readable(v.range_hi * kDegreesPerRadian).c_str(), v.limit.empty() ? "" : ": ", v.limit.c_str());
  }
  if (v.joint_travel.size() > 0) std::printf("  joint travel_deg      %s\n", degrees_text(v.joint_travel).c_str());
  const Classification& k = c.classification;
  std::printf("classification\n");
  std::printf("  family                %s", to_string(k.family));
  if (k.family == Family::bennett) std::printf(" (%s setup)", to_string(k.setup));
  std::printf("\n");
  if (!k.detail.empty()) std::printf("  detail                %s\n", k.detail.c_str());
  for (const FamilyCheck& check : k.checks) {
    std::printf("  %-21s residual %s\n", to_string(check.family), readable(check.residual).c_str());
  }
  std::printf("canonical key           %s\n", c.canonical.key.c_str());
  const LocalDimension& d = c.local_dimension;
  std::printf("local dimension         %d of %d free parameters (rank %d; singular values", d.dimension, d.parameters,
              d.rank);
  for (int i = 0; i < d.singular_values.size(); ++i) std::printf(" %s", readable(d.singular_values[i]).c_str());
  std::printf(")\n");
}

std::string candidate_json_fields(const CandidateAnalysis& c, bool analysed) {
  std::string json;
  if (!analysed) {
    return ",\"family\":null,\"setup\":null,\"verified\":false,\"rigid_residual\":null,\"full_turn\":null,"
           "\"input_range_deg\":null,\"family_residuals\":null,\"canonical_key\":null,\"local_dimension\":null,"
           "\"singular_values\":null";
  }
  const VerificationSummary& v = c.verification;
  json += ",\"family\":" + json_string(to_string(c.classification.family));
  json += ",\"setup\":" + json_string(to_string(c.classification.setup));
  json += ",\"verified\":" + std::string(v.verified ? "true" : "false");
  json += ",\"rigid_residual\":" + json_number(v.worst_residual);
  json += ",\"full_turn\":" + std::string(v.full_turn ? "true" : "false");
  json += ",\"input_range_deg\":[" + json_number(v.range_lo * kDegreesPerRadian) + "," +
          json_number(v.range_hi * kDegreesPerRadian) + "]";
  json += ",\"family_residuals\":{";
  bool first = true;
  for (const FamilyCheck& check : c.classification.checks) {
    if (!first) json += ',';
    json += json_string(to_string(check.family)) + ":" + json_number(check.residual);
    first = false;
  }
  json += "}";
  json += ",\"canonical_key\":" + json_string(c.canonical.key);
  json += ",\"local_dimension\":" + std::to_string(c.local_dimension.dimension);
  json += ",\"singular_values\":[";
  for (int i = 0; i < c.local_dimension.singular_values.size(); ++i) {
    if (i) json += ',';
    json += json_number(c.local_dimension.singular_values[i]);
  }
  json += "]";
  return json;
}

}  // namespace loopfarm::cli
