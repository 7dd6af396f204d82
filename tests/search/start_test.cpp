// analyse_candidate: verification, then classification, strict first and
// loosened to the rigid residual only when no family fits strictly.
#include <algorithm>
#include <cmath>
#include <span>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "loopfarm/core/assembly.hpp"
#include "loopfarm/core/constructions.hpp"
#include "loopfarm/core/cycle.hpp"
#include "loopfarm/core/equilibrium.hpp"
#include "loopfarm/core/motion.hpp"
#include "loopfarm/core/sample_loops.hpp"
#include "loopfarm/search/classify.hpp"
#include "loopfarm/search/job.hpp"
#include "loopfarm/search/objective.hpp"
#include "loopfarm/search/start.hpp"
#include "loopfarm/search/verify.hpp"
#include "test_support.hpp"

namespace loopfarm {
namespace {

using testing::rad;

constexpr double kPi = 3.14159265358979323846;

// Some joint angles that close the loop, from the rigid verification's own
// assembly (started from a rough guess).
JointVector assembled(const LoopGeometry& g, const JointVector& guess) {
  const VerificationSummary v = verify_motion(g, guess);
  EXPECT_TRUE(v.assembled);
  return v.joint_angles.empty() ? guess : v.joint_angles.front();
}

TEST(AnalyseCandidate, ExactBennettLoopNearlyPlanarStaysBennett) {
  // Twists 1e-7 rad short of 180 deg: a Bennett loop to round-off, and within
  // 1e-6 of planar. The strict pass must call it what it exactly is.
  const double eps = 1e-7;
  const LoopGeometry g = bennett_loop(2.0, M_PI - eps, M_PI - 2.0 * eps);
  const JointVector pose = bennett_angles(g, rad(120));
  const CandidateAnalysis c = analyse_candidate(g, pose, Eigen::MatrixXd::Zero(1, 1), StartOptions{});
  ASSERT_TRUE(c.verification.verified);
  EXPECT_EQ(c.classification.family, Family::bennett) << c.classification.detail;
  EXPECT_GT(c.classification.checks[1].residual, ClassifyOptions{}.tolerance);  // planar: not strictly
}

TEST(AnalyseCandidate, NearPlanarZeroIsPlanarOnTheLoosenedTolerance) {
  // A Bennett loop with twists of 1e-6 and 2e-6 rad (nearly planar) and a1
  // lengthened by 1e-6: off both families by about 1e-6, but where they meet
  // the closure error is a product of the two small distances, and the loop
  // closes along its motion to about 1e-10, below the verification's 1e-9:
  // the kind of zero a local search lands on. Strictly (1e-8) it fits no
  // family; loosened to the square root of its rigid residual it is planar.
  LoopGeometry g = bennett_loop(2.0, 1e-6, std::asin(2.0 * std::sin(1e-6)));
  g.a[0] = 2.000001;
  JointVector guess(4);
  guess << rad(120), rad(120), rad(-120), rad(-120);
  const JointVector pose = assembled(g, guess);
  const CandidateAnalysis c = analyse_candidate(g, pose, Eigen::MatrixXd::Zero(1, 1), StartOptions{});
  ASSERT_TRUE(c.verification.verified) << c.verification.worst_residual;
  EXPECT_GT(c.verification.worst_residual, 1e-13);
  const Classification strict = classify(g, pose, {}, ClassifyOptions{});
  EXPECT_EQ(strict.family, Family::unclassified) << strict.detail;
  EXPECT_EQ(c.classification.family, Family::planar) << c.classification.detail;
}

TEST(AnalyseCandidate, RigidLoopIsNotVerifiedAndNotLoosened) {
  const LoopGeometry g = random_loop(4, 7);
  const JointVector pose = random_angles(4, 7);
  const CandidateAnalysis c = analyse_candidate(g, pose, Eigen::MatrixXd::Zero(1, 1), StartOptions{});
  EXPECT_FALSE(c.verification.verified);
  // Not trivial either: without a verified motion no joint counts as frozen.
  EXPECT_EQ(c.classification.family, Family::unclassified) << c.classification.detail;
}

// A start drawn within 1e-9 of the paper's Bennett loop, in boxes that hold
// it: the search reaches the family at once. Whatever the search minimised, the analysis of the
// zero (its local dimension from every sample's deformations) is the same:
// the Bennett family has dimension 3 in (a1..a4, alpha1..alpha4).
TEST(RunStart, AZeroIsAnalysedOverTheWholeCycleWhateverTheObjective) {
  const std::string space = R"(
[space]
a1 = [2, 2.000000001]
a2 = [4, 4.000000001]
a3 = [2, 2.000000001]
a4 = [4, 4.000000001]
alpha1_deg = [30, 30.00000001]
alpha2_deg = [90, 90.00000001]
alpha3_deg = [30, 30.00000001]
alpha4_deg = [90, 90.00000001]
d = 0
theta1_deg = 120
theta2_deg = 90
theta3_deg = -120
theta4_deg = -90
[search]
zero_threshold = 1e-20
)";
  for (const char* objective : {"mean", "max"}) {
    const Job job =
        parse_job(std::string("[loop]\nsamples = 8\nobjective = \"") + objective + "\"\n" + space, "bennett.toml");
    const StartSummary s = run_start(job, 0);
    ASSERT_TRUE(s.zero) << objective << ": E_mean " << s.E_mean;
    EXPECT_TRUE(s.candidate.verification.verified) << objective;
    EXPECT_EQ(s.candidate.classification.family, Family::bennett) << objective;
    EXPECT_EQ(s.candidate.local_dimension.parameters, 8) << objective;
    EXPECT_EQ(s.candidate.local_dimension.dimension, 3) << objective;
  }
}

// The shipped rocker job (jobs/trihedral-rocker-6r.toml) finds, from random
// starts, trihedral Bricard loops whose input rocks: verified by the rigid
// tracer, classified, on the trihedral condition (checked here in closed
// form, a1^2 + a3^2 + a5^2 = a2^2 + a4^2 + a6^2), and with every sample of
// the cycle's window inside the traced input range (the elastic cycle and
// the rigid motion agree on where the loop moves; a gap in the range
// narrower than the samples' spacing may lie between two samples).
TEST(RunStart, TheRockerJobFindsTrihedralLoopsWhoseInputRocks) {
  const Job job = read_job_file(std::string(LOOPFARM_SOURCE_DIR) + "/jobs/trihedral-rocker-6r.toml");
  ASSERT_LT(job.loop.range, 2.0 * kPi);
  int rockers = 0;
  for (std::uint64_t index = 0; index < 30; ++index) {
    const StartSummary s = run_start(job, index);
    if (!s.zero || !s.candidate.verification.verified) continue;
    const VerificationSummary& v = s.candidate.verification;
    EXPECT_EQ(s.candidate.classification.family, Family::bricard_trihedral) << index;
    const JointVector& a = s.final_geometry.a;
    const double condition = a[0] * a[0] + a[2] * a[2] + a[4] * a[4] - a[1] * a[1] - a[3] * a[3] - a[5] * a[5];
    EXPECT_LT(std::abs(condition), 1e-8 * a.squaredNorm()) << index;
    if (v.full_turn) continue;
    ++rockers;
    EXPECT_LT(v.range_hi - v.range_lo, 2.0 * kPi) << index;
    // The samples theta0 - R/2 + j R / (N - 1), each at its image nearest
    // the middle of the range.
    const double middle = 0.5 * (v.range_lo + v.range_hi);
    for (int j = 0; j < job.loop.samples; ++j) {
      const double sample = s.initial_angles[0] - 0.5 * job.loop.range + j * job.loop.range / (job.loop.samples - 1);
      const double image = middle + std::remainder(sample - middle, 2.0 * kPi);
      EXPECT_GE(image, v.range_lo - 1e-9) << index << " sample " << j;
      EXPECT_LE(image, v.range_hi + 1e-9) << index << " sample " << j;
    }
  }
  EXPECT_GE(rockers, 3);
}

// A zero's analysis keeps a regular circuit traced in coarse steps (up to
// about 5.6 deg): on the first zeros of the default job it is what a trace
// in steps of 0.5 deg gives (verified, every joint's range and turns, the
// family), from a fraction of the points.
TEST(AnalyseZero, ARegularCircuitTracedInCoarseStepsIsTheFineTrace) {
  const Job job = read_job_file(std::string(LOOPFARM_SOURCE_DIR) + "/jobs/default.toml");
  VerificationOptions fine;
  fine.all_circuits = false;
  fine.steps_per_turn = 720;
  int zeros = 0;
  for (std::uint64_t index = 0; zeros < 12 && index < 100; ++index) {
    const StartSummary s = run_start(job, index);
    if (!s.zero) continue;
    ++zeros;
    const VerificationSummary& coarse = s.candidate.verification;
    const VerificationSummary reference = verify_motion(s.final_geometry, s.final_angles, fine);
    ASSERT_TRUE(reference.verified) << index;
    ASSERT_TRUE(coarse.verified) << index;
    EXPECT_LT(3 * coarse.poses, reference.poses) << index;  // the coarse trace was kept
    const Circuit& a = coarse.motion.circuits.at(static_cast<size_t>(coarse.circuit));
    const Circuit& b = reference.motion.circuits.at(static_cast<size_t>(reference.circuit));
    EXPECT_GE(a.least_singular_ratio, StartOptions{}.regular_circuit_ratio) << index;
    EXPECT_EQ(a.end, b.end) << index;
    ASSERT_EQ(a.ranges.size(), b.ranges.size());
    for (size_t j = 0; j < a.ranges.size(); ++j) {
      EXPECT_NEAR(a.ranges[j].lo, b.ranges[j].lo, 1e-9) << index << " joint " << j;
      EXPECT_NEAR(a.ranges[j].hi, b.ranges[j].hi, 1e-9) << index << " joint " << j;
      EXPECT_EQ(a.ranges[j].turns, b.ranges[j].turns) << index << " joint " << j;
    }
    const CandidateAnalysis by_reference =
        analyse_candidate(s.final_geometry, s.final_angles, reference, Eigen::MatrixXd::Zero(1, 1), StartOptions{});
    EXPECT_EQ(s.candidate.classification.family, by_reference.classification.family) << index;
  }
  EXPECT_EQ(zeros, 12);
}

// Near a singular pose a coarse step can cross to another branch: the
// parallelogram's circuit passes its change points (least singular ratio
// below the threshold), so its analysis is the trace in steps of 1 deg.
TEST(AnalyseZero, ACircuitNearASingularPoseIsTracedAgainInStepsOfOneDegree) {
  const LoopGeometry g = planar_four_bar(1.0, 2.0, 1.0, 2.0);
  const std::vector<JointVector> poses = find_assemblies(g, rad(60));
  ASSERT_FALSE(poses.empty());
  const StartOptions options;
  VerificationOptions through_pose;
  through_pose.all_circuits = false;
  through_pose.steps_per_turn = options.analysis_steps_per_turn;
  for (const JointVector& pose : poses) {
    const VerificationSummary coarse = verify_motion(g, pose, through_pose);
    ASSERT_FALSE(coarse.motion.circuits.empty());
    EXPECT_LT(coarse.motion.circuits.front().least_singular_ratio, options.regular_circuit_ratio);
    VerificationOptions fine = through_pose;
    fine.steps_per_turn = 360;
    fine.all_extremes = false;
    const VerificationSummary expected = verify_motion(g, pose, fine);
    ASSERT_TRUE(expected.verified);
    const CandidateAnalysis a = analyse_zero(g, pose, Eigen::MatrixXd::Zero(1, 1), 0.0, options);
    ASSERT_TRUE(a.verification.verified);
    EXPECT_EQ(a.verification.poses, expected.poses);
    EXPECT_EQ(a.verification.range_lo, expected.range_lo);
    EXPECT_EQ(a.verification.range_hi, expected.range_hi);
    EXPECT_EQ(a.classification.family, Family::planar);
  }
}

// A movable loop whose given pose does not close (off its circuit, as an
// elastic pose at theta0 in a gap of the input's range is) is analysed from
// every circuit and verified: a Bennett loop from a pose 0.3 rad off its
// motion in every joint.
TEST(AnalyseZero, AMovableLoopWhosePoseIsOffItsCircuitIsVerifiedFromEveryCircuit) {
  const LoopGeometry bennett = bennett_loop(1.0, rad(40), rad(70));
  const struct {
    LoopGeometry geometry;
    JointVector on_motion;
    Family family;
  } loops[] = {{bennett, bennett_angles(bennett, rad(50)), Family::bennett}};
  for (const auto& loop : loops) {
    const JointVector off = loop.on_motion + JointVector::Constant(loop.on_motion.size(), 0.3);
    VerificationOptions through_pose;
    through_pose.all_circuits = false;
    ASSERT_FALSE(verify_motion(loop.geometry, off, through_pose).assembled);
    const CandidateAnalysis a = analyse_zero(loop.geometry, off, Eigen::MatrixXd::Zero(1, 1), 0.0, StartOptions{});
    EXPECT_TRUE(a.verification.verified) << to_string(loop.family);
    EXPECT_EQ(a.classification.family, loop.family);
  }
}

// A near miss of the generic 6R job with 32 cycle samples (start 143: its
// cycle energy 1e-27, the rigid loop closing to about the tolerance along a
// curve, not to round-off) is not verified. Its walk creeps over a stretch of the curve: it ends
// `stalled` after a few thousand points, where without the stall rule the
// walk spends max_points there and ends too long, having covered less.
// The scan's seeds beyond its ends lie on the first trace that repeats it,
// and are not traced again: one circuit is kept. Independently, the circuit
// traced from an assembly at each of four inputs over the turn does not move.
TEST(AnalyseZero, ANearMissIsNotVerifiedAndItsCurveIsNotTracedAgainFromEverySeed) {
  Job job = read_job_file(std::string(LOOPFARM_SOURCE_DIR) + "/jobs/generic-6r.toml");
  job.loop.samples = 32;
  const StartSummary s = run_start(job, 143);
  ASSERT_TRUE(s.zero);
  const VerificationSummary& v = s.candidate.verification;
  EXPECT_FALSE(v.verified);
  ASSERT_EQ(v.motion.circuits.size(), 1u);
  const Circuit& stalled = v.motion.circuits.front();
  EXPECT_EQ(stalled.end, CircuitEnd::stalled);
  const MotionOptions defaults;
  EXPECT_LT(stalled.points.size(), static_cast<size_t>(defaults.max_points / 5));
  EXPECT_GT(stalled.worst_residual, 1e-3 * defaults.residual_tolerance);  // not round-off: a near miss
  const VerificationOptions creeping = StartOptions{}.verification;
  MotionOptions never_stalls = creeping.motion();
  never_stalls.stall_points = 0;
  const MotionAnalysis without_rule = analyse_motion(s.final_geometry, &s.final_angles, never_stalls);
  ASSERT_EQ(without_rule.circuits.size(), 1u);
  const Circuit& crept = without_rule.circuits.front();
  EXPECT_EQ(crept.end, CircuitEnd::too_long);
  // The creeping walk spent every point on one stretch; the stalled one gave
  // up there and walked the other way, covering more of the curve.
  EXPECT_GT(stalled.length, crept.length);
  EXPECT_FALSE(crept.moves(0, creeping.min_input_travel, creeping.residual_tolerance));
  const VerificationOptions options;
  const MotionOptions motion = options.motion();
  int traced = 0;
  for (double input : {0.0, 90.0, 180.0, 270.0}) {
    for (const JointVector& pose : find_assemblies(s.final_geometry, rad(input), motion)) {
      const Circuit c = trace_circuit(s.final_geometry, pose, motion);
      EXPECT_FALSE(c.moves(options.input_joint, options.min_input_travel, options.residual_tolerance)) << input;
      ++traced;
    }
  }
  EXPECT_GT(traced, 0);
}

// Zeros of the generic 6R job the search finds only to about 1e-7 of L: the
// rigid loop closes to 1e-11 along the circuit through the search's pose,
// which the tracer follows, but `loopfarm verify` (every circuit, over the
// whole turn) loses the thin tube of near-closed poses elsewhere. The
// analysis polishes the geometry onto its motion, within the job's ranges;
// the polished geometry is what `loopfarm verify` verifies. Start 1569 runs
// away from its geometry when polished: refused, as `loopfarm verify`
// refuses it.
// Bennett's conditions, independent of the tracer and the polish: opposite
// links equal, no offsets, sin(alpha1) / a1 = sin(alpha2) / a2 (twists in
// (0, pi)). The largest violation, lengths / L.
double bennett_violation(const LoopGeometry& g) {
  const double L = length_scale(g);
  double worst = std::abs(g.a[0] * std::sin(g.alpha[1]) - g.a[1] * std::sin(g.alpha[0])) / L;
  worst = std::max({worst, std::abs(g.a[0] - g.a[2]) / L, std::abs(g.a[1] - g.a[3]) / L,
                    std::abs(g.alpha[0] - g.alpha[2]), std::abs(g.alpha[1] - g.alpha[3])});
  for (int k = 0; k < 4; ++k) worst = std::max(worst, std::abs(g.d[k]) / L);
  return worst;
}

// `loopfarm verify` judges the geometry as given at round-off. A Bennett loop
// moved off its family by 1e-9 to 3e-9 of a length, or by 1e-9 rad of a twist, is rigid, but
// its circuit closes within the tracer's tolerance of 1e-9 all the way round
// (a circuit that moves by the tolerance): it is not verified as given, and
// polished onto its motion it is a Bennett loop again by the closed-form
// conditions, moved by about the perturbation. One 1e-6 off does not close
// within the tolerance and is refused with no polish.
TEST(CheckRoundOff, ABennettNearMissWithinTheToleranceIsNotVerifiedAsGiven) {
  const LoopGeometry exact = paper_bennett_loop();
  ASSERT_LT(bennett_violation(exact), 1e-15);
  const double L = length_scale(exact);
  struct Case {
    const char* what;
    LoopGeometry g;
    double offset;  // from the exact loop: lengths / L, twists [rad]
  };
  std::vector<Case> cases;
  for (const double eps : {1e-9, 3e-9}) {
    LoopGeometry g = exact;
    g.a[0] += eps;
    cases.push_back({"a1", g, eps / L});
  }
  LoopGeometry twisted = exact;
  twisted.alpha[0] += 1e-9;
  cases.push_back({"alpha1", twisted, 1e-9});
  for (const Case& c : cases) {
    SCOPED_TRACE(::testing::Message() << c.what << " off by " << bennett_violation(c.g));
    // Rigid by the closed-form conditions, yet closing within the tolerance.
    EXPECT_GT(bennett_violation(c.g), 1e-10);
    VerificationSummary v = verify_motion(c.g, nullptr);
    ASSERT_TRUE(v.verified) << v.limit;
    EXPECT_GT(v.worst_residual, 1e-10);
    const RoundOffCheck r = check_round_off(c.g, v, StartOptions{});
    EXPECT_TRUE(r.polished);
    EXPECT_FALSE(v.verified);
    EXPECT_NE(v.limit.find("the geometry as given does not move"), std::string::npos) << v.limit;
    // The polished geometry moves, a Bennett loop to round-off, about as far
    // from the given one as the given one is from Bennett's conditions.
    const GeometryPolishSummary& p = r.candidate.polish;
    ASSERT_TRUE(p.converged) << p.message;
    EXPECT_TRUE(r.candidate.verification.verified) << r.candidate.verification.limit;
    EXPECT_LT(r.candidate.verification.worst_residual, 1e-13);
    EXPECT_EQ(r.candidate.classification.family, Family::bennett);
    EXPECT_LT(bennett_violation(r.candidate.geometry), 1e-14);
    EXPECT_GT(p.displacement, 0.1 * bennett_violation(c.g));
    // The least change (minimum norm) is no larger than the way back to
    // the exact loop.
    EXPECT_LT(p.displacement, c.offset * (1.0 + 1e-3));
  }
  LoopGeometry far = exact;
  far.a[0] += 1e-6;
  VerificationSummary v = verify_motion(far, nullptr);
  EXPECT_FALSE(check_round_off(far, v, StartOptions{}).polished);
  EXPECT_FALSE(v.verified);
}

// Movable loops close to round-off along their circuits and stay verified
// as given, with no polish: Bennett, Goldberg's 5R and a trihedral Bricard
// 6R (alternating twists), each exactly as constructed.
TEST(CheckRoundOff, ExactLoopsOfTheFamiliesAreVerifiedAsGiven) {
  const Goldberg5R goldberg{{2.0, kPi / 2, kPi / 6, kPi / 3}, kPi};
  TrihedralBricard bricard;
  bricard.a = {2.636, 1.143, 0.558, 1.408, 2.969};
  bricard.sign_pattern = 0b101010;
  LoopGeometry trihedral{JointVector::Zero(6), JointVector::Zero(6), JointVector::Zero(6)};
  for (int k = 0; k < 5; ++k) trihedral.a[k] = bricard.a[static_cast<size_t>(k)];
  trihedral.a[5] = trihedral_bricard_a6(bricard);
  for (int k = 0; k < 6; ++k) trihedral.alpha[k] = (bricard.sign_pattern >> k & 1u) ? -kPi / 2 : kPi / 2;
  const struct {
    const char* what;
    LoopGeometry g;
    Family family;
  } cases[] = {{"bennett", paper_bennett_loop(), Family::bennett},
               {"goldberg", goldberg_5r(goldberg, 1.0).geometry, Family::goldberg},
               {"bricard", trihedral, Family::bricard_trihedral}};
  for (const auto& c : cases) {
    SCOPED_TRACE(c.what);
    VerificationSummary v = verify_motion(c.g, nullptr);
    ASSERT_TRUE(v.verified) << v.limit;
    const RoundOffCheck r = check_round_off(c.g, v, StartOptions{});
    EXPECT_TRUE(v.verified) << v.limit;
    EXPECT_FALSE(r.polished) << v.worst_residual;
    EXPECT_LT(v.worst_residual, 1e-14);
    const CandidateAnalysis a = analyse_candidate(c.g, v.pose(), std::move(v), Eigen::MatrixXd(), StartOptions{});
    EXPECT_EQ(a.classification.family, c.family);
  }
}

// A movable loop whose circuit, as traced, closes less well than round-off
// (the planar parallelogram 0.001, 1, 0.001, 1, to about 1e-11) is polished
// onto its motion; the polish moves it by no more than round-off, so it
// stays verified as given, its limit says so, and the polished geometry is
// classified.
TEST(CheckRoundOff, AMovableLoopTracedAboveRoundOffIsPolishedAndStaysVerified) {
  LoopGeometry g{JointVector::Zero(4), JointVector::Zero(4), JointVector::Zero(4)};
  g.a << 0.001, 1.0, 0.001, 1.0;
  VerificationSummary v = verify_motion(g, nullptr);
  ASSERT_TRUE(v.verified) << v.limit;
  const StartOptions options;
  ASSERT_GT(v.worst_residual, options.round_off_residual);
  const RoundOffCheck r = check_round_off(g, v, options);
  EXPECT_TRUE(r.polished);
  EXPECT_TRUE(v.verified) << v.limit;
  EXPECT_TRUE(r.candidate.polish.converged) << r.candidate.polish.message;
  EXPECT_LE(r.candidate.polish.displacement, options.round_off_displacement);
  EXPECT_NE(v.limit.find("only (round-off)"), std::string::npos) << v.limit;
  EXPECT_TRUE(r.candidate.verification.verified) << r.candidate.verification.limit;
  EXPECT_EQ(r.candidate.classification.family, Family::planar);
}

TEST(RunStart, AZeroFoundTo1e7IsPolishedOntoItsMotionAndVerifiedAsLoopfarmVerifyDoes) {
  const Job job = read_job_file(std::string(LOOPFARM_SOURCE_DIR) + "/jobs/generic-6r.toml");
  const StartSummary s = run_start(job, 567);
  ASSERT_TRUE(s.zero);
  const GeometryPolishSummary& p = s.candidate.polish;
  ASSERT_TRUE(p.converged) << p.message;
  EXPECT_GT(p.iterations, 0);
  EXPECT_GT(p.displacement, 1e-9);
  EXPECT_LT(p.displacement, 1e-6);
  EXPECT_TRUE(s.candidate.verification.verified) << s.candidate.verification.limit;
  const Eigen::VectorXd x = job.space.free_values(s.candidate.geometry);
  EXPECT_TRUE((x.array() >= job.space.lower_bounds().array()).all());
  EXPECT_TRUE((x.array() <= job.space.upper_bounds().array()).all());
  EXPECT_FALSE(verify_motion(s.final_geometry, nullptr).verified);
  const VerificationSummary polished = verify_motion(s.candidate.geometry, nullptr);
  EXPECT_TRUE(polished.verified);
  EXPECT_LT(polished.worst_residual, 1e-11);
  // The geometry the farm stores moves as given, at round-off, as `loopfarm
  // verify` judges it.
  VerificationSummary as_given = polished;
  const RoundOffCheck round_off = check_round_off(s.candidate.geometry, as_given, StartOptions{});
  EXPECT_TRUE(as_given.verified) << as_given.limit;
  if (round_off.polished) {
    EXPECT_LE(round_off.candidate.polish.displacement, 1e-12);
  }

  const StartSummary refused = run_start(job, 1569);
  ASSERT_TRUE(refused.zero);
  EXPECT_FALSE(refused.candidate.polish.converged);
  EXPECT_FALSE(refused.candidate.verification.verified);
  EXPECT_NE(refused.candidate.verification.limit.find("not polished"), std::string::npos);
  EXPECT_FALSE(verify_motion(refused.final_geometry, nullptr).verified);

  // Start 2245: a near-trivial loop whose closure Jacobian is near singular
  // all along its circuits (its fifth singular value below 1e-6 of the
  // largest): its circuit closes to 6e-10, not to round-off, and polished
  // along its few regular poses it no longer moves. It is refused.
  const StartSummary singular = run_start(job, 2245);
  ASSERT_TRUE(singular.zero);
  EXPECT_FALSE(singular.candidate.verification.verified);
  EXPECT_NE(singular.candidate.verification.limit.find("polish"), std::string::npos)
      << singular.candidate.verification.limit;
}

// Zeros of the rocker job whose circuit cannot be followed from the search's
// pose (starts 299 and 1464: theta0 lies in a gap of the input's range that
// the window's samples step over, so the pose at theta0 does not close;
// 1478: two freedoms, the curve with the chosen joint held ends) are
// verified, from the coarse trace where it is regular, else from the whole
// motion, as `loopfarm verify` does it. So are starts 144 and 211 of the
// Bricard 6R job, line-symmetric loops whose search left its samples on a
// near miss's tube while their circuits lie elsewhere. The farm seeks those
// circuits from guesses with every joint free only (whole_motion_scan_inputs
// 0), `loopfarm verify` at 24 input angles besides: the same verdict and
// family, from fewer seeds.
TEST(RunStart, AZeroWhoseCircuitCannotBeFollowedFromItsPoseIsVerifiedFromTheWholeMotion) {
  const Job rocker = read_job_file(std::string(LOOPFARM_SOURCE_DIR) + "/jobs/trihedral-rocker-6r.toml");
  const Job bricard = read_job_file(std::string(LOOPFARM_SOURCE_DIR) + "/jobs/bricard-6r.toml");
  VerificationOptions through_pose;  // the circuit through the pose in steps of 1 deg
  through_pose.all_circuits = false;
  through_pose.steps_per_turn = 360;
  const struct {
    const Job& job;
    std::uint64_t index;
    Family family;
  } zeros[] = {{rocker, 299, Family::bricard_trihedral},
               {rocker, 1464, Family::bricard_trihedral},
               {rocker, 1478, Family::bricard_trihedral},
               {bricard, 144, Family::bricard_line_symmetric},
               {bricard, 211, Family::bricard_line_symmetric}};
  ASSERT_EQ(StartOptions{}.whole_motion_scan_inputs, 0);
  for (const auto& zero : zeros) {
    const StartSummary s = run_start(zero.job, zero.index);
    ASSERT_TRUE(s.zero) << zero.index;
    EXPECT_FALSE(verify_motion(s.final_geometry, s.final_angles, through_pose).verified) << zero.index;
    const VerificationSummary& farm = s.candidate.verification;
    EXPECT_TRUE(farm.verified) << zero.index;
    EXPECT_EQ(s.candidate.classification.family, zero.family) << zero.index;

    // `loopfarm verify` at the farm's pose: the circuit through it is the one
    // reported, found with the scan of assemblies at fixed inputs too.
    const VerificationSummary verify = verify_motion(s.candidate.geometry, farm.pose());
    EXPECT_TRUE(verify.verified) << zero.index;
    EXPECT_TRUE(verify.on_motion) << zero.index;
    const CandidateAnalysis analysed =
        analyse_candidate(s.candidate.geometry, verify.pose(), verify, Eigen::MatrixXd::Zero(1, 1), StartOptions{});
    EXPECT_EQ(analysed.classification.family, zero.family) << zero.index;
    // Where the farm searched every circuit (starts 1478, 144, 211; 299 and
    // 1464 are verified by the trace through their pose, with no seeds):
    if (s.candidate.polish.iterations == 0 && farm.motion.seeds > 0) {
      EXPECT_LT(farm.motion.seeds, verify.motion.seeds) << zero.index;
    }
  }
}

// Start 1074 of the generic 6R job: its cycle closes at three isolated poses
// (the start pose among them; each sample adds one condition on 18
// parameters) and follows a trivial motion (joints 1 and 4 turning about
// coincident axes) at its other thirteen samples. The analysis verifies the
// motion from those samples, with no search of the whole motion; `loopfarm
// verify`'s search of the whole motion finds the same trivial loop.
TEST(RunStart, AZeroWhoseStartPoseIsIsolatedIsVerifiedFromItsOtherCycleSamples) {
  const Job job = read_job_file(std::string(LOOPFARM_SOURCE_DIR) + "/jobs/generic-6r.toml");
  const StartSummary s = run_start(job, 1074);
  ASSERT_TRUE(s.zero);
  VerificationOptions through_pose;
  through_pose.all_circuits = false;
  const VerificationSummary alone = verify_motion(s.final_geometry, s.final_angles, through_pose);
  EXPECT_FALSE(alone.verified);
  EXPECT_EQ(alone.motion.isolated_poses.size(), 1u);

  const VerificationSummary& v = s.candidate.verification;
  ASSERT_TRUE(v.verified) << v.limit;
  EXPECT_FALSE(v.on_motion);
  EXPECT_EQ(v.motion.seeds, 0);  // no assembly search: the circuit came from a sample
  EXPECT_EQ(s.candidate.classification.family, Family::trivial);

  const VerificationSummary whole = verify_motion(s.final_geometry, nullptr);
  ASSERT_TRUE(whole.verified);
  EXPECT_GT(whole.motion.seeds, 0);
  const Classification by_whole = classify(s.final_geometry, whole.pose(),
                                           {whole.joint_travel.data(), static_cast<size_t>(whole.joint_travel.size())},
                                           StartOptions{}.classification);
  EXPECT_EQ(by_whole.family, Family::trivial);
  // The same motion: the same joints turn fully, the others are frozen.
  for (int k = 0; k < 6; ++k) {
    EXPECT_EQ(v.joint_travel[k] > 1.0, whole.joint_travel[k] > 1.0) << k;
    EXPECT_NEAR(v.joint_travel[k], whole.joint_travel[k], 1e-6) << k;
  }
}

// A trial whose cycle shows it above what the step needs to be accepted is
// given up before its cycle ends. On the default job's first starts (steered,
// 4 samples, box bounds) many trials are rejected, and many of those are
// given up; none is accepted. (That a given-up trial's value is a lower
// bound above its ceiling is checked against whole evaluations in
// Objective.AnEvaluationAboveItsCeilingIsAbandonedWithALowerBound.)
TEST(RunStart, GaussNewtonGivesUpTrialsAboveTheAcceptanceCeiling) {
  const Job job = read_job_file(std::string(LOOPFARM_SOURCE_DIR) + "/jobs/default.toml");
  int abandoned = 0, rejected = 0, accepted = 0;
  for (std::uint64_t index = 0; index < 5; ++index) {
    StartOptions options;
    options.trace = [&](const SearchTraceRow& row) {
      if (row.accepted) {
        EXPECT_FALSE(row.abandoned) << index;
        ++accepted;
        return;
      }
      ++rejected;
      abandoned += row.abandoned;
    };
    const StartSummary s = run_start(job, index, options);
    EXPECT_TRUE(std::isfinite(s.E_mean)) << index;
  }
  EXPECT_GT(accepted, 0);
  EXPECT_GT(rejected, 0);
  EXPECT_GT(abandoned, rejected / 2) << abandoned << " of " << rejected;
}

// A start reports the unsteered energy of its final geometry, whichever
// cycle it was read from (the search's own, where the start is no zero): a
// cycle walked afresh from the start's final angles at its final geometry
// agrees, and a zero's energy is that of a cycle evaluated without steering.
TEST(RunStart, TheReportedEnergyIsTheFinalGeometrysUnsteeredCycle) {
  const Job job = read_job_file(std::string(LOOPFARM_SOURCE_DIR) + "/jobs/default.toml");
  const ObjectiveOptions plain = ObjectiveOptions::from_loop(job.loop);
  int compared = 0, zeros = 0;
  for (std::uint64_t index = 0; index < 24; ++index) {
    const StartSummary s = run_start(job, index);
    if (!std::isfinite(s.E_mean) || s.failed_samples > 0 || s.branch_jumps > 0) continue;
    const LoopModel model(s.final_geometry, plain.equilibrium);
    EquilibriumWorkspace ws(model);
    const EquilibriumSummary start = assemble_from_angles(model, ws, s.final_angles);
    ASSERT_EQ(start.status, SolveStatus::converged) << index;
    EXPECT_LT((start.state.theta - s.final_angles).cwiseAbs().maxCoeff(), 1e-8) << index;
    CycleSummary cycle;
    cycle_energy(model, ws, s.final_angles[0], start.state, plain.cycle, cycle);
    ASSERT_EQ(cycle.failed_samples, 0) << index;
    EXPECT_NEAR(cycle.E_mean, s.E_mean, 1e-8 * s.E_mean + 1e-22) << index;
    EXPECT_NEAR(cycle.E_max, s.E_max, 1e-8 * s.E_max + 1e-22) << index;
    EXPECT_EQ(s.zero, s.E_mean <= job.search.zero_threshold) << index;
    ++compared;
    zeros += s.zero;
  }
  EXPECT_GE(compared, 16);
  EXPECT_GE(zeros, 3);
  EXPECT_LE(zeros, compared - 3);
}

// Non-triviality moves a search off a frozen-joint minimum: start 46 of the
// unsteered generic 4R job ends on a trivial loop (a joint that does not
// turn); with [steering] nontrivial = true the same start ends on a Bennett
// loop, every joint turning.
TEST(RunStart, NonTrivialityLeadsASearchOffAFrozenJointMinimum) {
  Job job = read_job_file(std::string(LOOPFARM_SOURCE_DIR) + "/jobs/generic-4r.toml");
  ASSERT_FALSE(job.steering.nontrivial);
  const StartSummary plain = run_start(job, 46);
  ASSERT_TRUE(plain.zero);
  ASSERT_TRUE(plain.candidate.verification.verified);
  EXPECT_EQ(plain.candidate.classification.family, Family::trivial);
  const JointVector& frozen = plain.candidate.verification.joint_travel;
  EXPECT_LT(frozen.minCoeff(), job.steering.min_travel);

  job.steering.nontrivial = true;
  const StartSummary steered = run_start(job, 46);
  ASSERT_TRUE(steered.zero);
  ASSERT_TRUE(steered.candidate.verification.verified);
  EXPECT_EQ(steered.candidate.classification.family, Family::bennett);
  EXPECT_GT(steered.candidate.verification.joint_travel.minCoeff(), job.steering.min_travel);
}

// A search in a symmetric sub-space stays in it: the start, every step and
// the final geometry are line- or plane-symmetric to the bit (the images are
// ties, not variables of their own).
TEST(RunStart, ASearchInASymmetricSubspaceStaysInIt) {
  for (const char* symmetry : {"line", "plane"}) {
    const Job job = parse_job(std::string("[loop]\njoints = 6\nsamples = 8\n[space]\nsymmetry = \"") + symmetry +
                                  "\"\n[optimizer]\nmax_evaluations = 15\n",
                              "symmetric.toml");
    for (std::uint64_t index : {0u, 1u}) {
      const StartSummary s = run_start(job, index);
      for (const LoopGeometry* g : {&s.initial_geometry, &s.final_geometry}) {
        for (int i = 0; i < 6; ++i) {
          if (std::string(symmetry) == "line") {
            EXPECT_EQ(g->a[(i + 3) % 6], g->a[i]) << i;
            EXPECT_EQ(g->alpha[(i + 3) % 6], g->alpha[i]) << i;
            EXPECT_EQ(g->d[(i + 3) % 6], g->d[i]) << i;
          } else {
            EXPECT_EQ(g->a[5 - i], g->a[i]) << i;
            EXPECT_EQ(g->alpha[5 - i], -g->alpha[i]) << i;
            EXPECT_EQ(g->d[(6 - i) % 6], -g->d[i]) << i;
          }
        }
      }
      EXPECT_GE(s.evaluations, 1) << symmetry << " " << index;
    }
  }
}

LoopGeometry from_degrees(std::vector<double> a, std::vector<double> alpha_deg, std::vector<double> d) {
  return LoopGeometry::from_degrees(std::span<const double>(a), std::span<const double>(alpha_deg),
                                    std::span<const double>(d));
}

// Every family that [steering] deflate accepts for a loop of its size becomes
// a deflation term measuring the distance to that family: zero (to round-off)
// on a member (the examples of docs/guide/families.md), not on a generic loop of
// the same size. The job parser keeps its own list of these names (it stands
// alone for the fuzzers); this checks that start.cpp maps each of them.
TEST(ObjectiveOptions, EveryDeflatableFamilyMeasuresItsDistance) {
  const double s3 = std::sqrt(3.0);
  struct Case {
    const char* family;
    LoopGeometry member;
  };
  const Case cases[] = {
      {"bennett", paper_bennett_loop()},
      {"goldberg", from_degrees({2, 1, s3, 2, 1 + s3}, {90, 30, 60, 90, 90}, {0, 0, 0, 0, 0})},
      {"myard", from_degrees({2, 1, 1, 2, 2}, {90, 30, -30, 90, 0}, {0, 0, 0, 0, 0})},
      // docs/guide/families.md's bent Goldberg example: the Goldberg loop's links fused at 90 deg.
      {"goldberg_bent", from_degrees({2, 1, s3, 2, 1.7185034823583989}, {90, 30, 60, 90, 64.341093726744717},
                                     {0.60433895850392444, 0, 0, 0, 0.60433895850392444})},
      {"bricard_line_symmetric",
       from_degrees({1, 1.7, 0.8, 1, 1.7, 0.8}, {51.566, 120.321, -34.377, 51.566, 120.321, -34.377},
                    {0.4, 0.3, -0.5, 0.4, 0.3, -0.5})},
      {"bricard_plane_symmetric",
       from_degrees({1, 1.7, 0.8, 0.8, 1.7, 1}, {51.566, 120.321, -34.377, 34.377, -120.321, -51.566},
                    {0, 0.3, -0.5, 0, 0.5, -0.3})},
      {"bricard_trihedral",
       from_degrees({1.5, 1, 1.2, 0.8, 1, std::sqrt(1.5 * 1.5 + 1.2 * 1.2 + 1.0 - 1.0 - 0.8 * 0.8)},
                    {90, -90, 90, -90, 90, -90}, {0, 0, 0, 0, 0, 0})},
      // docs/guide/families.md's example: Bennett loops (1, 30 deg, 2, 90 deg) and (sqrt 3, 60 deg, 2, 90 deg) sharing
      // a link.
      {"bennett_pair", from_degrees({1, 2, 1, s3, 2, s3}, {30, 90, 30, 60, 90, 60}, {0, 0, 0, 0, 0, 0})},
      // docs/guide/families.md's example of two Bennett dyads joined by equal links.
      {"bennett_dyads",
       from_degrees({0.29105928100629913, 0.3266234112565141, 1.1155627045785708, 2.0724378472248963, 2.112627142478364,
                     1.1155627045785708},
                    {-160.21822699133264, -157.67920498998612, -40.123422809296045, -112.41458911002134,
                     -109.54549378379366, -40.123422809296045},
                    {-0.29099955783023707, 0, -0.29099955783023707, 0.017028759702287233, 0, 0.017028759702287233})},
      // Starts 864 (d4 = -d1) and 5 (d4 = d1: a member with axes 1, 3 and 5 flipped) of jobs/generic-6r.toml.
      {"bennett_triads", from_degrees({1.165752711796717, 0.8040533354316156, 1.3379730979393316, 0.9319483958859982,
                                       0.6430208449406091, 0.9274364786873017},
                                      {-129.8846740568725, -31.955084790648083, -118.27334450966706,
                                       -107.36344649060115, -41.18810320360831, -108.22967594575732},
                                      {-0.17635872006793546, 0, 0, 0.17635872006793538, 0, 0})},
      {"bennett_triads", from_degrees({1.0079702612795016, 1.1446335082314096, 0.6482949350461149, 1.240793584096262,
                                       1.1202202087502942, 0.636125942134677},
                                      {-50.751268926402275, -118.4296001713174, -29.872667185553468, -119.2737180304487,
                                       -51.95519308590798, -26.564476500103257},
                                      {-0.1649325812564212, 0, 0, -0.16493258125642063, 0, 0})},
      // Start 3846 of jobs/generic-6r.toml, as stored (its dyads are links 3-4 and 6-1).
      {"coupled_bennett_dyads", from_degrees({0.3023234939518641, 0.9844316004817011, 0.3042750933596505,
                                              1.2849219297835957, 1.3574945500275204, 1.1544084938366366},
                                             {-164.81806735367473, -80.70879432965593, -166.39161112330765,
                                              -83.50489277454984, -63.28144704971678, -89.82660131005586},
                                             {-1.8139442610943663e-15, -0.07435716153609594, 0.11150246029669164,
                                              -2.0663271497065275e-15, -0.011303211857753584, 0.0484485106183532})},
  };
  for (const Case& c : cases) {
    const int n = c.member.joints();
    const Job job = parse_job(
        "[loop]\njoints = " + std::to_string(n) + "\n[steering]\ndeflate = [\"" + c.family + "\", \"planar\"]\n",
        "deflate.toml");
    const ObjectiveOptions options = objective_options(job);
    ASSERT_EQ(options.deflation.size(), 2u) << c.family;
    EXPECT_EQ(options.deflation[0].family, c.family);
    GeometryVector gradient;
    EXPECT_LT(options.deflation[0].distance(c.member, &gradient), 1e-12) << c.family;
    const double generic = options.deflation[0].distance(random_loop(n, 11), nullptr);
    EXPECT_GT(generic, 1e-3) << c.family;
    EXPECT_GT(options.deflation[1].distance(c.member, nullptr), 1e-3) << c.family << ": planar";
  }
}

// The job parser's own list of deflatable names (it stands alone for the
// fuzzers) against classify's: a family is accepted in [steering] deflate,
// for a loop of its joint count, exactly where family_distance measures it.
TEST(ObjectiveOptions, DeflatableNamesAreTheFamiliesWithADistance) {
  for (Family f : kAllFamilies) {
    const int n = family_joints(f) != 0 ? family_joints(f) : 5;
    const std::string text =
        "[loop]\njoints = " + std::to_string(n) + "\n[steering]\ndeflate = [\"" + to_string(f) + "\"]\n";
    if (has_family_distance(f)) {
      const ObjectiveOptions options = objective_options(parse_job(text, "deflate.toml"));
      ASSERT_EQ(options.deflation.size(), 1u) << to_string(f);
      EXPECT_EQ(options.deflation[0].family, to_string(f));
    } else {
      EXPECT_ANY_THROW(parse_job(text, "deflate.toml")) << to_string(f);
    }
  }
}

}  // namespace
}  // namespace loopfarm
