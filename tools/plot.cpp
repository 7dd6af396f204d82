#include "plot.hpp"

#include <fcntl.h>
#include <spawn.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <functional>
#include <limits>
#include <vector>

#include "cli_support.hpp"

extern char** environ;

namespace loopfarm::cli {
namespace {

constexpr double kDegreesPerRadian = 180.0 / 3.14159265358979323846;

// The first non-empty line of a file (gnuplot's error message), trimmed.
std::string first_line(const std::filesystem::path& file) {
  std::ifstream in(file);
  std::string line;
  std::string found;
  while (std::getline(in, line)) {
    // gnuplot repeats the offending script line before "line N: message";
    // the message is the informative part, so prefer it.
    const std::string trimmed = one_line(line);
    if (trimmed.find_first_not_of(' ') == std::string::npos) continue;
    if (trimmed.find("line ") != std::string::npos && trimmed.find(':') != std::string::npos) {
      return trimmed.substr(trimmed.find_first_not_of(' '));
    }
    if (found.empty()) found = trimmed.substr(trimmed.find_first_not_of(' '));
  }
  return found;
}

// Runs `program` with `argument`, stdin from /dev/null and both output
// streams into `log`; returns the wait status.
int run_program(const std::filesystem::path& program, const std::filesystem::path& argument,
                const std::filesystem::path& log) {
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0600);
  posix_spawn_file_actions_adddup2(&actions, STDOUT_FILENO, STDERR_FILENO);

  std::string program_text = program.string();
  std::string argument_text = argument.string();
  char* argv[] = {program_text.data(), argument_text.data(), nullptr};
  pid_t pid = 0;
  const int spawn_error = posix_spawn(&pid, program_text.c_str(), &actions, nullptr, argv, environ);
  posix_spawn_file_actions_destroy(&actions);
  if (spawn_error != 0) {
    throw EnvironmentError("--plot: cannot start gnuplot (" + program_text + "): " + std::strerror(spawn_error));
  }
  int status = 0;
  while (waitpid(pid, &status, 0) < 0) {
    if (errno != EINTR) throw EnvironmentError(std::string("--plot: waiting for gnuplot: ") + std::strerror(errno));
  }
  return status;
}

}  // namespace

std::string gnuplot_string(std::string_view text) {
  std::string out = "'";
  for (const char c : text) {
    if (c == '\'') out += '\'';
    out += c;
  }
  out += '\'';
  return out;
}

std::filesystem::path find_program(std::string_view name) {
  const char* path = std::getenv("PATH");
  if (path == nullptr) return {};
  std::string_view directories(path);
  while (true) {
    const size_t colon = directories.find(':');
    std::string_view directory = directories.substr(0, colon);
    if (directory.empty()) directory = ".";  // an empty PATH entry means the current directory
    const std::filesystem::path candidate = std::filesystem::path(directory) / name;
    std::error_code ec;
    if (std::filesystem::is_regular_file(candidate, ec) && ::access(candidate.c_str(), X_OK) == 0) return candidate;
    if (colon == std::string_view::npos) break;
    directories.remove_prefix(colon + 1);
  }
  return {};
}

std::filesystem::path require_gnuplot(const std::string& flag) {
  std::filesystem::path gnuplot = find_program("gnuplot");
  if (gnuplot.empty()) {
    throw EnvironmentError(flag +
                           ": gnuplot not found on PATH; install it (Debian: apt-get install gnuplot-nox, "
                           "or run scripts/deps.sh) or leave out " +
                           flag);
  }
  return gnuplot;
}

const char* to_string(PlotFormat format) {
  switch (format) {
    case PlotFormat::svg:
      return "svg";
    case PlotFormat::pdf:
      return "pdf";
    case PlotFormat::png:
      break;
  }
  return "png";
}

PlotFormat plot_format(const std::filesystem::path& target, const std::string& flag) {
  if (target == "-") return PlotFormat::png;  // standard output
  std::string extension = target.extension().string();
  for (char& c : extension) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (extension == ".png") return PlotFormat::png;
  if (extension == ".svg") return PlotFormat::svg;
  if (extension == ".pdf") return PlotFormat::pdf;
  throw UsageError(flag, quote_text(target.string()) +
                             ": the extension picks the image format; expected .png, .svg or .pdf "
                             "(or - for a PNG on standard output)");
}

