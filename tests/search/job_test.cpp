#include "loopfarm/search/job.hpp"
#include "loopfarm/search/objective.hpp"

#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "test_support.hpp"

namespace loopfarm {
namespace {

using testing::rad;

constexpr const char* kFullJob = R"(# every table
[loop]
joints = 5
compliance = "full"
stiffness_ratio = 2.5
samples = 48
range_deg = 120

[space]
a = [1, 3]
alpha_deg = [10, 170]
d = 0
theta_deg = [-90, 90]
a1 = 2.0
alpha2_deg = [20, 40]
a3 = "a2"
d4 = [-0.5, 0.5]
d5 = "-d4"
theta1_deg = 30
theta2_deg = "-theta3_deg"

[optimizer]
algorithm = "LD_LBFGS"
xtol_rel = 1e-8
ftol_rel = 1e-12
ftol_abs = 1e-20
stopval = 1e-24
max_evaluations = 250
progress_window = 40
progress_factor = 3
checkpoint_evaluations = 20
checkpoint_objective = 1e-6
time_limit_s = 12.5
reuse_nearby_cycle = false

[search]
starts = 1000
seed = 42
zero_threshold = 1e-11

[steering]
nontrivial = true
min_travel_deg = 10
deflate = ["planar", "trivial"]
deflation_power = 3
deflation_shift = 0.5

[output]
database = "out/results.sqlite"
report_threshold = 1e-4
)";

TEST(Job, EquilibriumTolerancesDefaultToTheSolversAndCanBeSet) {
  const Job defaults = parse_job("[loop]\njoints = 4\n", "d.toml");
  EXPECT_EQ(defaults.loop.closure_tolerance, EquilibriumOptions{}.closure_tolerance);
  EXPECT_EQ(defaults.loop.stationarity_tolerance, EquilibriumOptions{}.stationarity_tolerance);
  const Job set = parse_job("[loop]\nclosure_tolerance = 1e-9\nstationarity_tolerance = 1e-7\n", "s.toml");
  EXPECT_EQ(set.loop.closure_tolerance, 1e-9);
  EXPECT_EQ(set.loop.stationarity_tolerance, 1e-7);
  EXPECT_EQ(defaults.loop.objective, "mean");
  EXPECT_EQ(ObjectiveOptions::from_loop(defaults.loop).measure, CycleMeasure::mean);
  EXPECT_EQ(ObjectiveOptions::from_loop(parse_job("[loop]\nobjective = \"max\"\n", "m.toml").loop).measure,
            CycleMeasure::max);
  // ... and reach the solver of every cycle the search evaluates.
  const ObjectiveOptions objective = ObjectiveOptions::from_loop(set.loop);
  EXPECT_EQ(objective.equilibrium.closure_tolerance, 1e-9);
  EXPECT_EQ(objective.equilibrium.stationarity_tolerance, 1e-7);
}

TEST(Job, ParsesEveryTableInTheDocumentedUnits) {
  const Job job = parse_job(kFullJob, "dir/full.toml");
  EXPECT_EQ(job.loop.joints, 5);
  EXPECT_EQ(job.loop.compliance, Compliance::full);
  EXPECT_EQ(job.loop.stiffness_ratio, 2.5);
  EXPECT_EQ(job.loop.samples, 48);
  EXPECT_NEAR(job.loop.range, rad(120), 1e-15);
  const ParameterSpace& s = job.space;
  using M = ParameterSpec::Mode;
  const auto& a1 = s.specs[static_cast<size_t>(s.index(ParameterKind::a, 0))];
  EXPECT_EQ(a1.mode, M::fixed);
  EXPECT_EQ(a1.value, 2.0);
  EXPECT_EQ(a1.line, 14);
  const auto& a2 = s.specs[static_cast<size_t>(s.index(ParameterKind::a, 1))];
  EXPECT_EQ(a2.mode, M::range);  // the default
  EXPECT_EQ(a2.lo, 1.0);
  EXPECT_EQ(a2.hi, 3.0);
  const auto& a3 = s.specs[static_cast<size_t>(s.index(ParameterKind::a, 2))];
  EXPECT_EQ(a3.mode, M::tied);
  EXPECT_EQ(a3.source, s.index(ParameterKind::a, 1));
  EXPECT_EQ(a3.sign, 1.0);
  const auto& alpha2 = s.specs[static_cast<size_t>(s.index(ParameterKind::alpha, 1))];
  EXPECT_NEAR(alpha2.lo, rad(20), 1e-15);
  EXPECT_NEAR(alpha2.hi, rad(40), 1e-15);
  const auto& d5 = s.specs[static_cast<size_t>(s.index(ParameterKind::d, 4))];
  EXPECT_EQ(d5.mode, M::tied);
  EXPECT_EQ(d5.sign, -1.0);
  EXPECT_EQ(s.specs[static_cast<size_t>(s.index(ParameterKind::d, 0))].mode, M::fixed);
  // Free: a2, a4, a5, alpha1..alpha5, d4 = 9.
  EXPECT_EQ(s.free_count(), 9);
  EXPECT_EQ(s.random_angle_count(), 3);  // theta3, theta4, theta5 (the default range)
  EXPECT_EQ(job.optimizer.algorithm, "LD_LBFGS");
  EXPECT_EQ(job.optimizer.xtol_rel, 1e-8);
  EXPECT_EQ(job.optimizer.ftol_rel, 1e-12);
  EXPECT_EQ(job.optimizer.ftol_abs, 1e-20);
  EXPECT_EQ(job.optimizer.stopval, 1e-24);
  EXPECT_EQ(job.optimizer.max_evaluations, 250);
  EXPECT_EQ(job.optimizer.progress_window, 40);
  EXPECT_EQ(job.optimizer.progress_factor, 3.0);
  EXPECT_EQ(job.optimizer.checkpoint_evaluations, 20);
  EXPECT_EQ(job.optimizer.checkpoint_objective, 1e-6);
  EXPECT_EQ(job.optimizer.time_limit, 12.5);
  EXPECT_FALSE(job.optimizer.reuse_nearby_cycle);
  EXPECT_EQ(job.search.starts, 1000);
  EXPECT_EQ(job.search.seed, 42u);
  EXPECT_EQ(job.search.zero_threshold, 1e-11);
  EXPECT_TRUE(job.steering.nontrivial);
  EXPECT_NEAR(job.steering.min_travel, rad(10), 1e-15);
  EXPECT_EQ(job.steering.deflate, (std::vector<std::string>{"planar", "trivial"}));
  EXPECT_EQ(job.steering.deflation_power, 3.0);
  EXPECT_EQ(job.steering.deflation_shift, 0.5);
  EXPECT_EQ(job.output.database, "out/results.sqlite");  // where the user stands, not the job file
  EXPECT_EQ(job.output.report_threshold, 1e-4);
}

TEST(Job, EmptyFileGivesTheDocumentedDefaults) {
  const Job job = parse_job("", "empty.toml");
  EXPECT_EQ(job.loop.joints, 4);
  EXPECT_EQ(job.loop.compliance, Compliance::paper);
  EXPECT_EQ(job.loop.samples, 32);
  EXPECT_NEAR(job.loop.range, 2 * 3.14159265358979323846, 0);
  EXPECT_EQ(job.space.free_count(), 12);  // a, alpha, d all free by default
  EXPECT_EQ(job.space.random_angle_count(), 4);
  EXPECT_EQ(job.space.lower_bounds()[0], 0.5);
  EXPECT_EQ(job.space.upper_bounds()[0], 5.0);
  EXPECT_NEAR(job.space.upper_bounds()[4], rad(180), 1e-15);
  EXPECT_EQ(job.space.lower_bounds()[8], -1.0);
  EXPECT_EQ(job.optimizer.algorithm, "gauss-newton");
  EXPECT_TRUE(job.optimizer.reuse_nearby_cycle);
  EXPECT_EQ(job.optimizer.progress_window, 0);         // the progress stop is off
  EXPECT_EQ(job.optimizer.checkpoint_evaluations, 0);  // and the checkpoint
  EXPECT_EQ(job.search.starts, 100);
  EXPECT_FALSE(job.steering.nontrivial);
  EXPECT_TRUE(job.steering.deflate.empty());
  EXPECT_EQ(job.output.database, "loopfarm.sqlite");
  EXPECT_EQ(job.output.report_threshold, 1e-6);
  // An [output] table without a database keeps the default, in the working directory.
  EXPECT_EQ(parse_job("[output]\nreport_threshold = 1e-3\n", "dir/job.toml").output.database, "loopfarm.sqlite");
  EXPECT_EQ(parse_job("", "dir/job.toml").output.database, "loopfarm.sqlite");
  EXPECT_EQ(parse_job("[output]\ndatabase = \"/abs/r.sqlite\"\n", "dir/job.toml").output.database, "/abs/r.sqlite");
  EXPECT_EQ(parse_job("[search]\nstarts = 5\n", "x.toml").text, "[search]\nstarts = 5\n");
}

TEST(ParameterSpace, GeometryHonoursFixedFreeAndTiedAndItsJacobianIsExact) {
  const Job job = parse_job(kFullJob, "full.toml");
  const ParameterSpace& s = job.space;
  Eigen::VectorXd x(s.free_count());
  for (int i = 0; i < x.size(); ++i) x[i] = 0.5 * (s.lower_bounds()[i] + s.upper_bounds()[i]) + 0.01 * i;
  const LoopGeometry g = s.geometry(x);
  EXPECT_EQ(g.a[0], 2.0);
  EXPECT_EQ(g.a[2], g.a[1]);
  EXPECT_EQ(g.d[4], -g.d[3]);
  EXPECT_EQ(g.d[0], 0.0);
  // Round trip on the free parameters.
  EXPECT_EQ(s.free_values(g), x);
  // The Jacobian against central differences of geometry(x).
  const Eigen::MatrixXd J = s.geometry_jacobian();
  for (int i = 0; i < x.size(); ++i) {
    Eigen::VectorXd p = x, m = x;
    p[i] += 1e-3;
    m[i] -= 1e-3;
    const LoopGeometry gp = s.geometry(p), gm = s.geometry(m);
    Eigen::VectorXd fd(15);
    fd << (gp.a - gm.a) / 2e-3, (gp.alpha - gm.alpha) / 2e-3, (gp.d - gm.d) / 2e-3;
    EXPECT_LT((J.col(i) - fd).cwiseAbs().maxCoeff(), 1e-9) << i;
  }
  // Initial angles: theta1 fixed, theta2 = -theta3, theta3..5 drawn.
  Eigen::VectorXd draws(s.random_angle_count());
  for (int i = 0; i < draws.size(); ++i) draws[i] = 0.1 * (i + 1);
  const JointVector theta = s.initial_angles(draws);
  EXPECT_NEAR(theta[0], rad(30), 1e-15);
  EXPECT_EQ(theta[1], -theta[2]);
}

// The geometry of a space at free values spread over their boxes.
LoopGeometry geometry_inside(const ParameterSpace& s) {
  Eigen::VectorXd x(s.free_count());
  for (int i = 0; i < x.size(); ++i) {
    const double u = 0.13 + 0.71 * std::fmod(0.37 * (i + 1), 1.0);
    x[i] = s.lower_bounds()[i] + u * (s.upper_bounds()[i] - s.lower_bounds()[i]);
  }
  return s.geometry(x);
}

// symmetry = "line": a_{i+3} = a_i, alpha_{i+3} = alpha_i, d_{i+3} = d_i
// for 6R, as ties to the first half (9 free parameters: the dimension of
// Bricard's line-symmetric family); the sources keep their own forms, and a
// source tied by the user takes its image along (alpha5 = alpha2 = -alpha1).
TEST(ParameterSpace, LineSymmetryTiesTheSecondHalfToTheFirst) {
  const Job job = parse_job("[loop]\njoints = 6\n[space]\nsymmetry = \"line\"\na1 = 2\nalpha2_deg = \"-alpha1_deg\"\n",
                            "line.toml");
  const ParameterSpace& s = job.space;
  EXPECT_EQ(s.free_count(), 7);  // a2, a3, alpha1, alpha3, d1..d3
  const LoopGeometry g = geometry_inside(s);
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(g.a[i + 3], g.a[i]) << i;
    EXPECT_EQ(g.alpha[i + 3], g.alpha[i]) << i;
    EXPECT_EQ(g.d[i + 3], g.d[i]) << i;
  }
  EXPECT_EQ(g.a[3], 2.0);
  EXPECT_EQ(g.alpha[4], -g.alpha[0]);
  EXPECT_NE(g.d[0], g.d[1]);
  EXPECT_EQ(s.random_angle_count(), 6);  // initial angles are not tied
  const Job plain = parse_job("[loop]\njoints = 6\n[space]\nsymmetry = \"line\"\n", "line.toml");
  EXPECT_EQ(plain.space.free_count(), 9);
  EXPECT_EQ(parse_job("[loop]\njoints = 6\n[space]\nsymmetry = \"none\"\n", "none.toml").space.free_count(), 18);
}

