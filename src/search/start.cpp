#include "loopfarm/search/start.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "loopfarm/search/sampler.hpp"

namespace loopfarm {
namespace {

// A start whose searched cycle is within this factor of the zero threshold
// is evaluated again without steering before it is judged: the re-solved
// energy of a cycle may differ from the searched one by the solves'
// tolerance, which matters only next to the threshold.
constexpr double kZeroRecheckFactor = 1e6;

std::string scientific(double v) {
  char buffer[40];
  std::snprintf(buffer, sizeof buffer, "%.3g", v);
  return buffer;
}

Family family_from_name(const std::string& name) {
  // Every family family_distance measures (the job parser has checked the
  // name and the joint count; family_distance checks the count again).
  const std::optional<Family> family = family_from_string(name);
  if (!family || !has_family_distance(*family)) {
    throw std::invalid_argument("unknown family \"" + name + "\" to deflate");
  }
  return *family;
}

}  // namespace

ObjectiveOptions objective_options(const Job& job) {
  ObjectiveOptions s = ObjectiveOptions::from_loop(job.loop);
  for (const std::string& name : job.steering.deflate) {
    const Family family = family_from_name(name);
    s.deflation.push_back({name, [family](const LoopGeometry& g, GeometryVector* gradient) {
                             return family_distance(family, g, gradient);
                           }});
  }
  s.deflation_power = job.steering.deflation_power;
  s.deflation_shift = job.steering.deflation_shift;
  s.nontrivial = job.steering.nontrivial;
  s.min_travel = job.steering.min_travel;
  s.reuse_nearby_cycle = job.optimizer.reuse_nearby_cycle;
  return s;
}

CandidateAnalysis analyse_candidate(const LoopGeometry& geometry, const JointVector& pose,
                                    const Eigen::MatrixXd& jacobian, const StartOptions& options) {
  return analyse_candidate(geometry, pose, verify_motion(geometry, pose, options.verification), jacobian, options);
}

CandidateAnalysis analyse_candidate(const LoopGeometry& geometry, const JointVector& pose,
                                    VerificationSummary verification, const Eigen::MatrixXd& jacobian,
                                    const StartOptions& options) {
  CandidateAnalysis out;
  out.geometry = geometry;
  out.verification = std::move(verification);
  // The family is read on the verified motion: from the given pose when it
  // lies on it, else from a pose of the circuit that moves.
  const JointVector classified_pose =
      out.verification.verified && !out.verification.on_motion ? out.verification.pose() : pose;
  const JointVector& travel = out.verification.joint_travel;
  // The joint travel is over the verified motion; a loop that could not be
  // followed has none (every joint would look frozen and the loop trivial).
  const std::span<const double> travel_span =
      out.verification.verified ? std::span<const double>(travel.data(), static_cast<size_t>(travel.size()))
                                : std::span<const double>();
  out.classification = classify(geometry, classified_pose, travel_span, options.classification);
  // Near the meeting of two families (a Bennett loop with tiny twists, a
  // parallelogram) a loop a distance eps off both closes to about eps^2, the
  // product of the two distances: a local search stops on such loops, and
  // they verify. When no family fits at the strict tolerance, a verified loop
  // is therefore classified again with the conditions met to about the square
  // root of its rigid residual. Strict first, so that an exact Bennett loop
  // with twists 1e-7 from planar stays a Bennett loop.
  if (out.classification.family == Family::unclassified && out.verification.verified) {
    ClassifyOptions loose = options.classification;
    loose.tolerance = std::max(loose.tolerance, 10.0 * std::sqrt(out.verification.worst_residual));
    out.classification = classify(geometry, classified_pose, travel_span, loose);
  }
  out.canonical = canonical_form(geometry);
  out.local_dimension = local_dimension(jacobian, options.rank_tolerance);
  return out;
}

namespace {

// A zero's pose is usually on its motion (the cycle went through it with no
// energy): only the circuit through it is traced, then, if that one does not
// move, the circuits through the cycle's other samples (a cycle may close at
// a few isolated poses and follow a motion at its other samples), with every
// joint's extremes solved for (its ranges exact whatever the step), first in
// steps that grow with the curve's straightness up to
// analysis_steps_per_turn. The coarse walk gives up where it nears a
// singular pose: the circuit is traced finely there anyway.
VerificationSummary trace_through_pose(const LoopGeometry& geometry, const JointVector& pose,
                                       std::span<const JointVector> cycle_poses, const StartOptions& options) {
  VerificationOptions through_pose = options.verification;
  through_pose.all_circuits = false;
  through_pose.all_extremes = true;
  through_pose.steps_per_turn = options.analysis_steps_per_turn;
  through_pose.stop_below_singular_ratio = options.regular_circuit_ratio;
  VerificationSummary verification = verify_motion(geometry, pose, cycle_poses, through_pose);
  const std::vector<Circuit>& circuits = verification.motion.circuits;
  const bool regular = std::all_of(circuits.begin(), circuits.end(), [&](const Circuit& c) {
    return c.least_singular_ratio >= options.regular_circuit_ratio;
  });
  if (verification.verified && regular) return verification;
  // Near a singular pose (branches crossing, a loop folding flat) a coarse
  // step can cross to another branch, or over a point where the circuit
  // ends: the circuit is traced again in steps of 1 deg, the other joints'
  // ranges read off its points (extremes solved for near a singular pose
  // cost many corrector calls each).
  through_pose.steps_per_turn = std::max(360, options.analysis_steps_per_turn);
  through_pose.all_extremes = false;
  through_pose.stop_below_singular_ratio = 0.0;
  return verify_motion(geometry, pose, cycle_poses, through_pose);
}

// `loopfarm verify`'s analysis of every circuit, the one covering theta0
// preferred, with the farm's scan of assemblies (StartOptions::
// whole_motion_scan_inputs).
VerificationSummary trace_whole_motion(const LoopGeometry& geometry, const JointVector& pose, double theta0,
                                       const StartOptions& options) {
  VerificationOptions whole = options.verification;
  whole.theta0 = theta0;
  whole.scan_inputs = options.whole_motion_scan_inputs;
  return verify_motion(geometry, pose, whole);
}

// The geometry polished onto the motion it approximates (geometry_polish.hpp),
// at poses spread along `circuit`'s points: as many as give 8 closure
// equations per free parameter (a pose gives 6 - (n - f)), between 32 and
// polish_poses (32 for a 4R's 12 parameters, 128 for a 6R's 18).
GeometryPolishSummary polish_along(const LoopGeometry& geometry, const Circuit& circuit, const PolishDirections& along,
                                   const StartOptions& options) {
  GeometryPolishSummary polish;
  const int n = geometry.joints();
  const size_t count = circuit.points.size();
  if (circuit.worst_residual <= options.polish.target_residual) {
    // Every traced point closes to round-off already (the tracer measured
    // it, as the polish would): nothing to polish.
    polish.converged = true;
    polish.geometry = geometry;
    polish.poses_used = static_cast<int>(count);
    polish.initial_residual = polish.final_residual = circuit.worst_residual;
    return polish;
  }
  if (circuit.freedoms < 1 || circuit.freedoms >= n) {
    polish.geometry = geometry;
    polish.message = "a circuit with " + std::to_string(circuit.freedoms) + " freedoms";
    return polish;
  }
  const int per_pose = std::max(1, 6 - (n - circuit.freedoms));
  const int enough = static_cast<int>((8 * along.directions.cols() + per_pose - 1) / per_pose);
  const size_t wanted = std::min(count, static_cast<size_t>(std::clamp(enough, std::min(32, options.polish_poses),
                                                                       std::max(1, options.polish_poses))));
  std::vector<JointVector> poses;
  for (size_t i = 0; i < wanted; ++i) poses.push_back(circuit.points[(2 * i + 1) * count / (2 * wanted)]);
  return polish_geometry(geometry, poses, circuit.freedoms, along, options.polish);
}

struct PolishedMotion {
  VerificationSummary verification;
  JointVector pose;  // the pose its trace went through
};

// The motion of a polished geometry, traced through the given pose (and the
// cycle's), which Newton's method brings onto it from about the polish's
// displacement away. Near a singular pose it may not: then from the polished
// pose nearest the given one, which lies on the circuit polished along, so
// that its trace needs no search of the whole motion but where it cannot be
// followed.
PolishedMotion trace_polished(const GeometryPolishSummary& polish, const JointVector& pose,
                              std::span<const JointVector> cycle_poses, double theta0, const StartOptions& options) {
  PolishedMotion out{trace_through_pose(polish.geometry, pose, cycle_poses, options), pose};
  if (out.verification.verified || polish.poses.empty()) return out;
  // Differences from the given pose, each angle's nearest 2 pi image (the
  // circuit's angles are unwrapped from where its trace starts).
  const auto from_pose = [&](const JointVector& p) -> JointVector {
    return (p - pose).unaryExpr([](double x) { return wrap_angle(x); });
  };
  const auto distance = [&](const JointVector& p) { return from_pose(p).cwiseAbs().maxCoeff(); };
  const JointVector& nearest =
      *std::min_element(polish.poses.begin(), polish.poses.end(),
                        [&](const JointVector& a, const JointVector& b) { return distance(a) < distance(b); });
  out.pose = pose + from_pose(nearest);
  out.verification = trace_through_pose(polish.geometry, out.pose, {}, options);
  if (!out.verification.verified) out.verification = trace_whole_motion(polish.geometry, out.pose, theta0, options);
  return out;
}

}  // namespace

CandidateAnalysis analyse_zero(const LoopGeometry& geometry, const JointVector& pose, const Eigen::MatrixXd& jacobian,
                               double theta0, const StartOptions& options, const PolishDirections* directions,
                               std::span<const JointVector> cycle_poses) {
  const PolishDirections every = directions ? PolishDirections{} : PolishDirections::every_parameter(geometry);
  const PolishDirections& along = directions ? *directions : every;
  VerificationSummary verification = trace_through_pose(geometry, pose, cycle_poses, options);
  if (!verification.verified) {
    // The circuits through the search's poses cannot always be followed
    // from them: a window's samples may step over a gap in the input's range
    // that holds theta0 (the pose at theta0 is then elastic, not closed), the
    // tracer may stall near a singular pose, or a loop with two freedoms may
    // be traced with a joint held whose curve ends. A zero that is not
    // verified so is analysed as `loopfarm verify` does it: every circuit,
    // the one covering theta0 preferred.
    verification = trace_whole_motion(geometry, pose, theta0, options);
  }
  if (!verification.verified) return analyse_candidate(geometry, pose, std::move(verification), jacobian, options);

  const Circuit& circuit = verification.motion.circuits[static_cast<size_t>(verification.circuit)];
  const GeometryPolishSummary polish = polish_along(geometry, circuit, along, options);
  JointVector polished_pose = pose;
  if (!polish.converged) {
    verification.verified = false;
    verification.limit = "not polished onto a motion: " + polish.message;
  } else if (polish.iterations > 0) {
    PolishedMotion polished = trace_polished(polish, pose, cycle_poses, theta0, options);
    verification = std::move(polished.verification);
    polished_pose = polished.pose;
    if (!verification.verified) verification.limit = "the polished geometry: " + verification.limit;
  }
  CandidateAnalysis out = analyse_candidate(polish.geometry, polished_pose, std::move(verification), jacobian, options);
  out.polish = polish;
  return out;
}

RoundOffCheck check_round_off(const LoopGeometry& geometry, VerificationSummary& verification,
                              const StartOptions& options) {
  RoundOffCheck out;
  if (!verification.verified || verification.circuit < 0 || verification.worst_residual <= options.round_off_residual) {
    return out;
  }
  out.polished = true;
  const Circuit& circuit = verification.motion.circuits[static_cast<size_t>(verification.circuit)];
  const GeometryPolishSummary polish =
      polish_along(geometry, circuit, PolishDirections::every_parameter(geometry), options);
  std::string limit = "the circuit closes to " + scientific(verification.worst_residual) + ", not to round-off (" +
                      scientific(options.round_off_residual) + "): ";
  if (!polish.converged) {
    out.candidate.geometry = geometry;
    out.candidate.polish = polish;
    verification.verified = false;
    verification.on_motion = false;
    verification.limit = limit + "a near miss, not polished onto a motion (" + polish.message + ")";
    return out;
  }
  // The polished geometry's motion, through the polished poses (closed on
  // it), else from every circuit as the given geometry's was found.
  VerificationOptions through = options.verification;
  through.all_circuits = false;
  const JointVector& start = polish.poses.front();
  const std::span<const JointVector> more(polish.poses.data() + 1, polish.poses.size() - 1);
  VerificationSummary polished = verify_motion(polish.geometry, start, more, through);
  if (!polished.verified) polished = verify_motion(polish.geometry, start, options.verification);
  out.candidate = analyse_candidate(polish.geometry, start, std::move(polished), Eigen::MatrixXd(), options);
  out.candidate.polish = polish;
  const bool moves = out.candidate.verification.verified;
  if (moves && polish.displacement <= options.round_off_displacement) {
    // A movable loop within round-off of the geometry (poses near a
    // singular one close less well than the rest).
    verification.limit += std::string(verification.limit.empty() ? "" : "; ") + limit +
                          "the polish onto its motion moves the geometry by " + scientific(polish.displacement) +
                          " only (round-off)";
    return out;
  }
  verification.verified = false;
  verification.on_motion = false;
  verification.limit = limit + "the geometry as given does not move; " +
                       (moves ? "polished onto the motion it approximates (moved by " +
                                    scientific(polish.displacement) + ", lengths / L and angles in radians) it does"
                              : "polished (moved by " + scientific(polish.displacement) +
                                    ") it does not move either: " + out.candidate.verification.limit);
  return out;
}

StartSummary run_start(const Job& job, std::uint64_t index, const StartOptions& options) {
  StartSummary out;
  out.index = index;
  out.algorithm = job.optimizer.algorithm;
  const StartPoint start = draw_start(job.space, job.search.seed, index);
  out.initial_geometry = job.space.geometry(start.x);
  out.initial_angles = start.theta;

  // The unsteered energy at the start, for the record (and for comparing
  // steered with unsteered runs on the same footing).
  ObjectiveOptions plain = ObjectiveOptions::from_loop(job.loop);
  // The analysis of a zero (its local dimension from the Jacobian of every
  // sample's deformations) needs the whole cycle, whatever the search minimised.
  plain.measure = CycleMeasure::mean;
  plain.reuse_nearby_cycle = job.optimizer.reuse_nearby_cycle;
  CycleObjective unsteered(job.space, plain, start.theta);
  const ObjectiveValue initial = unsteered.evaluate(start.x, nullptr);
  out.initial_E_mean = initial.ok ? initial.E_mean : std::numeric_limits<double>::quiet_NaN();

  CycleObjective objective(job.space, objective_options(job), start.theta);
  // The search's first evaluation is at the start itself, whose cycle the
  // record above has just walked (steering does not change the cycle).
  objective.continue_from(unsteered);
  LocalSearchOptions search;
  search.optimizer = job.optimizer;
  // NLopt's stochastic algorithms: a seed of their own per start.
  search.random_seed = job.search.seed * 0x9E3779B97F4A7C15ull + index;
  search.trace = options.trace;
  const LocalSearchSummary result = local_minimize(objective, start.x, search);
  out.status = result.status;
  out.message = result.message;
  out.evaluations = result.evaluations;
  out.seconds = result.seconds;
  out.objective = result.value;
  out.final_geometry = job.space.geometry(result.x);
  if (result.status == SearchStatus::evaluation_failed) {
    out.E_mean = std::numeric_limits<double>::quiet_NaN();
    out.E_max = out.E_mean;
    return out;
  }

  // The final point without steering: its true energy and pose, on the
  // branch the search followed to it (which an assembly from the start's
  // angles at the final geometry may miss). Steering scales the energy but
  // does not change the cycle, so where the search's last evaluation is at
  // its result (both local searches leave it there) that cycle is the
  // answer. A start that may be a zero is evaluated again without steering,
  // as its analysis needs that objective's Jacobian and cycle: the re-solved
  // energy decides, so a verdict never rests on which cycle was solved last.
  const ObjectiveValue searched = objective.last_x() == result.x ? objective.last_cycle_value() : ObjectiveValue{};
  // A cycle with a failed sample is solved again too: from the searched
  // cycle the failed solve may succeed.
  const bool maybe_zero =
      !searched.ok || searched.failed_samples > 0 || searched.E_mean <= kZeroRecheckFactor * job.search.zero_threshold;
  const CycleObjective& final_cycle = maybe_zero ? unsteered : objective;
  ObjectiveValue final_value = searched;
  if (maybe_zero) {
    unsteered.continue_from(objective);
    final_value = unsteered.evaluate(result.x, nullptr);
  }
  if (!final_value.ok) {
    out.E_mean = std::numeric_limits<double>::quiet_NaN();
    out.E_max = out.E_mean;
    return out;
  }
  out.E_mean = final_value.E_mean;
  out.E_max = final_value.E_max;
  out.failed_samples = final_value.failed_samples;
  out.branch_jumps = final_value.branch_jumps;
  out.final_angles = final_cycle.start_state().theta;
  // A failed sample's energy is that of wherever its solve stopped, often
  // near zero (docs/quality/stability.md, S4): a cycle with one is never a zero.
  out.zero = maybe_zero && out.E_mean <= job.search.zero_threshold && out.failed_samples == 0;
  if (!out.zero) return out;

  // The analysis: the local dimension from the cycle's Jacobian, then the
  // rigid verification, the family and the canonical form.
  const auto analysis_begin = std::chrono::steady_clock::now();
  Eigen::MatrixXd jacobian;
  unsteered.residual_jacobian(jacobian);
  std::vector<bool> is_length;
  for (int index : job.space.free_indices()) {
    const int kind = index / job.space.joints;
    is_length.push_back(kind == static_cast<int>(ParameterKind::a) || kind == static_cast<int>(ParameterKind::d));
  }
  const Eigen::MatrixXd columns = dimensionless_columns(jacobian, is_length, length_scale(out.final_geometry));
  // The polish moves the job's free parameters (ties with them), within
  // their ranges.
  PolishDirections directions;
  directions.directions = job.space.geometry_jacobian();
  directions.lower = job.space.lower_bounds() - result.x;
  directions.upper = job.space.upper_bounds() - result.x;
  // Every sample of the cycle closes (its energy is zero): where the motion
  // does not pass the start pose, it may pass the others.
  std::vector<JointVector> cycle_poses;
  for (const CycleSample& sample : unsteered.cycle().samples) cycle_poses.push_back(sample.state.theta);
  out.candidate = analyse_zero(out.final_geometry, out.final_angles, columns, out.initial_angles[0], options,
                               &directions, cycle_poses);
  out.analysis_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - analysis_begin).count();
  return out;
}

}  // namespace loopfarm