std::string gnuplot_terminal(PlotFormat format, int width, int height, const std::string& font) {
  const std::string font_option = font.empty() ? "" : " font " + gnuplot_string(font);
  char size[64];
  switch (format) {
    case PlotFormat::svg:
      std::snprintf(size, sizeof size, "%d,%d", width, height);
      return "set terminal svg size " + std::string(size) + " dynamic enhanced background rgb 'white'" + font_option +
             "\n";
    case PlotFormat::pdf:
      // pdfcairo measures in inches: the pixel size at 100 pixels an inch.
      std::snprintf(size, sizeof size, "%gin,%gin", width / 100.0, height / 100.0);
      return "if (strstrt(GPVAL_TERMINALS, 'pdfcairo') == 0) {\n"
             "  print 'this gnuplot has no pdfcairo terminal; write a .png or .svg instead'\n"
             "  exit status 1\n"
             "}\n"
             "set terminal pdfcairo size " +
             std::string(size) + " enhanced" + font_option + "\n";
    case PlotFormat::png:
      break;
  }
  // pngcairo draws antialiased text and lines; Debian's gnuplot-nox has it,
  // but fall back to the libgd png terminal should a build lack cairo.
  std::snprintf(size, sizeof size, "%d,%d", width, height);
  return "if (strstrt(GPVAL_TERMINALS, 'pngcairo') > 0) {\n"
         "  set terminal pngcairo size " +
         std::string(size) + " enhanced" + font_option +
         "\n"
         "} else {\n"
         "  set terminal png size " +
         std::string(size) + " enhanced\n}\n";
}

void require_plot_terminal(const std::filesystem::path& gnuplot, PlotFormat format, const std::string& flag) {
  if (format != PlotFormat::pdf) return;
  ScratchFile script(".gp");
  std::fputs("print GPVAL_TERMINALS\n", script.stream());
  script.close();
  ScratchFile log(".log");
  log.close();
  const int status = run_program(gnuplot, script.path(), log.path());
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    throw EnvironmentError(flag + ": gnuplot (" + gnuplot.string() +
                           ") cannot list its terminals: " + first_line(log.path()));
  }
  std::ifstream in(log.path());
  std::string word;
  while (in >> word) {
    if (word == "pdfcairo") return;
  }
  throw UsageError(flag, "this gnuplot (" + gnuplot.string() +
                             ") has no pdfcairo terminal, so it cannot write a PDF; write a .png or .svg instead");
}

std::string chart_number(double value) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.3g", value);
  return buffer;
}

std::string panel_x_axis_gnuplot(const std::vector<double>& values, const std::string& note) {
  // The note's label tag: one no chart here uses for another label.
  const std::string tag = "90";
  bool drawn = false;
  bool positive = true;
  for (const double value : values) {
    if (!std::isfinite(value)) continue;
    drawn = true;
    positive = positive && value > 0.0;
  }
  if (!drawn) {
    return "unset logscale x\nset xrange [0:1]\nset format x ''\nset label " + tag + " " + gnuplot_string(note) +
           " at graph 0.5, 0.5 center noenhanced\n";
  }
  return "unset label " + tag + "\nset format x '% h'\nset autoscale x\n" +
         (positive ? "set logscale x\n" : "unset logscale x\nset xrange [0:*]\n");
}

namespace {

std::string script_number(double value) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.17g", value);
  return buffer;
}

// A gnuplot string expression of several lines ('a'."\n".'b').
std::string gnuplot_lines(const std::string& first, const std::vector<std::string>& more) {
  std::string out = gnuplot_string(first);
  for (const std::string& line : more) out += ".\"\\n\"." + gnuplot_string(line);
  return out;
}

// Writes `input` to scratch files and runs gnuplot on them; the script
// names the data file as `data`.
void render(const std::filesystem::path& gnuplot, const std::function<GnuplotInput(const std::filesystem::path&)>& make,
            const std::filesystem::path& output, const std::string& flag) {
  ScratchFile data(".dat");
  const GnuplotInput input = make(data.path());
  std::fputs(input.data.c_str(), data.stream());
  data.close();
  ScratchFile script(".gp");
  std::fputs(input.script.c_str(), script.stream());
  script.close();
  render_gnuplot_script(gnuplot, script.path(), output, flag);
}

}  // namespace

