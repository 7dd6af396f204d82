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

nlohmann::ordered_json circuits_json(const MotionAnalysis& m, int input) {
  using nlohmann::ordered_json;
  auto degrees = [](const JointVector& theta) {
    ordered_json out = ordered_json::array();
    for (int i = 0; i < theta.size(); ++i) out.push_back(theta[i] * kDegreesPerRadian);
    return out;
  };
  ordered_json circuits = ordered_json::array();
  for (size_t i = 0; i < m.circuits.size(); ++i) {
    const Circuit& c = m.circuits[i];
    const JointRange& r = c.input_range(input);
    ordered_json circuit;
    circuit["end"] = to_string(c.end);
    circuit["closed"] = c.closed();
    circuit["through_given_pose"] = static_cast<int>(i) == m.given_circuit;
    circuit["freedoms"] = c.freedoms;
    ordered_json held = ordered_json::array();
    for (const int joint : c.held_joints) held.push_back(joint + 1);
    circuit["held_joints"] = held;
    circuit["points"] = c.points.size();
    circuit["arclength_rad"] = c.length;
    circuit["worst_residual"] = c.worst_residual;
    circuit["least_singular_ratio"] = c.least_singular_ratio;
    circuit["full_turn"] = r.crank();
    circuit["input_range_deg"] = {r.lo * kDegreesPerRadian, r.hi * kDegreesPerRadian};
    ordered_json joints = ordered_json::array();
    for (const JointRange& k : c.ranges) {
      ordered_json joint;
      joint["range_deg"] = {k.lo * kDegreesPerRadian, k.hi * kDegreesPerRadian};
      joint["crank"] = k.crank();
      joint["turns"] = k.turns;
      joints.push_back(joint);
    }
    circuit["joints"] = joints;
    ordered_json dead_points = ordered_json::array();
    for (const JointExtreme& e : c.extremes) {
      if (e.joint != input) continue;
      ordered_json point;
      point["input_deg"] = e.theta[input] * kDegreesPerRadian;
      point["maximum"] = e.maximum;
      point["theta_deg"] = degrees(e.theta);
      dead_points.push_back(point);
    }
    circuit["dead_points"] = dead_points;
    ordered_json bifurcations = ordered_json::array();
    for (const Bifurcation& b : c.bifurcations) {
      ordered_json point;
      point["branches"] = b.branches;
      point["theta_deg"] = degrees(b.theta);
      bifurcations.push_back(point);
    }
    circuit["bifurcations"] = bifurcations;
    circuits.push_back(circuit);
  }
  return circuits;
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