// symmetry = "plane" (6R): the mirror through joints 1 and 4 of
// docs/guide/families.md, a1 = a6, a2 = a5, a3 = a4, alpha1 = -alpha6, alpha2 =
// -alpha5, alpha3 = -alpha4, d1 = d4 = 0, d2 = -d6, d3 = -d5 (8 free: the
// dimension of Bricard's plane-symmetric family); for 4R the same mirror.
TEST(ParameterSpace, PlaneSymmetryMirrorsThroughJointsOneAndHalfWay) {
  const Job job = parse_job("[loop]\njoints = 6\n[space]\nsymmetry = \"plane\"\n", "plane.toml");
  EXPECT_EQ(job.space.free_count(), 8);
  const LoopGeometry g = geometry_inside(job.space);
  EXPECT_EQ(g.d[0], 0.0);
  EXPECT_EQ(g.d[3], 0.0);
  EXPECT_EQ(g.d[5], -g.d[1]);
  EXPECT_EQ(g.d[4], -g.d[2]);
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(g.a[5 - i], g.a[i]) << i;
    EXPECT_EQ(g.alpha[5 - i], -g.alpha[i]) << i;
  }
  EXPECT_NE(g.d[1], 0.0);
  const Job four = parse_job("[space]\nsymmetry = \"plane\"\n", "plane4.toml");
  const LoopGeometry h = geometry_inside(four.space);
  EXPECT_EQ(four.space.free_count(), 5);  // a1, a2, alpha1, alpha2, d2
  EXPECT_EQ(h.a[3], h.a[0]);
  EXPECT_EQ(h.a[2], h.a[1]);
  EXPECT_EQ(h.alpha[3], -h.alpha[0]);
  EXPECT_EQ(h.alpha[2], -h.alpha[1]);
  EXPECT_EQ(h.d[0], 0.0);
  EXPECT_EQ(h.d[2], 0.0);
  EXPECT_EQ(h.d[3], -h.d[1]);
}

