// One random start of a search, end to end: draw the geometry and initial
// angles of start `index` from the job's (seed, index) stream, minimise the
// (steered) cycle energy locally, and, if it reaches zero, verify the motion
// with the rigid closure, classify it, put it in canonical form and measure
// the local dimension of the zero set there.
#pragma once

#include <cstdint>
#include <functional>
#include <span>
#include <string>

#include "loopfarm/core/geometry_polish.hpp"
#include "loopfarm/search/canonical.hpp"
#include "loopfarm/search/classify.hpp"
#include "loopfarm/search/job.hpp"
#include "loopfarm/search/local_dimension.hpp"
#include "loopfarm/search/local_search.hpp"
#include "loopfarm/search/verify.hpp"

namespace loopfarm {

struct StartOptions {
  // `loopfarm verify`'s options; also a zero's analysis from every circuit
  // when the circuit through its pose cannot be followed (analyse_zero).
  VerificationOptions verification;
  // That analysis of every circuit seeks assemblies at this many input
  // angles over the turn (VerificationOptions::scan_inputs), `loopfarm
  // verify` at verification.scan_inputs. The zeros that reach it are mostly
  // near misses, on which the scan at fixed inputs costs two thirds of their
  // analysis; on the six jobs in jobs/ the guesses with every joint free
  // verified every zero the scan did (docs/guide/motion.md).
  int whole_motion_scan_inputs = 0;
  ClassifyOptions classification;
  double rank_tolerance = 1e-6;  // local_dimension's relative singular-value threshold
  // A zero's analysis (analyse_zero) traces the circuit through its pose in
  // steps of at most 360 / analysis_steps_per_turn degrees of arclength
  // (>= 64), every joint's extremes solved for on the curve, and keeps that
  // trace where every traced circuit is regular: its least singular ratio
  // (Circuit::least_singular_ratio) at least regular_circuit_ratio (the
  // coarse walk stops where it comes nearer). A circuit passing nearer a
  // singular pose is traced again in steps of 1 deg, the other joints'
  // ranges read off its points (docs/guide/motion.md).
  int analysis_steps_per_turn = 64;
  double regular_circuit_ratio = 1e-2;
  // A verified zero's geometry is polished onto its motion (polish_geometry)
  // at poses spread along the verified circuit, as many as give 8 closure
  // equations per free parameter but at least 32 and at most polish_poses
  // (a 6R's 18 parameters take 128, a 4R's 12 take 32), and its motion is
  // traced again on the polished geometry; a zero the polish cannot bring to
  // round-off is a near miss, not verified.
  int polish_poses = 128;
  GeometryPolishOptions polish;
  // A geometry judged as given (check_round_off: `loopfarm verify`,
  // `loopfarm motion`) moves when its reported circuit closes to this
  // residual (dimensionless) at every traced pose, round-off as for an open
  // circuit (Circuit::moves), or when the polish onto its motion moves it by
  // at most round_off_displacement (of L, or radians).
  double round_off_residual = 1e-12;
  double round_off_displacement = 1e-12;
  std::function<void(const SearchTraceRow&)> trace;
};

// What is known of a zero: its rigid verification, family, canonical form
// and the local dimension of the zero set.
struct CandidateAnalysis {
  // The geometry all of it is of: a zero's geometry polished onto its motion
  // (analyse_zero), else the geometry given.
  LoopGeometry geometry;
  GeometryPolishSummary polish;  // analyse_zero's polish (iterations 0: none was run or needed)
  VerificationSummary verification;
  Classification classification;
  CanonicalForm canonical;
  LocalDimension local_dimension;
};

// `pose`: joint angles of an assembled pose of `geometry` (the verification
// starts there: StartOptions::verification says whether every circuit is
// sought or only the one through the pose); `jacobian`: dr/dx of the cycle
// residuals with respect to the free parameters at the geometry, in
// dimensionless units (dimensionless_columns).
CandidateAnalysis analyse_candidate(const LoopGeometry& geometry, const JointVector& pose,
                                    const Eigen::MatrixXd& jacobian, const StartOptions& options);
// The same with the verification already done (`loopfarm verify` chooses
// the pose of its cycle energy from it); `pose` is that pose.
CandidateAnalysis analyse_candidate(const LoopGeometry& geometry, const JointVector& pose,
                                    VerificationSummary verification, const Eigen::MatrixXd& jacobian,
                                    const StartOptions& options);

struct StartSummary {
  std::uint64_t index = 0;
  std::string algorithm;
  LoopGeometry initial_geometry;
  JointVector initial_angles;   // drawn (fixed and tied filled in)
  double initial_E_mean = 0.0;  // unsteered, at the initial geometry (NaN if it cannot be assembled)
  LoopGeometry final_geometry;
  JointVector final_angles;  // assembled pose at theta0 of the final geometry
  double E_mean = 0.0;       // unsteered, at the final geometry
  double E_max = 0.0;
  double objective = 0.0;  // what the optimiser minimised (steered E_mean)
  int evaluations = 0;
  double seconds = 0.0;           // of the local minimisation
  double analysis_seconds = 0.0;  // of the zero's analysis (0 when not a zero)
  SearchStatus status = SearchStatus::failure;
  std::string message;
  int failed_samples = 0;  // of the final cycle
  int branch_jumps = 0;
  bool zero = false;  // E_mean <= the job's zero threshold

