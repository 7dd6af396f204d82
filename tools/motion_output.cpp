#include "motion_output.hpp"

#include <cmath>
#include <string>
#include <vector>

#include "cli_support.hpp"

namespace loopfarm::cli {
namespace {

constexpr double kDegreesPerRadian = 180.0 / 3.14159265358979323846;

std::string readable(double value) {
  char buffer[40];
  std::snprintf(buffer, sizeof buffer, "%.9g", value);
  return buffer;
}

std::string degrees_list(const JointVector& radians) {
  std::string out;
  for (int i = 0; i < radians.size(); ++i) {
    if (i) out += ", ";
    out += readable(radians[i] * kDegreesPerRadian);
  }
  return out;
}

std::string degrees_array(const JointVector& radians) {
  std::string out = "[";
  for (int i = 0; i < radians.size(); ++i) {
    if (i) out += ',';
    out += json_number(radians[i] * kDegreesPerRadian);
  }
  return out + "]";
}

std::string range_text(const JointRange& r) {
  if (r.crank()) return "crank (" + std::to_string(std::abs(r.turns)) + (std::abs(r.turns) == 1 ? " turn)" : " turns)");
  return "rocker [" + readable(r.lo * kDegreesPerRadian) + ", " + readable(r.hi * kDegreesPerRadian) + "]";
}

}  // namespace

void print_circuits(const MotionAnalysis& m, int input, int reported) {
  std::printf("circuits                %d found", static_cast<int>(m.circuits.size()));
  if (!m.isolated_poses.empty())
    std::printf(", and %d isolated closed poses", static_cast<int>(m.isolated_poses.size()));
  std::printf("\n");
  for (size_t i = 0; i < m.circuits.size(); ++i) {
    const Circuit& c = m.circuits[i];
    std::printf("  circuit %zu%s%s\n", i + 1, static_cast<int>(i) == reported ? " (reported)" : "",
                static_cast<int>(i) == m.given_circuit ? " (through the given pose)" : "");
    std::printf("    end                 %s, %d points, arclength %s rad, worst residual %s\n", to_string(c.end),
                static_cast<int>(c.points.size()), readable(c.length).c_str(), readable(c.worst_residual).c_str());
    std::printf("    freedoms            %d", c.freedoms);
    if (!c.held_joints.empty()) {
      std::printf(" (traced with joint");
      for (int j : c.held_joints) std::printf(" %d", j + 1);
      std::printf(" held)");
    }
    std::printf("\n");
    const JointRange& r = c.input_range(input);
    std::printf(
        "    input (joint %d)     %s\n", input + 1,
        r.crank()
            ? "full turn"
            : ("[" + readable(r.lo * kDegreesPerRadian) + ", " + readable(r.hi * kDegreesPerRadian) + "] deg").c_str());
    for (size_t j = 0; j < c.ranges.size(); ++j) {
      std::printf("    joint %-2zu            %s\n", j + 1, range_text(c.ranges[j]).c_str());
    }
    for (const JointExtreme& e : c.extremes) {
      if (e.joint != input) continue;
      std::printf("    dead point          input %s at %s deg: theta_deg %s\n", e.maximum ? "max" : "min",
                  readable(e.theta[input] * kDegreesPerRadian).c_str(), degrees_list(e.theta).c_str());
    }
    for (const Bifurcation& b : c.bifurcations) {
      std::printf(
          "    singular pose       the closure Jacobian loses rank; %d branch directions leave it; theta_deg %s\n",
          b.branches, degrees_list(b.theta).c_str());
    }
  }
}

std::string circuits_json(const MotionAnalysis& m, int input) {
  std::string json = "[";
  for (size_t i = 0; i < m.circuits.size(); ++i) {
    const Circuit& c = m.circuits[i];
    if (i) json += ',';
    const JointRange& r = c.input_range(input);
    json += "{\"end\":" + json_string(to_string(c.end));
    json += ",\"closed\":" + std::string(c.closed() ? "true" : "false");
    json += ",\"through_given_pose\":" + std::string(static_cast<int>(i) == m.given_circuit ? "true" : "false");
    json += ",\"freedoms\":" + std::to_string(c.freedoms);
    json += ",\"held_joints\":[";
    for (size_t k = 0; k < c.held_joints.size(); ++k) json += (k ? "," : "") + std::to_string(c.held_joints[k] + 1);
    json += "],\"points\":" + std::to_string(c.points.size());
    json += ",\"arclength_rad\":" + json_number(c.length);
    json += ",\"worst_residual\":" + json_number(c.worst_residual);
    json += ",\"least_singular_ratio\":" + json_number(c.least_singular_ratio);
    json += ",\"full_turn\":" + std::string(r.crank() ? "true" : "false");
    json += ",\"input_range_deg\":[" + json_number(r.lo * kDegreesPerRadian) + "," +
            json_number(r.hi * kDegreesPerRadian) + "]";
    json += ",\"joints\":[";
    for (size_t j = 0; j < c.ranges.size(); ++j) {
      const JointRange& k = c.ranges[j];
      if (j) json += ',';
      json += "{\"range_deg\":[" + json_number(k.lo * kDegreesPerRadian) + "," + json_number(k.hi * kDegreesPerRadian) +
              "],\"crank\":" + (k.crank() ? "true" : "false") + ",\"turns\":" + std::to_string(k.turns) + "}";
    }
    json += "],\"dead_points\":[";
    bool first = true;
    for (const JointExtreme& e : c.extremes) {
      if (e.joint != input) continue;
      json += std::string(first ? "" : ",") + "{\"input_deg\":" + json_number(e.theta[input] * kDegreesPerRadian) +
              ",\"maximum\":" + (e.maximum ? "true" : "false") + ",\"theta_deg\":" + degrees_array(e.theta) + "}";
      first = false;
    }
    json += "],\"bifurcations\":[";
    for (size_t b = 0; b < c.bifurcations.size(); ++b) {
      json += std::string(b ? "," : "") + "{\"branches\":" + std::to_string(c.bifurcations[b].branches) +
              ",\"theta_deg\":" + degrees_array(c.bifurcations[b].theta) + "}";
    }
    json += "]}";
  }
  return json + "]";
}

void write_circuits_csv(const MotionAnalysis& m, std::FILE* out) {
  const int n = m.circuits.empty() || m.circuits.front().points.empty()
                    ? 0
                    : static_cast<int>(m.circuits.front().points.front().size());
  std::fprintf(out, "circuit,point,arclength_rad");
  for (int j = 0; j < n; ++j) std::fprintf(out, ",theta%d_deg", j + 1);
  std::fprintf(out, "\n");
  for (size_t i = 0; i < m.circuits.size(); ++i) {
    const Circuit& c = m.circuits[i];
    for (size_t p = 0; p < c.points.size(); ++p) {
      std::fprintf(out, "%zu,%zu,%.17g", i + 1, p, c.arclength[p]);
      for (int j = 0; j < c.points[p].size(); ++j) std::fprintf(out, ",%.17g", c.points[p][j] * kDegreesPerRadian);
      std::fprintf(out, "\n");
    }
  }
}

}  // namespace loopfarm::cli