// One bad input: the text, and what the one-line message must contain.
struct BadJob {
  const char* name;
  const char* text;
  int line;
  const char* key;
  const char* words;
};

class JobRejects : public ::testing::TestWithParam<BadJob> {};

TEST_P(JobRejects, WithFileLineAndKey) {
  const BadJob& bad = GetParam();
  try {
    parse_job(bad.text, "bad.toml");
    FAIL() << bad.name << ": accepted";
  } catch (const JobError& e) {
    const std::string what = e.what();
    EXPECT_EQ(e.file(), "bad.toml");
    EXPECT_EQ(e.line(), bad.line) << what;
    EXPECT_EQ(e.key(), bad.key) << what;
    EXPECT_EQ(what.rfind("bad.toml:" + std::to_string(bad.line) + ": " + bad.key + ": ", 0), 0u) << what;
    EXPECT_NE(what.find(bad.words), std::string::npos) << what;
    EXPECT_EQ(what.find('\n'), std::string::npos) << what;
    EXPECT_EQ(what.find('\r'), std::string::npos) << what;
  }
}

INSTANTIATE_TEST_SUITE_P(
    EveryRule, JobRejects,
    ::testing::Values(
        BadJob{"syntax", "[loop]\njoints = = 4\n", 2, "(syntax)", "invalid TOML"},
        BadJob{"unknown_table", "[loops]\njoints = 4\n", 1, "loops", "unknown table"},
        BadJob{"unknown_key", "[loop]\njoint = 4\n", 2, "loop.joint", "unknown key"},
        BadJob{"joints_type", "[loop]\njoints = 4.5\n", 2, "loop.joints", "expected an integer"},
        BadJob{"joints_small", "[loop]\njoints = 3\n", 2, "loop.joints", "4 to 8"},
        BadJob{"joints_large", "[loop]\njoints = 9\n", 2, "loop.joints", "4 to 8"},
        BadJob{"compliance", "[loop]\ncompliance = \"rigid\"\n", 2, "loop.compliance", "\"rigid\""},
        BadJob{"ratio_zero", "[loop]\nstiffness_ratio = 0\n", 2, "loop.stiffness_ratio", "> 0"},
        BadJob{"ratio_nan", "[loop]\nstiffness_ratio = nan\n", 2, "loop.stiffness_ratio", "finite"},
        BadJob{"samples_few", "[loop]\nsamples = 3\n", 2, "loop.samples", "[4, 100000]"},
        BadJob{"range_large", "[loop]\nrange_deg = 400\n", 2, "loop.range_deg", "(0, 360]"},
        BadJob{"tolerance_large", "[loop]\nclosure_tolerance = 0.1\n", 2, "loop.closure_tolerance", "(0, 1e-3]"},
        BadJob{"objective", "[loop]\nobjective = \"median\"\n", 2, "loop.objective", "\"mean\""},
        BadJob{"tolerance_zero", "[loop]\nstationarity_tolerance = 0.0\n", 2, "loop.stationarity_tolerance", "> 0"},
        BadJob{"space_unknown", "[space]\nb1 = 2\n", 2, "space.b1", "unknown parameter"},
        BadJob{"space_beyond_n", "[space]\na5 = 2\n", 2, "space.a5", "joints = 4"},
        BadJob{"space_lo_gt_hi", "\n[space]\nalpha1_deg = [90, 30]\n", 3, "space.alpha1_deg", "lo > hi"},
        BadJob{"space_nan", "[space]\nd2 = nan\n", 2, "space.d2", "finite"},
        BadJob{"space_inf_range", "[space]\nd2 = [0, inf]\n", 2, "space.d2", "finite"},
        BadJob{"space_range_size", "[space]\nd2 = [0, 1, 2]\n", 2, "space.d2", "[lo, hi]"},
        BadJob{"space_type", "[space]\nd2 = true\n", 2, "space.d2", "expected a number"},
        BadJob{"negative_length", "[space]\na2 = -1\n", 2, "space.a2", ">= 0"},
        BadJob{"negative_range", "[space]\na2 = [-1, 2]\n", 2, "space.a2", ">= 0"},
        BadJob{"negative_default", "[space]\na = [-1, 2]\n", 0, "space.a1", ">= 0"},
        BadJob{"negated_length_tie", "[space]\na3 = \"-a1\"\n", 2, "space.a3", ">= 0"},
        BadJob{"tie_unknown", "[space]\na3 = \"a9\"\n", 2, "space.a3", "not a parameter"},
        BadJob{"tie_self", "[space]\na3 = \"a3\"\n", 2, "space.a3", "itself"},
        BadJob{"tie_chain", "[space]\na3 = \"a1\"\na4 = \"a3\"\n", 3, "space.a4", "itself tied"},
        BadJob{"tie_units", "[space]\nalpha3_deg = \"a1\"\n", 2, "space.alpha3_deg", "a twist"},
        BadJob{"default_tie", "[space]\na = \"a1\"\n", 2, "space.a", "not a tie"},
        BadJob{"algorithm", "[optimizer]\nalgorithm = \"LD_FAST\"\n", 2, "optimizer.algorithm", "unknown algorithm"},
        BadJob{"stogo", "[optimizer]\nalgorithm = \"GD_STOGO\"\n", 2, "optimizer.algorithm", "Debian"},
        BadJob{"max_eval", "[optimizer]\nmax_evaluations = 0\n", 2, "optimizer.max_evaluations", "[1, 1e8]"},
        BadJob{"progress_window", "[optimizer]\nprogress_window = -1\n", 2, "optimizer.progress_window", "[0, 1e8]"},
        BadJob{"progress_window_type", "[optimizer]\nprogress_window = 2.5\n", 2, "optimizer.progress_window",
               "an integer"},
        BadJob{"progress_factor", "[optimizer]\nprogress_factor = 1\n", 2, "optimizer.progress_factor", "> 1"},
        BadJob{"checkpoint_evaluations", "[optimizer]\ncheckpoint_evaluations = -3\n", 2,
               "optimizer.checkpoint_evaluations", "[0, 1e8]"},
        BadJob{"checkpoint_alone", "[optimizer]\ncheckpoint_evaluations = 20\n", 2, "optimizer.checkpoint_evaluations",
               "needs optimizer.checkpoint_objective"},
        BadJob{"checkpoint_objective", "[optimizer]\ncheckpoint_evaluations = 20\ncheckpoint_objective = 0\n", 3,
               "optimizer.checkpoint_objective", "> 0"},
        BadJob{"time_negative", "[optimizer]\ntime_limit_s = -1\n", 2, "optimizer.time_limit_s", ">= 0"},
        BadJob{"reuse_nearby_cycle", "[optimizer]\nreuse_nearby_cycle = \"yes\"\n", 2, "optimizer.reuse_nearby_cycle",
               "true or false"},
        BadJob{"starts_zero", "[search]\nstarts = 0\n", 2, "search.starts", "> 0"},
        BadJob{"seed_negative", "[search]\nseed = -3\n", 2, "search.seed", ">= 0"},
        BadJob{"threshold", "[search]\nzero_threshold = 0\n", 2, "search.zero_threshold", "> 0"},
        BadJob{"nontrivial_type", "[steering]\nnontrivial = 1\n", 2, "steering.nontrivial", "true or false"},
        BadJob{"deflate_unknown", "[steering]\ndeflate = [\"conic\"]\n", 2, "steering.deflate", "\"conic\""},
        BadJob{"deflate_twice", "[steering]\ndeflate = [\"planar\", \"planar\"]\n", 2, "steering.deflate", "twice"},
        BadJob{"output_type", "[output]\ndatabase = 3\n", 2, "output.database", "expected a string"},
        BadJob{"deflate_bennett_5r", "[loop]\njoints = 5\n[steering]\ndeflate = [\"bennett\"]\n", 4, "steering.deflate",
               "joints = 4"},
        BadJob{"deflate_goldberg_6r", "[loop]\njoints = 6\n[steering]\ndeflate = [\"goldberg\"]\n", 4,
               "steering.deflate", "\"goldberg\" needs joints = 5"},
        BadJob{"deflate_bricard_5r", "[loop]\njoints = 5\n[steering]\ndeflate = [\"planar\", \"bricard_trihedral\"]\n",
               4, "steering.deflate", "\"bricard_trihedral\" needs joints = 6"},
        BadJob{"deflate_degenerate", "[loop]\njoints = 5\n[steering]\ndeflate = [\"degenerate\"]\n", 4,
               "steering.deflate", "\"degenerate\" cannot be deflated: it is decided from the motion"},
        BadJob{"deflate_cubic_321", "[loop]\njoints = 6\n[steering]\ndeflate = [\"cubic_321\"]\n", 4,
               "steering.deflate", "\"cubic_321\" cannot be deflated: it is decided from the motion"},
        BadJob{"symmetry_unknown", "[loop]\njoints = 6\n[space]\nsymmetry = \"diagonal\"\n", 4, "space.symmetry",
               "got \"diagonal\"; expected \"none\", \"line\""},
        BadJob{"symmetry_type", "[space]\nsymmetry = 3\n", 2, "space.symmetry", "expected a string"},
        BadJob{"symmetry_odd", "[loop]\njoints = 5\n[space]\nsymmetry = \"line\"\n", 4, "space.symmetry",
               "needs an even number of joints, the job has 5"},
        BadJob{"symmetry_image_named", "[loop]\njoints = 6\n[space]\nsymmetry = \"line\"\na4 = 2\n", 5, "space.a4",
               "makes a4 = a1; give a1 instead"},
        BadJob{"symmetry_zero_named", "[loop]\njoints = 6\n[space]\nd4 = 0.5\nsymmetry = \"plane\"\n", 4, "space.d4",
               "fixes d4 = 0"},
        BadJob{"symmetry_tie_to_image", "[loop]\njoints = 6\n[space]\nsymmetry = \"plane\"\na2 = \"a6\"\n", 5,
               "space.a2", "itself tied"},
        BadJob{"algorithm_auglag", "[optimizer]\nalgorithm = \"LD_AUGLAG\"\n", 2, "optimizer.algorithm", "unknown"},
        BadJob{"report_threshold", "[output]\nreport_threshold = -1\n", 2, "output.report_threshold", "> 0"},
        BadJob{"table_is_value", "loop = 4\n", 1, "loop", "expected a table"},
        // Lengths whose squares overflow the length scale L (energies NaN, a
        // 1e200 link reported as a zero); found while building tests/tools/bad-inputs.
        BadJob{"huge_length", "[space]\na1 = 1e200\n", 2, "space.a1", "[-1e150, 1e150]"},
        BadJob{"huge_range_width", "[space]\nd = [-1e308, 1e308]\n", 2, "space.d", "overflow the length scale"},
        // Found by fuzz/job_file_fuzzer: a value's control character ("\r")
        // printed raw broke the one-line message.
        BadJob{"control_character", "[steering]\ndeflate = [\"plan\\r\"]\n", 2, "steering.deflate", "\"plan\\x0d\""},
        // Found by the fuzzers: text that sends toml++ 3.3 into undefined
        // behaviour or a failed precondition, refused before it is parsed
        // (find_toml_hazard).
        BadJob{"hazard_header_brace", "[{earc_]\nstarts = 0\n", 1, "(syntax)", "must begin with a name, not '{'"},
        BadJob{"hazard_header_brackets", "[search]\n[[[loop]]]\n", 2, "(syntax)", "must begin with a name, not '['"},
        BadJob{"hazard_header_newline", "[\nloop]\n", 1, "(syntax)", "not byte 0x0A"},
        BadJob{"hazard_non_ascii_value", "[space]\nalpha1_deg = 30\xc2\xb0\n", 2, "(syntax)",
               "U+00B0 outside a string"},
        BadJob{"hazard_escape", "[optimizer]\nalgorithm = \"\"\"\\\xc2\xa7\"\"\"\n", 2, "(syntax)",
               "U+00A7 right after a backslash"},
        BadJob{"hazard_line_ending_backslash", "[optimizer]\nalgorithm = \"\"\"\\\n\xc2\xa7\"\"\"\n", 3, "(syntax)",
               "U+00A7 right after a line-ending backslash"},
        BadJob{"hazard_array_newline", "[space]\na = [1,\n0a='\xc3\xa9']\n", 3, "(syntax)", "U+00E9 outside a string"},
        BadJob{"hazard_quote_in_value", "[search]\nseed = 0'''\xc8\x86\n", 2, "(syntax)", "U+0206 outside a string"}),
    [](const ::testing::TestParamInfo<BadJob>& info) { return std::string(info.param.name); });