  // For zeros only (`zero`); otherwise default. Its geometry is
  // final_geometry polished onto the motion, along the job's free parameters.
  CandidateAnalysis candidate;
};

// A zero's analysis as run_start does it: the circuit through `pose`, and
// when that one does not move, the circuits through `cycle_poses` (the
// other closed poses of its cycle), traced in coarse steps, again in steps
// of 1 deg when they are not regular or cannot be followed
// (StartOptions::analysis_steps_per_turn), and when neither verifies, every
// circuit as `loopfarm verify` finds them, the one covering `theta0` (the
// start's drawn input angle) preferred. A verified geometry is
// then polished onto its motion along `directions` (by default every
// parameter, lengths kept >= 0) and, when the polish moved it, verified
// again as it was the first time; the classification, canonical form and
// CandidateAnalysis::geometry are of the polished geometry. A zero whose
// polish does not converge is not verified (VerificationSummary::limit says
// why).
CandidateAnalysis analyse_zero(const LoopGeometry& geometry, const JointVector& pose, const Eigen::MatrixXd& jacobian,
                               double theta0, const StartOptions& options, const PolishDirections* directions = nullptr,
                               std::span<const JointVector> cycle_poses = {});

// A geometry judged as given, at round-off (`loopfarm verify`, `loopfarm
// motion`). A circuit moves (Circuit::moves) when it closes on itself within
// the tracer's tolerance (1e-9), and so does the circuit of a near miss about
// 1e-9 of L from a movable loop: the geometry as given moves only if its
// reported circuit closes to round-off (StartOptions::round_off_residual) at
// every traced pose. When it moves by the tolerance only, it is polished
// onto the motion it approximates as a zero of the farm is (analyse_zero:
// every parameter free, lengths kept >= 0, at poses spread along the
// circuit), and the polished geometry is traced again and classified. The
// given geometry stays verified when that polish converges moving it by at
// most round_off_displacement; otherwise `verification` is marked not
// verified (its limit says how far the polish moved the geometry, or why no
// movable loop is near).
struct RoundOffCheck {
  bool polished = false;  // the reported circuit does not close to round-off: a polish was run
  // When polished: the polished geometry, the polish, and the polished
  // geometry's verification, family and canonical form (its geometry is the
  // given one and its verification empty when the polish did not converge).
  CandidateAnalysis candidate;
};
RoundOffCheck check_round_off(const LoopGeometry& geometry, VerificationSummary& verification,
                              const StartOptions& options);

// The steering of a job as objective options (deflation terms from the
// families' distance functions).
ObjectiveOptions objective_options(const Job& job);

StartSummary run_start(const Job& job, std::uint64_t index, const StartOptions& options = {});

}  // namespace loopfarm