GnuplotInput energy_curve_gnuplot(const CycleSummary& summary, const EnergyPlotStyle& style,
                                  const std::filesystem::path& data_path, const std::filesystem::path& output) {
  const double threshold = style.zero_threshold;
  const bool clamp = threshold > 0.0;
  GnuplotInput out;
  int drawable = 0;
  int failed = 0;
  int jumped = 0;
  int below = 0;
  double highest = -std::numeric_limits<double>::infinity();
  for (const CycleSample& sample : summary.samples) {
    if (!std::isfinite(sample.energy)) continue;  // nothing to draw for it
    double energy = sample.energy;
    if (clamp && energy < threshold) {
      // Round-off of a zero: on the threshold (log axis) or at 0 (linear).
      energy = style.log_scale ? threshold : 0.0;
      ++below;
    } else if (style.log_scale && !(energy > 0.0)) {
      continue;  // without a threshold a log axis cannot show it
    }
    highest = std::max(highest, energy);
    const int marker = sample.status == SampleStatus::failed ? 1 : sample.status == SampleStatus::branch_jump ? 2 : 0;
    failed += marker == 1;
    jumped += marker == 2;
    ++drawable;
    const double theta_deg = style.theta0_deg + (sample.theta_in - style.theta0) * kDegreesPerRadian;
    char line[96];
    std::snprintf(line, sizeof line, "%.17g %.17g %d\n", theta_deg, energy, marker);
    out.data += line;
  }
  if (drawable == 0) throw EnvironmentError("--plot: no sample has a finite energy; nothing to plot");

  const std::string data_name = gnuplot_string(data_path.string());
  std::string& gp = out.script;
  gp += gnuplot_terminal(style.format, 960, 600 + 20 * static_cast<int>(style.notes.size()));
  gp += "set output " + gnuplot_string(output.string()) + "\n";
  gp += "set title " + gnuplot_lines(style.title, style.notes) + " noenhanced\n";
  gp += "set xlabel 'input angle theta_" + std::to_string(style.input_joint + 1) + " [deg]'\n";
  gp += "set ylabel 'cycle energy E / (k_a L^2)'\n";
  gp += "set grid\nset key outside bottom center horizontal\nset autoscale xfix\n";
  const bool all_zero = clamp && highest <= threshold;
  if (style.log_scale) {
    gp += "set logscale y\nset format y '10^{%L}'\n";
    // A decade below the threshold, so that the line and the zeros on it
    // stay inside the frame; two above when nothing rises over it.
    if (clamp) {
      gp += "set yrange [" + script_number(threshold / 10.0) + ":" +
            (all_zero ? script_number(threshold * 100.0) : "*") + "]\n";
    }
  } else if (all_zero) {
    // A flat zero curve, and the threshold line above it.
    gp += "set yrange [" + script_number(-0.25 * threshold) + ":" + script_number(2.0 * threshold) + "]\n";
  }
  std::string energy_title = "energy";
  if (below > 0) {
    energy_title += " (" + std::to_string(below) + " of " + std::to_string(drawable) +
                    " samples below the threshold: " + (style.log_scale ? "drawn on it)" : "drawn at 0)");
  }
  gp += "plot " + data_name + " using 1:2 with linespoints pt 7 ps 0.5 lw 1.5 lc rgb '#0072b2' title " +
        gnuplot_string(energy_title) + " noenhanced";
  if (clamp) {
    std::string threshold_title = "zero threshold " + chart_number(threshold);
    if (!style.threshold_source.empty()) threshold_title += " (" + style.threshold_source + ")";
    gp += ", \\\n  " + script_number(threshold) + " with lines dt 2 lw 1.5 lc rgb '#d55e00' title " +
          gnuplot_string(threshold_title) + " noenhanced";
  }
  if (failed > 0) {
    gp += ", \\\n  " + data_name +
          " using 1:($3 == 1 ? $2 : 1/0) with points pt 6 ps 1.6 lc rgb '#cc79a7' title 'failed solve'";
  }
  if (jumped > 0) {
    gp += ", \\\n  " + data_name +
          " using 1:($3 == 2 ? $2 : 1/0) with points pt 4 ps 1.6 lc rgb '#009e73' title 'branch jump'";
  }
  gp += "\nunset output\n";
  return out;
}