// find_toml_hazard must not refuse valid TOML: non-ASCII text is fine in
// comments and in every kind of string, after a byte order mark, and a
// line-ending backslash followed by ASCII is fine too.
TEST(Job, NonAsciiInCommentsAndStringsIsAccepted) {
  const std::string text =
      "\xEF\xBB\xBF# r\xC3\xA9sum\xC3\xA9: a 30\xC2\xB0 twist\n"
      "[loop]  # \xC2\xB0 here too\n"
      "compliance = \"full\"  # \"\xC3\xA9\n"
      "[optimizer]\n"
      "algorithm = \"\"\"\\\n   gauss-newton\"\"\"\n"
      "[steering]\n"
      "deflate = [\n  # \xC2\xA7 a comment in an array\n  'planar',\n]\n"
      "[output]\n"
      "database = \"r\xC3\xA9sultats-\xC2\xA7.sqlite\"\n";
  EXPECT_FALSE(find_toml_hazard(text).has_value());
  const Job job = parse_job(text, "dir/job.toml");
  EXPECT_EQ(job.loop.compliance, Compliance::full);
  EXPECT_EQ(job.optimizer.algorithm, "gauss-newton");
  EXPECT_EQ(job.steering.deflate, std::vector<std::string>{"planar"});
  EXPECT_EQ(job.output.database, "r\xC3\xA9sultats-\xC2\xA7.sqlite");
  EXPECT_FALSE(
      find_toml_hazard("s = '''\n\xC2\xA7'''\nt = \"\"\"\xC2\xA7\\n\"\"\"\nu = \"\xC2\xA7\\\"\"\n").has_value());
}

