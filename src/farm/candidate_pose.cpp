// A closed pose of a stored linkage and its joint axes there (candidate_pose.hpp).
#include "loopfarm/farm/candidate_pose.hpp"

#include <algorithm>
#include <cmath>
#include <span>

#include "loopfarm/search/verify.hpp"

namespace loopfarm {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDegreesPerRadian = 180.0 / kPi;

}  // namespace

LoopGeometry candidate_geometry(const CandidateRow& row) {
  return LoopGeometry::from_degrees(std::span<const double>(row.a), std::span<const double>(row.alpha_deg),
                                    std::span<const double>(row.d));
}

std::optional<CandidatePose> candidate_pose(const LoopGeometry& geometry, double input_deg) {
  validate_geometry(geometry);
  VerificationOptions options;
  options.theta0 = input_deg / kDegreesPerRadian;
  const VerificationSummary verification = verify_motion(geometry, nullptr, options);
  const std::optional<MotionWindow> window = motion_window(geometry, verification, options.theta0, options);
  if (!window) return std::nullopt;
  CandidatePose pose;
  pose.theta = window->pose;
  pose.input_deg = window->theta0 * kDegreesPerRadian;
  pose.closure_residual = closure_residual(geometry, pose.theta).cwiseAbs().maxCoeff();
  pose.full_turn = verification.full_turn;
  pose.range_lo_deg = verification.range_lo * kDegreesPerRadian;
  pose.range_hi_deg = verification.range_hi * kDegreesPerRadian;
  pose.axes = joint_axes(geometry, pose.theta);
  return pose;
}

}  // namespace loopfarm
