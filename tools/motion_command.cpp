#include "motion_command.hpp"

#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>

#include "candidate_output.hpp"
#include "cli_support.hpp"
#include "geometry_options.hpp"
#include "loopfarm/search/start.hpp"
#include "loopfarm/search/verify.hpp"
#include "motion_output.hpp"
#include "output_format.hpp"
#include "plot.hpp"

namespace loopfarm::cli {
namespace {

constexpr double kDegreesPerRadian = 180.0 / 3.14159265358979323846;

struct MotionArguments {
  GeometryOptions geometry;
  std::string theta0_deg;
  std::string steps = "720";
  std::string csv, plot;
  CLI::Option* csv_option = nullptr;
  CLI::Option* plot_option = nullptr;
  FormatChoice format;
};

int run_motion(const MotionArguments& args) {
  // Everything the user gave is checked before any work.
  const GeometryRequest request = read_geometry(args.geometry);
  std::optional<double> theta0_deg = request.theta0_deg;
  if (!args.theta0_deg.empty()) theta0_deg = parse_number(args.theta0_deg, "--theta0-deg");
  const long long steps = parse_integer(args.steps, "--steps");
  if (steps < 64 || steps > 1000000) {
    throw UsageError("--steps", "got " + std::to_string(steps) + "; must be in [64, 1000000]");
  }
  const bool file_on_stdout = file_takes_standard_output({{"--csv", args.csv}, {"--plot", args.plot}}, args.format);
  if (given(args.csv_option) && given(args.plot_option) && !file_on_stdout) {
    std::error_code ec1, ec2;
    const auto csv_path = std::filesystem::weakly_canonical(args.csv, ec1);
    const auto plot_path = std::filesystem::weakly_canonical(args.plot, ec2);
    if (!ec1 && !ec2 && csv_path == plot_path) {
      throw UsageError("--plot", quote_text(args.plot) + " is also the --csv file; give two different files");
    }
  }
  PlotFormat plot_format_wanted = PlotFormat::png;
  if (given(args.plot_option)) plot_format_wanted = plot_format(args.plot, "--plot");
  std::filesystem::path gnuplot;
  if (given(args.plot_option)) gnuplot = require_gnuplot("--plot");
  std::optional<PendingOutput> csv;
  std::optional<PendingOutput> png;
  if (given(args.csv_option)) csv.emplace(args.csv, "--csv");
  if (given(args.plot_option)) png.emplace(args.plot, "--plot");

  const LoopGeometry& geometry = request.geometry;
  StartOptions start;
  VerificationOptions& options = start.verification;
  options.steps_per_turn = static_cast<int>(steps);
  if (theta0_deg) options.theta0 = *theta0_deg / kDegreesPerRadian;
  const JointVector* pose = request.theta ? &*request.theta : nullptr;
  VerificationSummary v = verify_motion(geometry, pose, options);
  // Verified as `loopfarm verify` verifies: the geometry as given, at
  // round-off (the note says how far a polish moved it).
  check_round_off(geometry, v, start);
  const int status = v.verified ? kExitSuccess : kExitNotVerified;

  // Files first, each written whole before it replaces its target.
  if (csv) {
    write_circuits_csv(v.motion, csv->stream());
    csv->close();
  }
  if (png && !v.motion.circuits.empty()) {
    png->close();
    plot_motion(gnuplot, v.motion,
                "motion of the " + std::to_string(geometry.joints()) + "R loop a = " + lengths_text(geometry.a) +
                    ", alpha_deg = " + degrees_text(geometry.alpha) + ", d = " + lengths_text(geometry.d),
                plot_format_wanted, png->temporary());
  }
  if (csv) csv->commit();
  if (png && !v.motion.circuits.empty()) png->commit();
  if (png && v.motion.circuits.empty()) {
    std::fprintf(stderr, "loopfarm motion: the loop has no circuit; %s not written\n", args.plot.c_str());
  }

  if (file_on_stdout) return status;
  if (args.format.format != OutputFormat::text) {
    nlohmann::ordered_json record;
    record["geometry"] = geometry_json(geometry);
    record["verified"] = v.verified;
    record["circuit"] = v.circuit >= 0 ? nlohmann::ordered_json(v.circuit + 1) : nlohmann::ordered_json(nullptr);
    record["isolated_poses"] = v.motion.isolated_poses.size();
    record["least_residual"] = v.motion.least_residual;
    record["note"] = v.limit;
    record["circuits"] = circuits_json(v.motion, v.motion.input_joint);
    write_record(stdout, record, args.format.format);
    return status;
  }
  std::printf("loop (%dR)\n", geometry.joints());
  std::printf("  a                     %s\n", lengths_text(geometry.a).c_str());
  std::printf("  alpha_deg             %s\n", degrees_text(geometry.alpha).c_str());
  std::printf("  d                     %s\n", lengths_text(geometry.d).c_str());
  std::printf("verified                %s\n", v.verified ? "yes" : "no");
  if (!v.limit.empty()) std::printf("  note                  %s\n", v.limit.c_str());
  if (v.circuit < 0 && v.motion.isolated_poses.empty()) {
    std::printf("  least residual        %.6g (no closed pose found)\n", v.motion.least_residual);
  }
  print_circuits(v.motion, v.motion.input_joint, v.circuit);
  return status;
}

}  // namespace

Subcommand add_motion_command(CLI::App& parent) {
  auto args = std::make_shared<MotionArguments>();
  CLI::App* app = parent.add_subcommand(
      "motion",
      "Trace every circuit of a geometry's rigid motion over the whole turn: each joint's range (crank or "
      "rocker), dead points, bifurcation points, freedoms; the input-output curves as CSV and a plot.");
  app->footer(
      "Examples:\n"
      "  loopfarm motion --a 3,1,2.5,2 --alpha-deg 0,0,0,0 --csv curves.csv --plot curves.png\n"
      "  loopfarm motion --geometry loop.toml --json\n"
      "  loopfarm motion --a 2,4,2,4 --alpha-deg 30,90,30,90 --csv - | head\n"
      "Exit codes: 0 verified (a circuit moves), 4 analysed but not verified, 1 failure (e.g. gnuplot missing),\n"
      "2 bad input.\n");
  add_geometry_options(*app, args->geometry);
  CLI::Option* theta0 = app->add_option("--theta0-deg", args->theta0_deg,
                                        "input angle theta0 [deg]: report the circuit whose input reaches it")
                            ->type_name("DEG");
  args->geometry.theta_option->excludes(theta0);
  app->add_option("--steps", args->steps, "tracing: the largest step along a circuit is 360/S deg (>= 64)")
      ->type_name("S")
      ->capture_default_str();
  args->csv_option = app->add_option("--csv", args->csv,
                                     "write every circuit's points (every joint angle against the input and "
                                     "arclength), one row a point; '-' for standard output")
                         ->type_name("FILE");
  args->plot_option = app->add_option("--plot", args->plot,
                                      "draw the joint angles against input and arclength (needs gnuplot); FILE's "
                                      "extension picks the format: .png, .svg or .pdf ('-': PNG on stdout)")
                          ->type_name("FILE");
  add_format_option(*app, args->format,
                    {OutputFormat::text, OutputFormat::json, OutputFormat::csv, OutputFormat::markdown},
                    "print the verdict and circuits as");
  return {app, [args] { return run_motion(*args); }};
}

}  // namespace loopfarm::cli