// Found by fuzz/job_file_fuzzer: a quoted key with a newline made the message two lines.
TEST(Job, ControlCharactersInKeysStayOnOneLine) {
  try {
    parse_job("[loop]\n\"jo\\nints\" = 4\n", "bad.toml");
    FAIL() << "accepted";
  } catch (const JobError& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.find('\n'), std::string::npos) << what;
    EXPECT_NE(what.find("loop.jo\\x0aints: unknown key"), std::string::npos) << what;
  }
}

TEST(Job, LengthsUpToTheLimitAreAccepted) {
  const Job job = parse_job("[space]\na = [0, 1e150]\nd = -1e150\n", "job.toml");
  EXPECT_EQ(job.space.specs[static_cast<size_t>(job.space.index(ParameterKind::a, 0))].hi, 1e150);
}

// Found by the fuzzers: a form feed where a value begins made the hazard
// scan stop advancing (a hang). Any answer will do, as long as there is one.
TEST(Job, HazardScanEndsOnControlCharacters) {
  for (const char* text : {"a = [0,\f+\x04]\n", "a =\v1\n", "[space]\na1 = [0,\f1]\n"}) {
    (void)find_toml_hazard(text);
    EXPECT_THROW(parse_job(text, "bad.toml"), JobError) << text;
  }
}

