// A job file: the single description of a search (TOML, documented key by
// key in docs/guide/job-file.md, examples in jobs/).
//
//   [loop]       joints, compliance, stiffness_ratio, samples, range_deg
//   [space]      every DH parameter and initial joint angle: fixed, a range,
//                or tied to another; defaults for what is not named
//   [optimizer]  algorithm ("gauss-newton" or an NLopt name), tolerances,
//                evaluation and time limits per start
//   [search]     starts, seed, zero_threshold
//   [steering]   non-triviality requirement, deflation of known families
//   [output]     database path
//
// Parsing validates everything: an unknown key, a wrong type, lo > hi, NaN,
// n outside [4, 8], starts <= 0, a tie to an unknown or tied parameter... each
// throws a JobError whose message is one line naming the file, line and key.
#pragma once

#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include "loopfarm/core/equilibrium.hpp"
#include "loopfarm/core/loop.hpp"

namespace loopfarm {

// One line: "FILE:LINE: KEY: what is wrong" (LINE 0 when the problem has no
// line, e.g. a missing file). The CLI prints it and exits with code 2.
class JobError : public std::runtime_error {
 public:
  JobError(std::string file, int line, std::string key, const std::string& message);
  const std::string& file() const { return file_; }
  int line() const { return line_; }
  const std::string& key() const { return key_; }

 private:
  std::string file_;
  int line_;
  std::string key_;
};

// The parameters of a search space, in this order, each n long: link lengths
// a, twists alpha, offsets d (the geometry, GeometryVector order) and the
// initial joint angles theta at the start of the cycle (theta_1 is theta0).
enum class ParameterKind { a = 0, alpha = 1, d = 2, theta = 3 };
inline constexpr int kParameterKinds = 4;

struct ParameterSpec {
  enum class Mode { fixed, range, tied };
  Mode mode = Mode::fixed;
  double value = 0.0;         // fixed: the value [length or rad]
  double lo = 0.0, hi = 0.0;  // range: closed interval, lo <= hi
  int source = -1;            // tied: value = sign * value of parameter `source`
  double sign = 1.0;          //       (an index into ParameterSpace::specs)
  int line = 0;               // job-file line it was given on; 0 for a default
};

// Every parameter of the loop's geometry and initial pose as fixed, a range or
// tied. The geometry's ranges (a, alpha, d) are the free variables x of the
// local minimisation, in spec order; ranges of theta are drawn at random per
// start but not optimised. A tie's source is never itself tied, and has the
// same unit (lengths a, d tie to lengths; twists to twists; angles to angles).
struct ParameterSpace {
  int joints = 4;
  std::vector<ParameterSpec> specs;  // kParameterKinds * joints, index(kind, joint)

  int index(ParameterKind kind, int joint) const { return static_cast<int>(kind) * joints + joint; }
  // The name used in job files and messages: "a1", "alpha3_deg", "d2", "theta1_deg" (1-based).
  std::string name(int index) const;

  // Free geometric parameters (ranges of a, alpha, d), in spec order.
  int free_count() const;
  std::vector<int> free_indices() const;
  Eigen::VectorXd lower_bounds() const;  // of the free parameters
  Eigen::VectorXd upper_bounds() const;

  // The geometry at free values x: fixed, free and tied parameters filled in.
  LoopGeometry geometry(const Eigen::VectorXd& x) const;
  // d(a, alpha, d) / dx: 3n x free_count, constant (entries 0, 1 or a tie's sign).
  Eigen::MatrixXd geometry_jacobian() const;
  // The free values of a geometry (the inverse of geometry() on the free parameters).
  Eigen::VectorXd free_values(const LoopGeometry& geometry) const;

