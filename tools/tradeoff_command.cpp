#include "tradeoff_command.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "cli_support.hpp"
#include "loopfarm/search/job.hpp"
#include "loopfarm/study/tradeoff.hpp"
#include "output_format.hpp"
#include "plot.hpp"

namespace loopfarm::cli {
namespace {

struct TradeoffArguments {
  std::string job;
  std::string starts = "50";
  std::string per_family = "4";
  std::string generic = "8";
  std::string perturbations = "1e-2,1e-3,1e-4,1e-5,1e-6,1e-7,1e-8";
  std::string samples = "4,8,16,32,64,128";
  std::string ranges_deg = "360,180,90";
  std::string closure_tolerances = "1e-6,1e-8,1e-10,1e-13";
  std::string compliances = "paper,full";
  std::string objectives = "mean,max";
  std::string algorithms = "gauss-newton,LD_LBFGS,LD_SLSQP,LD_MMA,LN_BOBYQA";
  std::string zero_thresholds = "1e-8,1e-12,1e-16,1e-20,1e-24";
  std::string ftol_rels = "0,1e-4,1e-3,1e-2";
  std::string progress_windows = "0";
  std::string checkpoints = "0";
  std::string reuse_nearby_cycles = "true,false";
  std::string analysis_steps = "64,128,360";
  std::string csv;
  FormatChoice format;
  std::string plot;
  bool quiet = false;
};

long long bounded_integer(const std::string& text, const std::string& flag, long long lo, long long hi) {
  const long long value = parse_integer(text, flag);
  if (value < lo || value > hi) {
    throw UsageError(
        flag, "got " + std::to_string(value) + "; must be in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
  }
  return value;
}

// Comma-separated words ("paper,full"); no empty elements, none twice.
std::vector<std::string> parse_word_list(const std::string& text, const std::string& flag) {
  std::vector<std::string> words;
  std::set<std::string> seen;
  size_t begin = 0;
  while (true) {
    const size_t comma = text.find(',', begin);
    const std::string word = text.substr(begin, comma == std::string::npos ? std::string::npos : comma - begin);
    const std::string element = "element " + std::to_string(words.size() + 1) + " of " + quote_text(text);
    if (word.empty()) throw UsageError(flag, element + " is empty");
    if (!seen.insert(word).second) throw UsageError(flag, element + " is " + quote_text(word) + ": given twice");
    words.push_back(word);
    if (comma == std::string::npos) break;
    begin = comma + 1;
  }
  return words;
}

// Numbers, each checked by `valid` (which says what is allowed), none twice.
std::vector<double> checked_numbers(const std::string& text, const std::string& flag, bool (*valid)(double),
                                    const std::string& allowed) {
  const std::vector<double> values = parse_number_list(text, flag);
  std::set<double> seen;
  for (size_t i = 0; i < values.size(); ++i) {
    const std::string element =
        "element " + std::to_string(i + 1) + " of " + quote_text(text) + " is " + format_double(values[i]);
    if (!valid(values[i])) throw UsageError(flag, element + ": must be " + allowed);
    if (!seen.insert(values[i]).second) throw UsageError(flag, element + ": given twice");
  }
  return values;
}

// Every flag checked here, so that a message names its flag; the library's
// TradeoffOptions::validate stays as its own check.
TradeoffOptions read_options(const TradeoffArguments& args) {
  TradeoffOptions o;
  o.starts = bounded_integer(args.starts, "--starts", 1, 1000000);
  o.ground_truth.cases_per_family = static_cast<int>(bounded_integer(args.per_family, "--per-family", 0, 10000));
  o.ground_truth.generic_loops = static_cast<int>(bounded_integer(args.generic, "--generic", 0, 10000));
  o.ground_truth.relative_perturbations.clear();
  if (args.perturbations != "none") {
    o.ground_truth.relative_perturbations = checked_numbers(
        args.perturbations, "--perturbations", [](double v) { return v > 0.0 && v < 1.0; }, "in (0, 1)");
  }
  o.samples.clear();
  for (double n : checked_numbers(
           args.samples, "--samples", [](double v) { return v >= 4 && v <= 100000 && v == std::floor(v); },
           "a whole number in [4, 100000]")) {
    o.samples.push_back(static_cast<int>(n));
  }
  o.ranges_deg = checked_numbers(
      args.ranges_deg, "--ranges-deg", [](double v) { return v > 0.0 && v <= 360.0; }, "in (0, 360]");
  o.closure_tolerances = checked_numbers(
      args.closure_tolerances, "--closure-tolerances", [](double v) { return v > 0.0 && v <= 1e-5; }, "in (0, 1e-5]");
  o.compliances = parse_word_list(args.compliances, "--compliances");
  for (const std::string& c : o.compliances) {
    if (c != "paper" && c != "full") {
      throw UsageError("--compliances", quote_text(c) + " is not a compliance set; expected paper or full");
    }
  }
  o.objectives = parse_word_list(args.objectives, "--objectives");
  for (const std::string& objective : o.objectives) {
    if (objective != "mean" && objective != "max") {
      throw UsageError("--objectives", quote_text(objective) + " is not an objective; expected mean or max");
    }
  }
  o.algorithms = parse_word_list(args.algorithms, "--algorithms");
  for (const std::string& a : o.algorithms) {
    if (!is_known_algorithm(a)) {
      throw UsageError("--algorithms", quote_text(a) + " is not gauss-newton or an NLopt algorithm of this build");
    }
  }
  o.zero_thresholds = checked_numbers(
      args.zero_thresholds, "--zero-thresholds", [](double v) { return v > 0.0 && v < 1.0; }, "in (0, 1)");
  o.ftol_rels = checked_numbers(
      args.ftol_rels, "--ftol-rels", [](double v) { return v >= 0.0 && v < 1.0; }, "in [0, 1)");
  o.progress_windows.clear();
  for (double w : checked_numbers(
           args.progress_windows, "--progress-windows",
           [](double v) { return v >= 0 && v <= 100000000 && v == std::floor(v); }, "a whole number in [0, 1e8]")) {
    o.progress_windows.push_back(static_cast<int>(w));
  }
  o.checkpoints.clear();
  for (const std::string& word : parse_word_list(args.checkpoints, "--checkpoints")) {
    // "0" (off) or "EVALUATIONS:OBJECTIVE".
    const size_t colon = word.find(':');
    if (colon == std::string::npos) {
      if (word != "0") throw UsageError("--checkpoints", quote_text(word) + " is not 0 or EVALUATIONS:OBJECTIVE");
      o.checkpoints.emplace_back(0, 0.0);
      continue;
    }
    const long long evaluations = bounded_integer(word.substr(0, colon), "--checkpoints", 1, 100000000);
    const double objective = parse_number(word.substr(colon + 1), "--checkpoints");
    if (!(objective > 0.0)) {
      throw UsageError("--checkpoints", quote_text(word) + ": the objective must be > 0");
    }
    o.checkpoints.emplace_back(static_cast<int>(evaluations), objective);
  }
  o.reuse_nearby_cycles.clear();
  for (const std::string& r : parse_word_list(args.reuse_nearby_cycles, "--reuse-nearby-cycles")) {
    if (r != "true" && r != "false") {
      throw UsageError("--reuse-nearby-cycles", quote_text(r) + " is not true or false");
    }
    if (std::find(o.reuse_nearby_cycles.begin(), o.reuse_nearby_cycles.end(), r == "true") !=
        o.reuse_nearby_cycles.end()) {
      throw UsageError("--reuse-nearby-cycles", quote_text(r) + " is given twice");
    }
    o.reuse_nearby_cycles.push_back(r == "true");
  }
  o.analysis_steps.clear();
  for (double n : checked_numbers(
           args.analysis_steps, "--analysis-steps",
           [](double v) { return v >= 64 && v <= 100000 && v == std::floor(v); }, "a whole number in [64, 100000]")) {
    o.analysis_steps.push_back(static_cast<int>(n));
  }
  o.validate();
  return o;
}

// Every measure of one configuration: the CSV row, the JSON object.
nlohmann::ordered_json row_record(const TradeoffRow& r) {
  nlohmann::ordered_json f;
  f["axis"] = r.axis;
  f["value"] = r.value;
  f["median_seconds"] = r.median_seconds;
  f["p90_seconds"] = r.p90_seconds;
  f["search_seconds"] = r.search_seconds;
  f["analysis_seconds"] = r.analysis_seconds;
  f["total_seconds"] = r.total_seconds;
  f["starts"] = r.starts;
  f["zeros"] = r.zeros;
  f["zero_fraction"] = r.zero_fraction();
  f["verified"] = r.verified;
  f["seconds_per_verified_zero"] = r.seconds_per_verified_zero();
  f["false_zeros"] = r.false_zeros;
  f["worst_family_residual"] = r.worst_family_residual;
  f["movable_cases"] = r.movable_cases;
  f["missed_zeros"] = r.missed_zeros;
  f["misanalysed"] = r.misanalysed;
  f["rigid_cases"] = r.rigid_cases;
  f["rigid_read_as_zero"] = r.rigid_read_as_zero;
  f["smallest_told_apart"] = r.smallest_told_apart;
  f["error_rate"] = r.error_rate();
  f["pareto"] = r.pareto;
  return f;
}

std::string name_of(const TradeoffRow& r) { return r.axis == "base" ? "base" : r.axis + "=" + r.value; }

void print_table(const std::vector<TradeoffRow>& rows) {
  std::printf("%-26s %10s %10s %11s %9s %8s %6s %9s %8s %9s %9s %10s %8s %s\n", "configuration", "median_ms", "p90_ms",
              "analysis_ms", "zeros", "verified", "false", "fam_res", "missed", "misread", "rigid0", "told_apart",
              "error_%", "front");
  for (const TradeoffRow& r : rows) {
    const std::string zeros = std::to_string(r.zeros) + "/" + std::to_string(r.starts);
    const std::string missed = std::to_string(r.missed_zeros) + "/" + std::to_string(r.movable_cases);
    const std::string rigid = std::to_string(r.rigid_read_as_zero) + "/" + std::to_string(r.rigid_cases);
    const std::string misread = std::to_string(r.misanalysed) + "/" + std::to_string(r.movable_cases);
    // Milliseconds of analysis per zero (0 when the search found none).
    const double analysis_ms = r.zeros > 0 ? 1e3 * r.analysis_seconds / static_cast<double>(r.zeros) : 0.0;
    std::printf("%-26s %10.3f %10.3f %11.3f %9s %8ld %6ld %9.1e %8s %9s %9s %10.0e %8.2f %s\n", name_of(r).c_str(),
                1e3 * r.median_seconds, 1e3 * r.p90_seconds, analysis_ms, zeros.c_str(), r.verified, r.false_zeros,
                r.worst_family_residual, missed.c_str(), misread.c_str(), rigid.c_str(), r.smallest_told_apart,
                100.0 * r.error_rate(), r.pareto ? "*" : "");
  }
}

// Three panels with one marker per configuration, each named in the key:
// median seconds per start against error rate (the Pareto front joined),
// core-seconds per verified zero against error rate (what a discovery
// costs), and median seconds per start against the worst family residual of
// the verified zeros, the accuracy that still tells apart the many
// configurations of error rate 0. The error axis is logarithmic, with
// error-free configurations drawn on its floor, labelled 0. A colour per
// axis (colour-blind safe), a point shape per value on it; front members
// filled and larger.
constexpr double kErrorFloor = 0.01;  // [%]

// The colour of an axis's markers: Okabe and Ito's palette, then Tol's
// muted wine, teal, olive and indigo, and grey.
const char* axis_colour(const std::string& axis) {
  static const std::pair<const char*, const char*> colours[] = {{"base", "#000000"},
                                                                {"samples", "#0072b2"},
                                                                {"range_deg", "#56b4e9"},
                                                                {"closure_tolerance", "#009e73"},
                                                                {"compliance", "#e69f00"},
                                                                {"objective", "#882255"},
                                                                {"algorithm", "#d55e00"},
                                                                {"ftol_rel", "#cc79a7"},
                                                                {"progress_window", "#44aa99"},
                                                                {"checkpoint", "#aa4499"},
                                                                {"reuse_nearby_cycle", "#999933"},
                                                                {"zero_threshold", "#332288"},
                                                                {"analysis_steps", "#777777"}};
  for (const auto& [name, colour] : colours) {
    if (axis == name) return colour;
  }
  return "#777777";
}

void plot_tradeoff(const std::vector<TradeoffRow>& rows, const std::string& job_name, PlotFormat format,
                   const std::filesystem::path& output) {
  const std::filesystem::path gnuplot = require_gnuplot("--plot");
  // The residual axis: its floor holds verified zeros of residual 0, its top
  // the configurations without a verified zero.
  double lowest = std::numeric_limits<double>::infinity();
  double highest = 0.0;
  for (const TradeoffRow& r : rows) {
    if (r.verified > 0 && r.worst_family_residual > 0.0) {
      lowest = std::min(lowest, r.worst_family_residual);
      highest = std::max(highest, r.worst_family_residual);
    }
  }
  if (!(highest > 0.0)) lowest = highest = 1e-12;
  const double residual_floor = std::pow(10.0, std::floor(std::log10(lowest)) - 1.0);
  const double residual_none = std::pow(10.0, std::ceil(std::log10(highest)) + 1.0);

  ScratchFile data(".dat");
  ScratchFile front(".dat");
  std::vector<const TradeoffRow*> on_front;
  // The panels' x values, for their axes: times per start, costs per zero.
  std::vector<double> median_ms, per_zero_s;
  auto drawn_error = [](const TradeoffRow& r) { return std::max(100.0 * r.error_rate(), kErrorFloor); };
  for (const TradeoffRow& r : rows) {
    // A configuration without a verified zero has no cost per zero: NaN,
    // which gnuplot leaves out of the second panel.
    const double per_zero = r.seconds_per_verified_zero();
    const double residual = r.verified == 0                 ? residual_none
                            : r.worst_family_residual > 0.0 ? r.worst_family_residual
                                                            : residual_floor;
    std::fprintf(data.stream(), "%.17g %.17g %s %.17g\n", 1e3 * r.median_seconds, drawn_error(r),
                 std::isfinite(per_zero) ? format_double(per_zero).c_str() : "NaN", residual);
    median_ms.push_back(1e3 * r.median_seconds);
    per_zero_s.push_back(per_zero);
    if (r.pareto) on_front.push_back(&r);
  }
  // A time axis is logarithmic unless a value on it is 0; the second panel
  // is empty, and says why, when no configuration found a verified zero.
  const std::string time_axis = panel_x_axis_gnuplot(median_ms, "no time per start measured");
  const std::string cost_axis =
      panel_x_axis_gnuplot(per_zero_s, "no configuration found a verified zero: no cost per zero to draw");
  std::sort(on_front.begin(), on_front.end(),
            [](const TradeoffRow* a, const TradeoffRow* b) { return a->median_seconds < b->median_seconds; });
  for (const TradeoffRow* r : on_front)
    std::fprintf(front.stream(), "%.17g %.17g\n", 1e3 * r->median_seconds, drawn_error(*r));
  data.close();
  front.close();
  const std::string d = data.path().string();

  // One plot element per configuration (row i of the data), so that the key
  // names each: the axis's colour, a shape per value along the axis (open;
  // filled on the front).
  // A marker style per configuration: the axis's colour, a shape per value
  // along the axis (open; filled and larger on the front).
  std::vector<std::string> styles;
  std::map<std::string, int> seen;
  for (const TradeoffRow& r : rows) {
    static const int kShapes[] = {4, 6, 8, 10, 12, 14};  // square, circle, triangles, diamond, pentagon
    const int shape = kShapes[seen[r.axis]++ % 6];
    styles.push_back("with points pt " + std::to_string(r.pareto ? shape + 1 : shape) + " ps " +
                     (r.pareto ? "2.2" : "1.6") + " lw 1.5 lc rgb '" + axis_colour(r.axis) + "'");
  }
  // One plot element per configuration (row i of the data).
  auto markers = [&](int x_column, int y_column) {
    std::string elements;
    for (size_t i = 0; i < rows.size(); ++i) {
      elements += ", \\\n  " + gnuplot_string(d) + " every ::" + std::to_string(i) + "::" + std::to_string(i) +
                  " using " + std::to_string(x_column) + ":" + std::to_string(y_column) + " " + styles[i] + " notitle";
    }
    return elements;
  };
  ScratchFile script(".gp");
  std::FILE* gp = script.stream();
  std::fputs(gnuplot_terminal(format, 2100, 900, ",10").c_str(), gp);
  std::fprintf(gp, "set output %s\n", gnuplot_string(output.string()).c_str());
  // The same frame for the three panels; the key is a band of its own below them.
  std::fprintf(gp,
               "set multiplot layout 1,3 title %s noenhanced margins screen 0.06, 0.99, 0.34, 0.93 spacing "
               "screen 0.07\n",
               gnuplot_string("Speed against accuracy: " + job_name + ", one marker per configuration").c_str());
  std::fprintf(gp,
               "set ylabel 'error rate [%%]: wrong answers / judged (0 drawn at %g)' noenhanced\n"
               "set logscale y\nset grid\nset yrange [%g:100]\nset ytics add ('0' %g)\nset key off\n"
               "set offsets graph 0.05, graph 0.05, 0, 0\n"
               "set xlabel 'median time of local minimisation per start [ms]' noenhanced\n",
               kErrorFloor, kErrorFloor / 2.0, kErrorFloor);
  std::fputs(time_axis.c_str(), gp);
  std::fprintf(gp, "plot %s using 1:2 with lines lw 2 lc rgb '#444444' notitle%s\n",
               gnuplot_string(front.path().string()).c_str(), markers(1, 2).c_str());
  std::fputs("set xlabel 'core-seconds of search and analysis per verified zero [s]' noenhanced\n", gp);
  std::fputs(cost_axis.c_str(), gp);
  std::fprintf(gp, "plot 1/0 notitle%s\n", markers(3, 2).c_str());
  std::fputs(time_axis.c_str(), gp);
  std::fprintf(gp,
               "set xlabel 'median time of local minimisation per start [ms]' noenhanced\n"
               "set ylabel 'worst family residual of the verified zeros (none: no verified zero)' noenhanced\n"
               "set yrange [%.17g:%.17g]\nset format y '10^{%%L}'\n"
               "set ytics add ('0' %.17g, 'none' %.17g)\n",
               residual_floor / 3.0, residual_none * 3.0, residual_floor, residual_none);
  std::fprintf(gp, "plot 1/0 notitle%s\n", markers(1, 4).c_str());
  // The key: an empty frame across the bottom holding one entry per
  // configuration (gnuplot needs one real element: a line outside the range).
  std::fputs(
      "set origin 0, 0\nset size 1, 0.25\nunset border\nunset tics\nunset xlabel\nunset ylabel\nunset grid\nunset "
      "label\n"
      "unset logscale\nset offsets 0, 0, 0, 0\nset margins 0, 0, 0, 0\nset xrange [0:1]\nset yrange [0:1]\n"
      "set key center center horizontal maxcols 6 font ',10' samplen 1 width 2\n",
      gp);
  std::string entries =
      "plot 2 with lines notitle, \\\n  keyentry with lines lw 2 lc rgb '#444444' title 'Pareto front'";
  for (size_t i = 0; i < rows.size(); ++i) {
    entries += ", \\\n  keyentry " + styles[i] + " title " +
               gnuplot_string(name_of(rows[i]) + (rows[i].pareto ? " (front)" : "")) + " noenhanced";
  }
  std::fputs((entries + "\n").c_str(), gp);
  std::fputs("unset multiplot\nunset output\n", gp);
  script.close();
  render_gnuplot_script(gnuplot, script.path(), output, "--plot");
}

int run_tradeoff_command(const TradeoffArguments& args) {
  Job job;
  try {
    job = read_job_file(args.job);
  } catch (const JobError& error) {
    throw UsageError("job file", error.what());
  }
  TradeoffOptions options = read_options(args);
  // Outputs are opened (and gnuplot found) before the work: a bad path fails at once.
  const bool file_on_stdout = file_takes_standard_output({{"--csv", args.csv}, {"--plot", args.plot}}, args.format);
  std::optional<PendingOutput> csv;
  if (!args.csv.empty()) csv.emplace(args.csv, "--csv");
  std::optional<PendingOutput> plot;
  PlotFormat plot_format_wanted = PlotFormat::png;
  if (!args.plot.empty()) {
    plot_format_wanted = plot_format(args.plot, "--plot");
    require_plot_terminal(require_gnuplot("--plot"), plot_format_wanted, "--plot");
    plot.emplace(args.plot, "--plot");
  }
  if (!args.quiet) {
    options.progress = [](int done, int total, const std::string& name) {
      std::fprintf(stderr, "loopfarm tradeoff: %d/%d configurations measured (%s)\n", done, total, name.c_str());
    };
  }
  const std::vector<TradeoffRow> rows = run_tradeoff(job, options);
  std::vector<nlohmann::ordered_json> records;
  for (const TradeoffRow& r : rows) records.push_back(row_record(r));
  if (!file_on_stdout) {
    if (args.format.format == OutputFormat::text) {
      print_table(rows);
    } else {
      write_records(stdout, records, args.format.format);
    }
  }
  if (csv) {
    write_records(csv->stream(), records, OutputFormat::csv);
    csv->commit();
  }
  if (plot) {
    plot->close();
    plot_tradeoff(rows, std::filesystem::path(args.job).filename().string(), plot_format_wanted, plot->temporary());
    plot->commit();
  }
  return kExitSuccess;
}

}  // namespace

Subcommand add_tradeoff_command(CLI::App& parent) {
  auto args = std::make_shared<TradeoffArguments>();
  CLI::App* app = parent.add_subcommand(
      "tradeoff",
      "Measure a job under many configurations, one choice changed at a time (cycle samples, equilibrium tolerance, "
      "compliance, objective, algorithm, its relative-decrease stop, reuse of the nearby cycle, zero threshold, step "
      "of a zero's analysis): "
      "seconds per start against accuracy on the job's starts and on the "
      "ground-truth set. docs/quality/tradeoff.md explains the measures and the chart.");
  app->footer(
      "Examples:\n"
      "  loopfarm tradeoff jobs/default.toml --csv docs/quality/tradeoff.csv --plot docs/quality/tradeoff.png\n"
      "  loopfarm tradeoff jobs/default.toml --starts 10 --algorithms gauss-newton,LD_LBFGS --samples 8,16\n"
      "Runs on one core; each start and each ground-truth loop is measured under every configuration.\n"
      "Exit codes: 0 done, 1 failure (gnuplot), 2 bad input.\n");
  app->add_option("JOB", args->job, "job file (TOML): the base configuration and its starts")->required();
  app->add_option("--starts", args->starts, "starts 0..N-1 of the job measured per configuration")
      ->type_name("N")
      ->capture_default_str();
  app->add_option("--per-family", args->per_family, "ground truth: movable loops per family")
      ->type_name("N")
      ->capture_default_str();
  app->add_option("--generic", args->generic, "ground truth: generic rigid loops")
      ->type_name("N")
      ->capture_default_str();
  app->add_option("--perturbations", args->perturbations, "ground truth: relative perturbation sizes, or none")
      ->type_name("LIST")
      ->capture_default_str();
  app->add_option("--samples", args->samples, "cycle samples N tried")->type_name("LIST")->capture_default_str();
  app->add_option("--ranges-deg", args->ranges_deg,
                  "cycle input ranges tried [deg]: 360 a full turn, less a window around theta0")
      ->type_name("LIST")
      ->capture_default_str();
  app->add_option("--closure-tolerances", args->closure_tolerances,
                  "equilibrium closure tolerances tried (stationarity 100x looser)")
      ->type_name("LIST")
      ->capture_default_str();
  app->add_option("--compliances", args->compliances, "compliance sets tried")
      ->type_name("LIST")
      ->capture_default_str();
  app->add_option("--objectives", args->objectives, "search objectives tried (mean: E_mean, max: E_max)")
      ->type_name("LIST")
      ->capture_default_str();
  app->add_option("--algorithms", args->algorithms, "local algorithms tried")->type_name("LIST")->capture_default_str();
  app->add_option("--zero-thresholds", args->zero_thresholds, "zero thresholds tried")
      ->type_name("LIST")
      ->capture_default_str();
  app->add_option("--ftol-rels", args->ftol_rels, "relative-decrease stops of the local search tried (0: off)")
      ->type_name("LIST")
      ->capture_default_str();
  app->add_option("--progress-windows", args->progress_windows,
                  "progress stops of the local search tried, in evaluations (0: off), with the job's progress_factor")
      ->type_name("LIST")
      ->capture_default_str();
  app->add_option("--checkpoints", args->checkpoints,
                  "checkpoints of the local search tried, EVALUATIONS:OBJECTIVE (0: off): a start still above the "
                  "objective after that many evaluations stops")
      ->type_name("LIST")
      ->capture_default_str();
  app->add_option("--reuse-nearby-cycles", args->reuse_nearby_cycles,
                  "whether each evaluation's cycle starts from the last one's samples, tried")
      ->type_name("LIST")
      ->capture_default_str();
  app->add_option("--analysis-steps", args->analysis_steps,
                  "steps per turn of a zero's analysis tried (its largest step is 360/S deg)")
      ->type_name("LIST")
      ->capture_default_str();
  add_format_option(*app, args->format,
                    {OutputFormat::text, OutputFormat::csv, OutputFormat::json, OutputFormat::markdown},
                    "print the configurations (text: a table of the main measures; the others: every measure) as");
  app->add_option("--csv", args->csv, "write every measure of every configuration as CSV ('-': stdout)")
      ->type_name("FILE");
  app->add_option("--plot", args->plot,
                  "draw seconds per start against error rate and family residual (needs gnuplot); the "
                  "extension picks the format: .png, .svg or .pdf ('-': PNG on stdout)")
      ->type_name("FILE");
  app->add_flag("--quiet", args->quiet, "no progress lines on stderr");
  return {app, [args] { return run_tradeoff_command(*args); }};
}

}  // namespace loopfarm::cli