void plot_energy_curve(const std::filesystem::path& gnuplot, const CycleSummary& summary, const EnergyPlotStyle& style,
                       const std::filesystem::path& output) {
  render(
      gnuplot, [&](const std::filesystem::path& data) { return energy_curve_gnuplot(summary, style, data, output); },
      output, "--plot");
}

GnuplotInput minima_histogram_gnuplot(const std::map<int, std::int64_t>& decades, std::int64_t exact_zeros,
                                      double zero_threshold, PlotFormat format, const std::filesystem::path& data_path,
                                      const std::filesystem::path& output) {
  const bool clamp = zero_threshold > 0.0 && std::isfinite(zero_threshold);
  // Decade d holds [10^d, 10^(d+1)); those wholly below the threshold's
  // decade are zeros, one bar just below it.
  const int zero_decade = clamp ? static_cast<int>(std::floor(std::log10(zero_threshold))) - 1 : 0;
  GnuplotInput out;
  std::int64_t zeros = clamp ? exact_zeros : 0;
  int lowest = std::numeric_limits<int>::max();
  int highest = std::numeric_limits<int>::min();
  for (const auto& [decade, count] : decades) {
    if (clamp && decade <= zero_decade) {
      zeros += count;
      continue;
    }
    out.data += std::to_string(decade) + " " + std::to_string(count) + " 0\n";
    lowest = std::min(lowest, decade);
    highest = std::max(highest, decade);
  }
  if (zeros > 0) {
    out.data += std::to_string(zero_decade) + " " + std::to_string(zeros) + " 1\n";
    lowest = std::min(lowest, zero_decade);
    highest = std::max(highest, zero_decade);
  }
  if (out.data.empty()) throw EnvironmentError("--plot: no start has an energy; no histogram to draw");

  std::string& gp = out.script;
  gp += gnuplot_terminal(format, 900, 540);
  gp += "set output " + gnuplot_string(output.string()) + "\n";
  gp += "set title 'log10 of the cycle energy minimum E_mean of every start' noenhanced\n";
  gp += "set xlabel 'log10(E_mean), E / (k_a L^2)' noenhanced\n";
  gp += "set ylabel 'starts'\nset style fill solid 0.7 border -1\nset boxwidth 0.9\nset grid ytics\n";
  gp += "set key outside bottom center horizontal\n";
  gp += "set xrange [" + std::to_string(lowest) + ":" + std::to_string(highest + 1) + "]\n";
  // Decade tics at the bars' edges; the zero bar has its own name.
  std::string tics;
  for (int d = lowest; d <= highest + 1; ++d) {
    // The zero bar's right edge is the threshold's dashed line: no tic there to crowd the bar's name.
    if (clamp && d <= zero_decade + (zeros > 0 ? 1 : 0)) continue;
    tics += (tics.empty() ? "" : ", ") + std::string("'") + std::to_string(d) + "' " + std::to_string(d);
  }
  if (zeros > 0) tics += (tics.empty() ? "" : ", ") + std::string("'zero' ") + script_number(zero_decade + 0.5);
  gp += "set xtics (" + tics + ")\n";
  if (clamp) {
    const double x = std::log10(zero_threshold);
    gp += "set arrow from " + script_number(x) + ", graph 0 to " + script_number(x) +
          ", graph 1 nohead dt 2 lw 2 lc rgb '#d55e00' front\n";
  }
  const std::string data_name = gnuplot_string(data_path.string());
  gp +=
      "plot " + data_name + " using ($3 == 0 ? $1 + 0.5 : 1/0):2 with boxes lc rgb '#0072b2' title 'starts per decade'";
  if (zeros > 0) {
    gp += ", \\\n  " + data_name + " using ($3 == 1 ? $1 + 0.5 : 1/0):2 with boxes lc rgb '#009e73' title " +
          gnuplot_string("zero: E_mean below the threshold (" + std::to_string(zeros) + " starts, " +
                         std::to_string(exact_zeros) + " exactly 0)") +
          " noenhanced";
  }
  if (clamp) {
    gp += ", \\\n  keyentry with lines dt 2 lw 2 lc rgb '#d55e00' title " +
          gnuplot_string("zero threshold " + chart_number(zero_threshold)) + " noenhanced";
  }
  gp += "\nunset output\n";
  return out;
}

