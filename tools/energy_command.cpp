#include "energy_command.hpp"

#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "cli_support.hpp"
#include "geometry_input.hpp"
#include "geometry_options.hpp"
#include "loopfarm/core/cycle.hpp"
#include "loopfarm/core/cycle_start.hpp"
#include "loopfarm/core/equilibrium.hpp"
#include "loopfarm/core/loop.hpp"
#include "loopfarm/search/job.hpp"
#include "output_format.hpp"
#include "plot.hpp"

namespace loopfarm::cli {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDegreesPerRadian = 180.0 / kPi;
// A cycle keeps every sample's state in memory; beyond this a curve has no
// more to show and a typo (an extra zero or three) would only eat memory.
constexpr long long kMaxSamples = 100000;

// The option texts exactly as given; everything is parsed and checked by
// read_request so that every message has the same form.
struct EnergyArguments {
  GeometryOptions geometry;
  std::string theta0_deg = "0";
  std::string samples = "32";
  std::string compliance = "paper";
  std::string torsion_ratio = "1";
  std::string range_deg = "auto";
  std::string csv, plot;
  FormatChoice format;
  bool log = false;

  CLI::Option* csv_option = nullptr;
  CLI::Option* plot_option = nullptr;
};

// The checked request.
struct EnergyRequest {
  GeometryInput input;
  LoopGeometry geometry;
  std::optional<JointVector> theta;  // initial joint angles [rad], if given
  double theta0_deg = 0.0;
  int samples = 32;
  Compliance compliance = Compliance::paper;
  double torsion_ratio = 1.0;
  std::optional<double> range_deg;  // [deg]; empty: auto (choose_cycle_start)
  bool log = false;
};

EnergyRequest read_request(const EnergyArguments& args) {
  EnergyRequest request;
  GeometryRequest geometry = read_geometry(args.geometry);
  request.input = std::move(geometry.input);
  request.geometry = geometry.geometry;
  request.theta = geometry.theta;
  request.theta0_deg = geometry.theta0_deg ? *geometry.theta0_deg : parse_number(args.theta0_deg, "--theta0-deg");

  const long long samples = parse_integer(args.samples, "--samples");
  if (samples < 2 || samples > kMaxSamples) {
    throw UsageError("--samples",
                     "got " + std::to_string(samples) + "; must be in [2, " + std::to_string(kMaxSamples) + "]");
  }
  request.samples = static_cast<int>(samples);

  request.compliance = compliance_from_string(args.compliance);

  request.torsion_ratio = parse_number(args.torsion_ratio, "--torsion-ratio");
  if (!(request.torsion_ratio > 0.0)) {
    throw UsageError("--torsion-ratio", "got " + format_double(request.torsion_ratio) + "; must be > 0");
  }

  if (args.range_deg != "auto") {
    const double range = parse_number(args.range_deg, "--range-deg");
    if (!(range > 0.0 && range <= 360.0)) {
      throw UsageError("--range-deg", "got " + format_double(range) + "; must be in (0, 360] or auto");
    }
    request.range_deg = range;
  }

  request.log = args.log;
  return request;
}

// An angle in degrees wrapped to (-180, 180], as people read joint angles.
double wrap_degrees(double degrees) {
  double wrapped = std::fmod(degrees, 360.0);
  if (wrapped <= -180.0) wrapped += 360.0;
  if (wrapped > 180.0) wrapped -= 360.0;
  return wrapped;
}

// Degrees for display. Input angles are measured from theta0 in the user's own
// degrees, so that theta0 = 120 prints as 120 and not as the 119.99999999999999
// a round trip through radians gives; other angles are converted directly.
struct DegreeDisplay {
  double theta0_deg = 0.0;
  double theta0 = 0.0;  // [rad]
  int input_joint = 0;

