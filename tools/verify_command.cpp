#include "verify_command.hpp"

#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "candidate_output.hpp"
#include "cli_support.hpp"
#include "geometry_options.hpp"
#include "loopfarm/assembly.hpp"
#include "loopfarm/cycle.hpp"
#include "loopfarm/start.hpp"

namespace loopfarm::cli {
namespace {

constexpr double kDegreesPerRadian = 180.0 / 3.14159265358979323846;

struct VerifyArguments {
  GeometryOptions geometry;
  std::string theta0_deg = "0";
  std::string samples = "32";
  std::string steps = "720";
  bool json = false;
};

std::string readable(double value) {
  char buffer[40];
  std::snprintf(buffer, sizeof buffer, "%.6g", value);
  return buffer;
}

int run_verify(const VerifyArguments& args) {
  const GeometryRequest request = read_geometry(args.geometry);
  const double theta0_deg = request.theta0_deg ? *request.theta0_deg : parse_number(args.theta0_deg, "--theta0-deg");
  const long long samples = parse_integer(args.samples, "--samples");
  if (samples < 4 || samples > 4096) {
    throw UsageError("--samples", "got " + std::to_string(samples) + "; must be in [4, 4096]");
  }
  const long long steps = parse_integer(args.steps, "--steps");
  if (steps < 360 || steps > 1000000) {
    throw UsageError("--steps", "got " + std::to_string(steps) + "; must be in [360, 1000000]");
  }

  // The pose to verify from: the elastic assembly at theta0 (from --theta-deg
  // when given), which for a movable loop is a closed pose.
  const LoopModel model(request.geometry);
  EquilibriumWorkspace workspace(model);
  const double theta0 = theta0_deg / kDegreesPerRadian;
  const EquilibriumSummary assembly =
      request.theta ? assemble_from_angles(model, workspace, *request.theta) : assemble(model, workspace, theta0);
  const bool assembled = assembly.status == SolveStatus::converged;
  CycleOptions cycle_options;
  cycle_options.samples = static_cast<int>(samples);
  CycleSummary cycle;
  cycle_energy(model, workspace, assembly.state.theta[0], assembly.state, cycle_options, cycle);
  // Every geometric parameter free: the local dimension of the zero set in
  // the full (a, alpha, d) space.
  const int n = request.geometry.joints();
  std::vector<bool> is_length(static_cast<size_t>(3 * n), true);
  for (int i = n; i < 2 * n; ++i) is_length[static_cast<size_t>(i)] = false;  // the twists
  const Eigen::MatrixXd jacobian =
      dimensionless_columns(cycle_deformation_jacobian(model, workspace, cycle), is_length, model.length_scale());

  StartOptions options;
  options.verification.steps_per_turn = static_cast<int>(steps);
  const CandidateAnalysis candidate = analyse_candidate(request.geometry, assembly.state.theta, jacobian, options);

  if (args.json) {
    std::string json = "{";
    json += "\"status\":" + json_string(assembled ? to_string(assembly.status) : "assembly_failed");
    json += ",\"E_mean\":" + json_number(cycle.E_mean);
    json += ",\"E_max\":" + json_number(cycle.E_max);
    json += ",\"failed_samples\":" + std::to_string(cycle.failed_samples);
    json += ",\"geometry\":" + geometry_json(request.geometry);
    json += ",\"theta_deg\":[";
    for (int i = 0; i < assembly.state.theta.size(); ++i) {
      if (i) json += ',';
      json += json_number(assembly.state.theta[i] * kDegreesPerRadian);
    }
    json += "]";
    json += candidate_json_fields(candidate, true);
    json += "}\n";
    std::fputs(json.c_str(), stdout);
    return kExitSuccess;
  }
  std::printf("loop (%dR)\n", request.geometry.joints());
  std::printf("  a                     %s\n", lengths_text(request.geometry.a).c_str());
  std::printf("  alpha_deg             %s\n", degrees_text(request.geometry.alpha).c_str());
  std::printf("  d                     %s\n", lengths_text(request.geometry.d).c_str());
  std::printf("assembly at theta0      %s (%s)\n", to_string(assembly.status),
              request.theta ? "from --theta-deg" : "least-energy of the deterministic guesses");
  std::printf("  theta_deg             %s\n", degrees_text(assembly.state.theta).c_str());
  std::printf("cycle energy (%d samples)\n", static_cast<int>(samples));
  std::printf("  E_mean                %s   [E / (k_a L^2)]\n", readable(cycle.E_mean).c_str());
  std::printf("  E_max                 %s\n", readable(cycle.E_max).c_str());
  print_candidate(candidate);
  return kExitSuccess;
}

}  // namespace

Subcommand add_verify_command(CLI::App& parent) {
  auto args = std::make_shared<VerifyArguments>();
  CLI::App* app = parent.add_subcommand(
      "verify", "Verify a geometry with the rigid closure along its motion, classify it (Bennett, planar, "
                "spherical, trivial) and give its canonical key and the local dimension of its zero set.");
  app->footer(
      "Examples:\n"
      "  loopfarm verify --a 2,4,2,4 --alpha-deg 30,90,30,90 --theta-deg 120,90,-120,-90\n"
      "  loopfarm verify --geometry loop.toml --json\n"
      "Exit codes: 0 done (whatever the verdict), 1 failure, 2 bad input.\n");
  add_geometry_options(*app, args->geometry);
  CLI::Option* theta0 = app->add_option("--theta0-deg", args->theta0_deg, "input angle theta0 to assemble at [deg]")
                            ->type_name("DEG")
                            ->capture_default_str();
  args->geometry.theta_option->excludes(theta0);
  app->add_option("--samples", args->samples, "cycle samples for E_mean and the local dimension")
      ->type_name("N")
      ->capture_default_str();
  app->add_option("--steps", args->steps, "verification steps per full turn (>= 360)")
      ->type_name("S")
      ->capture_default_str();
  app->add_flag("--json", args->json, "print one JSON object instead of the summary");
  return {app, [args] { return run_verify(*args); }};
}

}  // namespace loopfarm::cli