void plot_minima_histogram(const std::filesystem::path& gnuplot, const std::map<int, std::int64_t>& decades,
                           std::int64_t exact_zeros, double zero_threshold, PlotFormat format,
                           const std::filesystem::path& output, const std::string& flag) {
  render(
      gnuplot,
      [&](const std::filesystem::path& data) {
        return minima_histogram_gnuplot(decades, exact_zeros, zero_threshold, format, data, output);
      },
      output, flag);
}

void plot_motion(const std::filesystem::path& gnuplot, const MotionAnalysis& motion, const std::string& title,
                 PlotFormat format, const std::filesystem::path& output) {
  if (motion.circuits.empty() || motion.circuits.front().points.empty()) {
    throw EnvironmentError("--plot: the loop has no circuit; nothing to plot");
  }
  const int n = static_cast<int>(motion.circuits.front().points.front().size());
  // One block per circuit (two blank lines apart: gnuplot's index).
  ScratchFile data(".dat");
  for (const Circuit& c : motion.circuits) {
    for (size_t p = 0; p < c.points.size(); ++p) {
      std::fprintf(data.stream(), "%.17g", c.arclength[p]);
      for (int j = 0; j < n; ++j) std::fprintf(data.stream(), " %.17g", c.points[p][j] * kDegreesPerRadian);
      std::fputs("\n", data.stream());
    }
    std::fputs("\n\n", data.stream());
  }
  data.close();

  ScratchFile script(".gp");
  std::FILE* gp = script.stream();
  const std::string data_name = gnuplot_string(data.path().string());
  const int input = motion.input_joint + 2;  // the input's column
  std::fputs(gnuplot_terminal(format, 1400, 600).c_str(), gp);
  std::fprintf(gp, "set output %s\n", gnuplot_string(output.string()).c_str());
  std::fprintf(gp, "set multiplot layout 1,2 title %s noenhanced\n", gnuplot_string(title).c_str());
  std::fputs("set grid\nset key outside right\nset ylabel 'joint angle [deg]'\n", gp);
  // A colour per joint, a dash pattern per circuit.
  const int circuits = static_cast<int>(motion.circuits.size());
  std::fprintf(gp, "set xlabel 'input angle theta_%d [deg]'\n", motion.input_joint + 1);
  std::fputs("curve_title(c, j) = c == 0 ? sprintf('theta_%d', j-1) : (j == 2 ? sprintf('circuit %d', c+1) : '')\n",
             gp);
  const char* plot =
      "plot for [c=0:%d] for [j=2:%d] %s index c using %s:j with lines lw 1.5 lc (j-1) dt 1+c%%5 title (curve_title(c, "
      "j))\n";
  std::fprintf(gp, plot, circuits - 1, n + 1, data_name.c_str(), std::to_string(input).c_str());
  std::fputs("set xlabel 'arclength in joint space [rad]'\n", gp);
  std::fprintf(gp, plot, circuits - 1, n + 1, data_name.c_str(), "1");
  std::fputs("unset multiplot\nunset output\n", gp);
  script.close();
  render_gnuplot_script(gnuplot, script.path(), output, "--plot");
}

void render_gnuplot_script(const std::filesystem::path& gnuplot, const std::filesystem::path& script,
                           const std::filesystem::path& output, const std::string& flag) {
  ScratchFile log(".log");
  log.close();
  const int status = run_program(gnuplot, script, log.path());
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    const std::string message = first_line(log.path());
    const std::string how = WIFEXITED(status) ? "exit code " + std::to_string(WEXITSTATUS(status))
                                              : "signal " + std::to_string(WTERMSIG(status));
    throw EnvironmentError(flag + ": gnuplot failed (" + how + ")" + (message.empty() ? "" : ": " + message));
  }
  std::error_code ec;
  const auto size = std::filesystem::file_size(output, ec);
  if (ec || size == 0) throw EnvironmentError(flag + ": gnuplot exited normally but wrote no image");
}

}  // namespace loopfarm::cli