  double input_deg(double theta_in) const { return theta0_deg + (theta_in - theta0) * kDegreesPerRadian; }
  // Joint i's angle in (-180, 180]; `theta_in` is the sample's input angle.
  double joint_deg(const JointVector& theta, int i) const {
    return i == input_joint ? wrap_degrees(input_deg(theta[i])) : wrap_degrees(theta[i] * kDegreesPerRadian);
  }
};

bool is_twist(const LoopModel& model, int k) {
  return model.deformation_element(k) % kElementsPerJoint == static_cast<int>(ChainParameter::alpha);
}

void write_csv(std::FILE* out, const LoopModel& model, const DegreeDisplay& degrees, const CycleSummary& cycle) {
  const int n = model.joints();
  std::fputs("theta_in_deg,energy,status,iterations,closure_residual", out);
  for (int i = 0; i < n; ++i) std::fprintf(out, ",theta%d_deg", i + 1);
  for (int k = 0; k < model.deformation_count(); ++k) {
    const std::string name = deformation_name(model, k);
    std::fprintf(out, ",d%s%s", name.c_str(), is_twist(model, k) ? "_deg" : "");
  }
  std::fputc('\n', out);
  for (const CycleSample& sample : cycle.samples) {
    std::fprintf(out, "%s,%s,%s,%d,%s", format_double(degrees.input_deg(sample.theta_in)).c_str(),
                 format_double(sample.energy).c_str(), to_string(sample.status), sample.iterations,
                 format_double(sample.closure_residual).c_str());
    for (int i = 0; i < n; ++i)
      std::fprintf(out, ",%s", format_double(degrees.joint_deg(sample.state.theta, i)).c_str());
    for (int k = 0; k < model.deformation_count(); ++k) {
      const double value = physical_deformation(model, sample.state.deformations, k);
      std::fprintf(out, ",%s", format_double(is_twist(model, k) ? value * kDegreesPerRadian : value).c_str());
    }
    std::fputc('\n', out);
  }
}

// The input's range on the motion [deg], as the 2 pi image that holds theta0.
std::array<double, 2> input_range_deg(const CycleStart& start, int input_joint, double theta0) {
  const JointRange& r = start.motion->circuit.input_range(input_joint);
  const double middle = 0.5 * (r.lo + r.hi);
  const double shift = middle + std::remainder(theta0 - middle, 2.0 * kPi) - theta0;
  return {(r.lo - shift) * kDegreesPerRadian, (r.hi - shift) * kDegreesPerRadian};
}

struct EnergyResult {
  CycleStart start;
  CycleSummary cycle;
  double seconds = 0.0;
  DegreeDisplay degrees;
};

nlohmann::ordered_json summary_record(const EnergyRequest& request, const LoopModel& model,
                                      const EnergyResult& result) {
  const CycleSummary& c = result.cycle;
  nlohmann::ordered_json record;
  record["E_mean"] = c.E_mean;
  record["E_max"] = c.E_max;
  record["samples"] = c.samples.size();
  record["failed_samples"] = c.failed_samples;
  record["branch_jumps"] = c.branch_jumps;
  record["refinements"] = c.refinements;
  record["iterations"] = c.total_iterations;
  record["max_closure_residual"] = c.max_closure_residual;
  record["theta0_deg"] = request.theta0_deg;
  nlohmann::ordered_json theta = nlohmann::ordered_json::array();
  for (int i = 0; i < model.joints(); ++i)
    theta.push_back(result.degrees.joint_deg(result.start.assembly.state.theta, i));
  record["theta_deg"] = theta;
  const CycleStart& start = result.start;
  const int input = model.options().input_joint;
  record["range_deg"] = request.range_deg.value_or(start.range * kDegreesPerRadian);
  record["on_motion"] = start.motion.has_value();
  record["full_turn"] = nullptr;
  record["input_range_deg"] = nullptr;
  if (start.motion) {
    const bool full_turn = start.motion->circuit.input_range(input).crank();
    record["full_turn"] = full_turn;
    if (!full_turn) {
      const std::array<double, 2> r = input_range_deg(start, input, result.degrees.theta0);
      record["input_range_deg"] = {r[0], r[1]};
    }
  }
  record["length_scale"] = model.length_scale();
  record["compliance"] = to_string(request.compliance);
  record["seconds"] = result.seconds;
  return record;
}

std::string readable(double value) {
  char buffer[40];
  std::snprintf(buffer, sizeof buffer, "%.6g", value);
  return buffer;
}

std::string joint_angles_deg(const LoopModel& model, const DegreeDisplay& display, const JointVector& theta) {
  std::vector<double> degrees;
  for (int i = 0; i < model.joints(); ++i) degrees.push_back(display.joint_deg(theta, i));
  return format_list(degrees);
}

void print_summary(const EnergyRequest& request, const LoopModel& model, const EnergyResult& result) {
  const CycleSummary& c = result.cycle;
  const EquilibriumSummary& a = result.start.assembly;
  const CycleStart& start = result.start;
  const int input = model.options().input_joint;
  const std::vector<double> d =
      request.input.d ? request.input.d->values : std::vector<double>(request.input.a.values.size(), 0.0);
  std::printf("loop (%dR)\n", model.joints());
  std::printf("  a                     %s\n", format_list(request.input.a.values).c_str());
  std::printf("  alpha_deg             %s\n", format_list(request.input.alpha_deg.values).c_str());
  std::printf("  d                     %s\n", format_list(d).c_str());
  std::printf("  length scale L        %s\n", readable(model.length_scale()).c_str());
  std::printf("  compliance            %s, torsion ratio k_t/(k_a L^2) = %s\n", to_string(request.compliance),
              readable(request.torsion_ratio).c_str());
  const char* assembled = request.theta  ? "from --theta-deg"
                          : start.motion ? "on a motion of the rigid loop"
                                         : "least-energy of the deterministic guesses: none at theta0 is on a motion";
  std::printf("assembly at theta0 = %s deg (%s)\n", readable(request.theta0_deg).c_str(), assembled);
  std::printf("  status                %s after %d Newton iterations\n", to_string(a.status), a.iterations);
  std::printf("  theta_deg             %s\n", joint_angles_deg(model, result.degrees, a.state.theta).c_str());
  std::string covered;
  if (request.range_deg) {
    covered = "as asked";
  } else if (!start.motion) {
    covered = request.theta ? "a full turn: the given pose is not on a motion" : "a full turn";
  } else if (start.motion->circuit.input_range(input).crank()) {
    covered = "a full turn: the input turns fully on the motion";
  } else {
    const std::array<double, 2> r = input_range_deg(start, input, result.degrees.theta0);
    covered = "a window inside the input's range [" + readable(r[0]) + ", " + readable(r[1]) + "] deg on the motion";
  }
  std::printf("cycle (%d samples over %s deg: %s)\n", static_cast<int>(c.samples.size()),
              readable(request.range_deg.value_or(start.range * kDegreesPerRadian)).c_str(), covered.c_str());
  std::printf("  E_mean                %s   [E / (k_a L^2)]\n", readable(c.E_mean).c_str());
  std::printf("  E_max                 %s\n", readable(c.E_max).c_str());
  std::printf("  failed samples        %d\n", c.failed_samples);
  std::printf("  branch jumps          %d\n", c.branch_jumps);
  std::printf("  refinements           %d\n", c.refinements);
  std::printf("  Newton iterations     %d\n", c.total_iterations);
  std::printf("  max closure residual  %s\n", readable(c.max_closure_residual).c_str());
  std::printf("  wall time             %s s\n", readable(result.seconds).c_str());
}

std::string plot_title(const EnergyRequest& request) {
  std::string title = "a = " + format_list(request.input.a.values) +
                      "   alpha = " + format_list(request.input.alpha_deg.values) + " deg";
  if (request.input.d) title += "   d = " + format_list(request.input.d->values);
  title += "   (" + std::string(to_string(request.compliance)) + " compliance)";
  return title;
}

int run_energy(const EnergyArguments& args) {
  // 1. Check everything the user gave before doing any work, so that bad
  //    input costs nothing and leaves no file behind.
  const EnergyRequest request = read_request(args);

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

  EquilibriumOptions equilibrium_options;
  equilibrium_options.compliance = request.compliance;
  equilibrium_options.torsion_stiffness_ratio = request.torsion_ratio;
  const LoopModel model(request.geometry, equilibrium_options);
  if (!std::isfinite(model.length_scale())) {
    throw UsageError(request.input.a.source, "the lengths are too large to compute with (length scale " +
                                                 format_double(model.length_scale()) + ")");
  }
  CycleOptions cycle_options;
  cycle_options.samples = request.samples;

  // 2. The computation.
  EquilibriumWorkspace workspace(model);
  EnergyResult result;
  const double theta0 = request.theta ? (*request.theta)[0] : request.theta0_deg / kDegreesPerRadian;
  result.degrees = {request.theta0_deg, theta0, model.options().input_joint};
  const auto clock = std::chrono::steady_clock::now();
  CycleStartOptions start_options;
  // 360 gives exactly 2 pi, so that the library treats it as a full turn.
  if (request.range_deg) start_options.range = *request.range_deg / 360.0 * (2.0 * kPi);
  result.start = choose_cycle_start(model, workspace, theta0, request.theta ? &*request.theta : nullptr, start_options);
  cycle_options.range = result.start.range;
  cycle_options.validate();
  cycle_energy(model, workspace, theta0, result.start.assembly.state, cycle_options, result.cycle);
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - clock).count();