TEST(Job, MissingFileIsAJobErrorNamingIt) {
  try {
    read_job_file("/nonexistent/dir/job.toml");
    FAIL();
  } catch (const JobError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/dir/job.toml:0:"), std::string::npos) << e.what();
  }
}

TEST(Job, ShippedJobFilesParse) {
  const std::filesystem::path dir = std::filesystem::path(LOOPFARM_SOURCE_DIR) / "jobs";
  int count = 0;
  for (const auto& entry : std::filesystem::recursive_directory_iterator(dir)) {  // jobs/discovery/ too
    if (entry.path().extension() != ".toml") continue;
    EXPECT_NO_THROW(read_job_file(entry.path().string())) << entry.path();
    ++count;
  }
  EXPECT_GE(count, 3);
}

TEST(Job, KnownAlgorithms) {
  for (const char* name : {"gauss-newton", "LD_LBFGS", "LD_SLSQP", "LD_MMA", "LN_BOBYQA", "LN_SBPLX", "LN_COBYLA"}) {
    EXPECT_TRUE(is_known_algorithm(name)) << name;
  }
  for (const char* name : {"", "lbfgs", "LD_LBFGS ", "GN_AGS"}) EXPECT_FALSE(is_known_algorithm(name)) << name;
}

}  // namespace
}  // namespace loopfarm