  // Initial joint angles from the values drawn for the theta ranges (one per
  // theta parameter in range mode, in joint order): fixed and tied filled in.
  JointVector initial_angles(const Eigen::VectorXd& theta_draws) const;
  int random_angle_count() const;  // theta parameters in range mode
};

// Names: a struct holding one table of the job file is a `*Section`
// (LoopSection is [loop], and so on), a member of Job named after its table;
// what an algorithm takes is its `*Options` (EquilibriumOptions, CycleOptions,
// ObjectiveOptions, LocalSearchOptions), which the search builds from the
// sections (ObjectiveOptions::from_loop, objective_options in start.hpp).
struct LoopSection {
  int joints = 4;
  Compliance compliance = Compliance::paper;
  double stiffness_ratio = 1.0;                 // k_t / (k_a L^2)
  int samples = 32;                             // N
  double range = 2.0 * 3.14159265358979323846;  // [rad]; 2 pi is a full turn
  // The equilibrium solve's tolerances (EquilibriumOptions): closure residual
  // (rotation [rad], translation / L) and stationarity, max-norms.
  double closure_tolerance = EquilibriumOptions{}.closure_tolerance;
  double stationarity_tolerance = EquilibriumOptions{}.stationarity_tolerance;
  // What the search minimises of the cycle's energies: "mean" (E_mean, smooth:
  // the default) or "max" (E_max, the paper's peak energy; non-smooth where
  // the worst sample changes).
  std::string objective = "mean";
};

struct OptimizerSection {
  std::string algorithm = "gauss-newton";  // or an NLopt name: "LD_LBFGS", "LN_BOBYQA", ...
  double xtol_rel = 1e-10;
  double ftol_rel = 0.0;  // 0: not used
  double ftol_abs = 0.0;  // 0: not used
  // Stop once the objective is below this: 1e-26 is deformations of about
  // 1e-13, near round-off (a zero polished further gains nothing).
  double stopval = 1e-26;
  int max_evaluations = 500;  // cycle evaluations per start
  // Stop a start once its best objective has fallen by less than a factor of
  // progress_factor over its last progress_window evaluations (0: not used):
  // a start creeping towards a minimum it would not reach in its budget.
  int progress_window = 0;
  double progress_factor = 10.0;
  // Stop a start whose best objective after checkpoint_evaluations
  // evaluations is still above checkpoint_objective (0: not used): a start
  // that far from a zero by then seldom reaches one in its budget.
  int checkpoint_evaluations = 0;
  double checkpoint_objective = 0.0;
  double time_limit = 30.0;  // seconds per start; 0: none
  // Start each evaluation's cycle from the last one's samples instead of
  // walking it from the assembly (ObjectiveOptions::reuse_nearby_cycle).
  bool reuse_nearby_cycle = true;
};

struct SearchSection {
  long starts = 100;
  std::uint64_t seed = 1;
  double zero_threshold = 1e-12;  // E_mean below this is a zero
};

// Steering away from the known families (docs/design.md, "Steering away from
// the known families"). Families are named "planar", "spherical", "trivial"
// (any n), "bennett" (n = 4), "goldberg", "myard", "goldberg_bent" (n = 5),
// "bricard_line_symmetric", "bricard_plane_symmetric", "bricard_trihedral",
// "bennett_pair", "bennett_dyads", "bennett_triads", "coupled_bennett_dyads", "sarrus", "bricard_octahedral_plane",
// "waldron_hybrid", "goldberg_6r", "double_goldberg", "hooke", "bricard_octahedral_collapsible",
// "angle_symmetric_parallel" (n = 6): those family_distance measures.
struct SteeringSection {
  bool nontrivial = false;                    // every joint must move over the cycle
  double min_travel = 0.0872664625997164788;  // [rad] (5 deg): what "moves" means
  std::vector<std::string> deflate;           // families whose neighbourhood is penalised
  double deflation_power = 2.0;               // objective * prod (1 / dist^p + shift)
  double deflation_shift = 1.0;
};

struct OutputSection {
  std::string database = "loopfarm.sqlite";  // relative paths are relative to the job file
  // Starts whose final E_mean is at most this keep their final geometry in
  // the database (every start keeps its energies, for the histogram of minima).
  double report_threshold = 1e-6;
};

struct Job {
  std::string path;  // the file it was read from
  std::string text;  // its text as read (the farm stores and hashes it)
  LoopSection loop;
  ParameterSpace space;
  OptimizerSection optimizer;
  SearchSection search;
  SteeringSection steering;
  OutputSection output;
};

// Reads and validates a job file; throws JobError.
Job read_job_file(const std::string& path);
// The same from text; `source_name` stands for the file in messages.
Job parse_job(std::string_view text, const std::string& source_name);

// Where TOML text would drive the toml++ 3.3 parser (Debian 12's) into
// undefined behaviour instead of a parse error; both found by fuzz/ and both
// reported upstream (marzer/tomlplusplus issues 190 and 295, pull 301):
//   - a non-ASCII character where the parser tests for whitespace, i.e.
//     outside strings and comments, or first on the line after a line-ending
//     backslash in a multi-line basic string (is_non_ascii_horizontal_whitespace
//     reaches TOML_UNREACHABLE for U+00A1..U+0499 and U+2C0E..U+3007);
//   - a table header whose name starts with neither a bare-key character nor a
//     quote ("[{a]", "[[[a]]]": parse_key's precondition).
// Valid TOML 1.0 has neither (non-ASCII text is allowed only in strings and
// comments), so rejecting them costs nothing. parse_job and the geometry
// reader call this before toml::parse.
struct TomlHazard {
  int line = 0;    // 1-based
  int column = 0;  // 1-based, in bytes
  std::string message;
};
std::optional<TomlHazard> find_toml_hazard(std::string_view text);

// Whether `name` is an algorithm the job may ask for: "gauss-newton" or an
// NLopt algorithm name this NLopt build provides (LD_LBFGS, LN_BOBYQA, ...).
bool is_known_algorithm(const std::string& name);

}  // namespace loopfarm