  if (result.start.assembly.status != SolveStatus::converged) {
    std::fprintf(stderr,
                 "loopfarm energy: warning: the assembly at theta0 did not converge (%s); "
                 "the cycle starts from the best attempt\n",
                 to_string(result.start.assembly.status));
  }

  // 3. Files first, each written in full before it replaces its target; then
  //    stdout, so that a failed plot leaves neither files nor a summary.
  if (csv) {
    write_csv(csv->stream(), model, result.degrees, result.cycle);
    csv->close();
  }
  if (png) {
    png->close();  // gnuplot writes the temporary file itself
    EnergyPlotStyle style;
    style.title = plot_title(request);
    style.log_scale = request.log;
    style.theta0_deg = request.theta0_deg;
    style.theta0 = theta0;
    // A job's default: what a search would call a zero.
    style.zero_threshold = SearchSection{}.zero_threshold;
    style.threshold_source = "a job's default";
    style.notes = {"E_mean " + chart_number(result.cycle.E_mean) + ", E_max " + chart_number(result.cycle.E_max) +
                   " over " + std::to_string(result.cycle.samples.size()) + " samples" +
                   (result.cycle.E_max < style.zero_threshold ? ": below the zero threshold, a zero" : "")};
    style.format = plot_format_wanted;
    plot_energy_curve(gnuplot, result.cycle, style, png->temporary());
  }
  if (csv) csv->commit();
  if (png) png->commit();

