#include "verify_command.hpp"

#include <cstdio>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "candidate_output.hpp"
#include "cli_support.hpp"
#include "geometry_options.hpp"
#include "loopfarm/core/assembly.hpp"
#include "loopfarm/core/cycle.hpp"
#include "loopfarm/search/start.hpp"
#include "output_format.hpp"

namespace loopfarm::cli {
namespace {

constexpr double kDegreesPerRadian = 180.0 / 3.14159265358979323846;

struct VerifyArguments {
  GeometryOptions geometry;
  std::string theta0_deg;
  std::string samples = "32";
  std::string steps = "720";
  FormatChoice format;
};

std::string readable(double value) {
  char buffer[40];
  std::snprintf(buffer, sizeof buffer, "%.6g", value);
  return buffer;
}

// The polish of a geometry whose circuit closes within the tolerance only
// (check_round_off): the same keys whether or not one was run, null if not.
void add_polish_json(nlohmann::ordered_json& record, const RoundOffCheck& r) {
  const bool converged = r.polished && r.candidate.polish.converged;
  const VerificationSummary& v = r.candidate.verification;
  nlohmann::ordered_json polish = polish_json(r.candidate.polish, r.polished);
  polish["verified"] = converged ? nlohmann::ordered_json(v.verified) : nlohmann::ordered_json();
  polish["rigid_residual"] = converged ? nlohmann::ordered_json(v.worst_residual) : nlohmann::ordered_json();
  // A family is named only for a polished geometry that moves.
  polish["family"] = converged && v.verified ? nlohmann::ordered_json(to_string(r.candidate.classification.family))
                                             : nlohmann::ordered_json();
  record["polish"] = polish;
  nlohmann::ordered_json polished = geometry_json(r.candidate.geometry);
  for (auto& value : polished) {
    if (!converged) value = nullptr;
  }
  record["polished_geometry"] = polished;
}

void print_polish(const RoundOffCheck& r) {
  const GeometryPolishSummary& p = r.candidate.polish;
  std::printf("polish onto the motion  %s: closure %s -> %s at %d poses in %d iterations, moved %s of L\n",
              p.converged ? "converged" : "failed", readable(p.initial_residual).c_str(),
              readable(p.final_residual).c_str(), p.poses_used, p.iterations, readable(p.displacement).c_str());
  if (!p.converged) {
    std::printf("  note                  %s\n", p.message.c_str());
    return;
  }
  const LoopGeometry& g = r.candidate.geometry;
  const VerificationSummary& v = r.candidate.verification;
  std::printf("polished geometry\n");
  std::printf("  a                     %s\n", lengths_text(g.a).c_str());
  std::printf("  alpha_deg             %s\n", degrees_text(g.alpha).c_str());
  std::printf("  d                     %s\n", lengths_text(g.d).c_str());
  std::printf("  verified              %s (worst residual %s over %d poses)\n", v.verified ? "yes" : "no",
              readable(v.worst_residual).c_str(), v.poses);
  if (v.verified) {
    const Classification& k = r.candidate.classification;
    std::printf("  family                %s", to_string(k.family));
    if (k.family == Family::bennett) std::printf(" (%s setup)", to_string(k.setup));
    std::printf("\n");
  } else if (!v.limit.empty()) {
    std::printf("  note                  %s\n", v.limit.c_str());
  }
}

int run_verify(const VerifyArguments& args) {
  const GeometryRequest request = read_geometry(args.geometry);
  std::optional<double> theta0_deg = request.theta0_deg;
  if (!args.theta0_deg.empty()) theta0_deg = parse_number(args.theta0_deg, "--theta0-deg");
  const long long samples = parse_integer(args.samples, "--samples");
  if (samples < 4 || samples > 4096) {
    throw UsageError("--samples", "got " + std::to_string(samples) + "; must be in [4, 4096]");
  }
  const long long steps = parse_integer(args.steps, "--steps");
  if (steps < 64 || steps > 1000000) {
    throw UsageError("--steps", "got " + std::to_string(steps) + "; must be in [64, 1000000]");
  }
  const LoopGeometry& geometry = request.geometry;
  const int n = geometry.joints();

  // The rigid loop's motion first: every circuit, from the given pose (if
  // any) and from assemblies over the whole turn.
  StartOptions options;
  options.verification.steps_per_turn = static_cast<int>(steps);
  if (theta0_deg) options.verification.theta0 = *theta0_deg / kDegreesPerRadian;
  const JointVector* pose = request.theta ? &*request.theta : nullptr;
  VerificationSummary verification = verify_motion(geometry, pose, options.verification);
  // A circuit closing within the tracer's tolerance only is no motion of
  // the geometry as given: it is polished onto the motion it approximates,
  // and verified as given only when that moves it by round-off.
  const RoundOffCheck round_off = check_round_off(geometry, verification, options);

  // The cycle energy, only where it means something: driven along the
  // verified motion, from a pose on it (motion_window says where and over
  // what input range).
  const std::optional<MotionWindow> window = motion_window(geometry, verification, options.verification.theta0,
                                                           options.verification, static_cast<int>(samples));
  const LoopModel model(geometry);
  EquilibriumWorkspace workspace(model);
  CycleSummary cycle;
  EquilibriumSummary assembly;
  Eigen::MatrixXd jacobian;
  // No cycle where the input joint does not move on the circuit (range 0).
  const bool cycled = window && window->range > 0.0;
  if (cycled) {
    assembly = assemble_from_angles(model, workspace, window->pose);
    CycleOptions cycle_options;
    cycle_options.samples = static_cast<int>(samples);
    cycle_options.range = window->range;
    cycle_energy(model, workspace, window->theta0, assembly.state, cycle_options, cycle);
    // Every geometric parameter free: the local dimension of the zero set in
    // the full (a, alpha, d) space.
    std::vector<bool> is_length(static_cast<size_t>(3 * n), true);
    for (int i = n; i < 2 * n; ++i) is_length[static_cast<size_t>(i)] = false;  // the twists
    jacobian =
        dimensionless_columns(cycle_deformation_jacobian(model, workspace, cycle), is_length, model.length_scale());
  }
  const JointVector classified_pose =
      window ? window->pose : (request.theta ? *request.theta : JointVector(JointVector::Zero(n)));
  const CandidateAnalysis candidate =
      analyse_candidate(geometry, classified_pose, std::move(verification), jacobian, options);
  const VerificationSummary& v = candidate.verification;
  const int status = v.verified ? kExitSuccess : kExitNotVerified;

  if (args.format.format != OutputFormat::text) {
    nlohmann::ordered_json record;
    record["geometry"] = geometry_json(geometry);
    for (const char* field :
         {"theta0_deg", "cycle_range_deg", "status", "E_mean", "E_max", "failed_samples", "theta_deg"}) {
      record[field] = nullptr;
    }
    if (cycled) {
      record["theta0_deg"] = window->theta0 * kDegreesPerRadian;
      record["cycle_range_deg"] = window->range * kDegreesPerRadian;
      record["status"] = to_string(assembly.status);
      record["E_mean"] = cycle.E_mean;
      record["E_max"] = cycle.E_max;
      record["failed_samples"] = cycle.failed_samples;
      record["theta_deg"] = degrees_json(window->pose);
    }
    add_candidate_json(record, candidate, true);
    add_polish_json(record, round_off);
    write_record(stdout, record, args.format.format);
    return status;
  }
  std::printf("loop (%dR)\n", n);
  std::printf("  a                     %s\n", lengths_text(geometry.a).c_str());
  std::printf("  alpha_deg             %s\n", degrees_text(geometry.alpha).c_str());
  std::printf("  d                     %s\n", lengths_text(geometry.d).c_str());
  print_candidate(candidate);
  if (round_off.polished) print_polish(round_off);
  if (cycled) {
    std::printf("cycle energy along the motion (%d samples, %s from theta0 = %s deg)\n", static_cast<int>(samples),
                window->range >= 2.0 * 3.14159265358979323846
                    ? "full turn"
                    : ("window of " + readable(window->range * kDegreesPerRadian) + " deg").c_str(),
                readable(window->theta0 * kDegreesPerRadian).c_str());
    std::printf("  theta_deg             %s\n", degrees_text(window->pose).c_str());
    std::printf("  E_mean                %s   [E / (k_a L^2)]\n", readable(cycle.E_mean).c_str());
    std::printf("  E_max                 %s\n", readable(cycle.E_max).c_str());
    print_local_dimension(candidate.local_dimension);
  }
  return status;
}

}  // namespace

Subcommand add_verify_command(CLI::App& parent) {
  auto args = std::make_shared<VerifyArguments>();
  CLI::App* app = parent.add_subcommand(
      "verify",
      "Verify a geometry: find every circuit of its rigid motion over the whole turn, classify it (Bennett, "
      "planar, spherical, trivial, the 5R and 6R families), give its canonical key and, for a verified loop, "
      "its cycle energy along the motion and the local dimension of its zero set.");
  app->footer(
      "Examples:\n"
      "  loopfarm verify --a 2,4,2,4 --alpha-deg 30,90,30,90 --theta-deg 120,90,-120,-90\n"
      "  loopfarm verify --geometry loop.toml --json\n"
      "Exit codes: 0 verified (a circuit of the rigid loop moves), 4 analysed but not verified, 1 failure,\n"
      "2 bad input.\n");
  add_geometry_options(*app, args->geometry);
  CLI::Option* theta0 =
      app->add_option("--theta0-deg", args->theta0_deg,
                      "input angle theta0 [deg]: report the circuit whose input reaches it and start the cycle there "
                      "(default: from --theta-deg, else 0 for a full turn, moved off the circuit's singular poses, "
                      "and the middle of a rocker's range)")
          ->type_name("DEG");
  args->geometry.theta_option->excludes(theta0);
  app->add_option("--samples", args->samples, "cycle samples for E_mean and the local dimension")
      ->type_name("N")
      ->capture_default_str();
  app->add_option("--steps", args->steps, "tracing: the largest step along a circuit is 360/S deg (>= 64)")
      ->type_name("S")
      ->capture_default_str();
  add_format_option(*app, args->format,
                    {OutputFormat::text, OutputFormat::json, OutputFormat::csv, OutputFormat::markdown},
                    "print the verdict as");
  return {app, [args] { return run_verify(*args); }};
}

}  // namespace loopfarm::cli
