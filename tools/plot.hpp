// Plots through gnuplot, run as a separate program: the energy curve of a
// cycle, the input-output curves of a loop's motion and the histogram of a
// database's minima, as PNG, SVG or PDF (the file's extension decides).
#pragma once

#include <cstdint>
#include <filesystem>
#include <map>
#include <string>
#include <string_view>
#include <vector>

#include "loopfarm/core/cycle.hpp"
#include "loopfarm/core/motion.hpp"

namespace loopfarm::cli {

// A string literal for a gnuplot script: single quotes, in which only the
// quote itself needs escaping (by doubling) and backslashes stay literal.
std::string gnuplot_string(std::string_view text);

// The first executable called `name` on PATH, or an empty path.
std::filesystem::path find_program(std::string_view name);

// gnuplot's path; throws EnvironmentError naming `flag` when it is not
// installed, so a command can refuse before it starts any work.
std::filesystem::path require_gnuplot(const std::string& flag);

// The image formats a chart can be written in, picked by the target's
// extension: .png (pngcairo, or libgd's png when gnuplot lacks cairo), .svg,
// .pdf (pdfcairo). The target "-" (standard output) is PNG.
enum class PlotFormat { png, svg, pdf };
const char* to_string(PlotFormat format);

// The format for `target` (case-insensitive extension); throws UsageError
// naming `flag` and the extensions accepted for any other name, so that a
// command can refuse before it does any work.
PlotFormat plot_format(const std::filesystem::path& target, const std::string& flag);

// The gnuplot lines that select `format`'s terminal for a chart of
// width x height pixels (PDF: the same size at 100 pixels an inch) with
// enhanced text; `font` ("" for the terminal's default) as gnuplot takes it,
// e.g. ",10". A PDF whose gnuplot lacks pdfcairo stops with a message.
std::string gnuplot_terminal(PlotFormat format, int width, int height, const std::string& font = "");

// Refuses (UsageError naming `flag`) a format `gnuplot` cannot write: a PDF
// without its pdfcairo terminal (PNG falls back to libgd's png, and SVG is
// in every gnuplot). For a command whose work comes before its chart, so
// that it refuses before the work rather than fail after it. Throws
// EnvironmentError when gnuplot cannot be asked.
void require_plot_terminal(const std::filesystem::path& gnuplot, PlotFormat format, const std::string& flag);

// A number as a chart quotes it: 3 significant digits, "1e-12" not "1.00e-12".
std::string chart_number(double value);

// The gnuplot lines that set the x axis of one panel of a multiplot for the
// values drawn along it (one that is not finite is not drawn): logarithmic
// when every value is positive; linear from 0 when one is 0 or less, which
// a logarithmic axis would leave out (and fail on, with "logscaled axis
// must have positive range", when none is left); and when no value is
// drawn at all, an empty axis from 0 to 1 without numbers and `note` in the
// panel's middle. Each panel's lines undo what the last one's set.
std::string panel_x_axis_gnuplot(const std::vector<double>& values, const std::string& note);

struct EnergyPlotStyle {
  std::string title;       // plain text, one line
  bool log_scale = false;  // logarithmic energy axis
  // The x axis shows theta0_deg + (theta_in - theta0) in degrees, so that
  // the start angle appears exactly as the user gave it.
  double theta0_deg = 0.0;
  double theta0 = 0.0;  // [rad]
  int input_joint = 0;  // the joint whose angle the x axis shows (0-based)
  // E/(k_a L^2) at or below which an energy is zero (> 0), and where that
  // threshold comes from ("job default", "run 1"), for the chart's key.
  double zero_threshold = 1e-12;
  std::string threshold_source;
  // Plain-text lines under the title (e.g. the E_mean a table prints for the
  // same loop beside this curve's own), one per element.
  std::vector<std::string> notes;
  PlotFormat format = PlotFormat::png;
};

// What plot_energy_curve hands gnuplot: the data file's text (input angle
// [deg], energy as drawn, marker class: 0 solved, 1 failed, 2 branch jump)
// and the script that reads it from `data_path` and writes `output`.
// Energies below the zero threshold are drawn at it on a logarithmic axis
// and at 0 on a linear one (round-off of a zero, not a shape), and the
// threshold is a labelled dashed line; a curve that is all zero gets a
// linear range around [0, threshold]. Throws EnvironmentError when no sample
// has a finite energy.
struct GnuplotInput {
  std::string data;
  std::string script;
};
GnuplotInput energy_curve_gnuplot(const CycleSummary& summary, const EnergyPlotStyle& style,
                                  const std::filesystem::path& data_path, const std::filesystem::path& output);

// Draws energy against input angle [deg] into `output` (overwritten) in
// style.format. Throws EnvironmentError if gnuplot fails or writes nothing,
// with gnuplot's first error line.
void plot_energy_curve(const std::filesystem::path& gnuplot, const CycleSummary& summary, const EnergyPlotStyle& style,
                       const std::filesystem::path& output);

// The histogram of log10 of every start's E_mean: `decades` maps
// floor(log10 E_mean) to its starts, `exact_zeros` counts E_mean = 0. Every
// decade below the zero threshold's, and the exact zeros, make one bar
// labelled as zero; the threshold is a labelled line. `zero_threshold` <= 0:
// unknown (no runs), every decade drawn as it is.
GnuplotInput minima_histogram_gnuplot(const std::map<int, std::int64_t>& decades, std::int64_t exact_zeros,
                                      double zero_threshold, PlotFormat format, const std::filesystem::path& data_path,
                                      const std::filesystem::path& output);
void plot_minima_histogram(const std::filesystem::path& gnuplot, const std::map<int, std::int64_t>& decades,
                           std::int64_t exact_zeros, double zero_threshold, PlotFormat format,
                           const std::filesystem::path& output, const std::string& flag);

// Draws every circuit's joint angles [deg, unwrapped along the circuit]
// against the input angle (left) and against arclength (right) into
// `output` in `format`. Throws EnvironmentError as plot_energy_curve does.
void plot_motion(const std::filesystem::path& gnuplot, const MotionAnalysis& motion, const std::string& title,
                 PlotFormat format, const std::filesystem::path& output);

// Runs gnuplot on a finished script that writes `output`. Throws
// EnvironmentError naming `flag` if gnuplot fails (with its first error line)
// or writes nothing.
void render_gnuplot_script(const std::filesystem::path& gnuplot, const std::filesystem::path& script,
                           const std::filesystem::path& output, const std::string& flag);

}  // namespace loopfarm::cli