  if (file_on_stdout) return kExitSuccess;
  if (args.format.format == OutputFormat::text) {
    print_summary(request, model, result);
  } else {
    write_record(stdout, summary_record(request, model, result), args.format.format);
  }
  return kExitSuccess;
}

}  // namespace

Subcommand add_energy_command(CLI::App& parent) {
  auto args = std::make_shared<EnergyArguments>();
  CLI::App* app =
      parent.add_subcommand("energy",
                            "Cycle energy of one loop: drive joint 1 through a turn and report the elastic energy "
                            "E/(k_a L^2) that closing the loop costs (zero for a movable linkage).");
  app->footer(
      "Lists are comma-separated, without spaces; use --flag=LIST when a list starts with '-'.\n"
      "Examples:\n"
      "  loopfarm energy --a 2,4,2,4 --alpha-deg 30,90,30,90 --theta-deg 120,90,-120,-90\n"
      "  loopfarm energy --geometry loop.toml --samples 64 --csv curve.csv --plot curve.png --log\n"
      "Exit codes: 0 done, 1 failure (e.g. gnuplot missing), 2 bad input.\n");

  add_geometry_options(*app, args->geometry);
  CLI::Option* theta0 =
      app->add_option("--theta0-deg", args->theta0_deg, "input angle theta0 the cycle starts at [deg]")
          ->type_name("DEG")
          ->capture_default_str();
  args->geometry.theta_option->excludes(theta0);

  app->add_option("--samples", args->samples, "samples N over the cycle (>= 2)")->type_name("N")->capture_default_str();
  app->add_option("--compliance", args->compliance,
                  "springy parameters: paper (a and alpha, the paper's model) or full (a, alpha and d)")
      ->type_name("paper|full")
      ->check(CLI::IsMember({"paper", "full"}))
      ->capture_default_str();
  app->add_option("--torsion-ratio", args->torsion_ratio, "torsion stiffness k_t / (k_a L^2), > 0")
      ->type_name("X")
      ->capture_default_str();
  app->add_option("--range-deg", args->range_deg,
                  "input range [deg]: 360 is a full turn from theta0, less is [theta0 - R/2, theta0 + R/2]; "
                  "auto: a full turn, or, when the assembly lies on a motion whose input rocks, a window "
                  "centred on theta0 reaching 90 % of the way to the nearer dead point")
      ->type_name("R")
      ->capture_default_str();

  add_format_option(*app, args->format,
                    {OutputFormat::text, OutputFormat::json, OutputFormat::csv, OutputFormat::markdown},
                    "print the summary as");
  args->csv_option = app->add_option("--csv", args->csv, "write the energy curve, one row per sample ('-': stdout)")
                         ->type_name("FILE");
  args->plot_option = app->add_option("--plot", args->plot,
                                      "draw energy against input angle (needs gnuplot); FILE's extension "
                                      "picks the format: .png, .svg or .pdf ('-': PNG on stdout)")
                          ->type_name("FILE");
  app->add_flag("--log", args->log, "logarithmic energy axis in --plot")->needs(args->plot_option);

  return {app, [args] { return run_energy(*args); }};
}

}  // namespace loopfarm::cli
