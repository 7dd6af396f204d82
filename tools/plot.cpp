#include "plot.hpp"

#include <fcntl.h>
#include <spawn.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
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

void plot_energy_curve(const std::filesystem::path& gnuplot, const CycleSummary& summary, const EnergyPlotStyle& style,
                       const std::filesystem::path& png) {
  // The data: input angle [deg], energy as drawn, and a marker class
  // (0 solved, 1 failed, 2 branch jump) for the points to highlight.
  ScratchFile data(".dat");
  int drawable = 0;
  int failed = 0;
  int jumped = 0;
  bool floored = false;
  for (const CycleSample& sample : summary.samples) {
    if (!std::isfinite(sample.energy)) continue;  // nothing to draw for it
    double energy = sample.energy;
    if (style.log_scale && !(energy >= kLogFloor)) {
      energy = kLogFloor;
      floored = true;
    }
    const int marker = sample.status == SampleStatus::failed ? 1 : sample.status == SampleStatus::branch_jump ? 2 : 0;
    failed += marker == 1;
    jumped += marker == 2;
    ++drawable;
    const double theta_deg = style.theta0_deg + (sample.theta_in - style.theta0) * kDegreesPerRadian;
    std::fprintf(data.stream(), "%.17g %.17g %d\n", theta_deg, energy, marker);
  }
  data.close();
  if (drawable == 0) throw EnvironmentError("--plot: no sample has a finite energy; nothing to plot");

  ScratchFile script(".gp");
  std::FILE* gp = script.stream();
  const std::string data_name = gnuplot_string(data.path().string());
  // pngcairo draws antialiased text and lines; Debian's gnuplot-nox has it,
  // but fall back to the libgd png terminal should a build lack cairo.
  std::fputs(
      "if (strstrt(GPVAL_TERMINALS, 'pngcairo') > 0) {\n"
      "  set terminal pngcairo size 960,600 enhanced\n"
      "} else {\n"
      "  set terminal png size 960,600 enhanced\n"
      "}\n",
      gp);
  std::fprintf(gp, "set output %s\n", gnuplot_string(png.string()).c_str());
  std::fprintf(gp, "set title %s noenhanced\n", gnuplot_string(style.title).c_str());
  std::fputs("set xlabel 'input angle theta_1 [deg]'\n", gp);
  std::fputs("set ylabel 'cycle energy E / (k_a L^2)'\n", gp);
  std::fputs("set grid\nset key top right\nset autoscale xfix\n", gp);
  if (style.log_scale) {
    std::fputs("set logscale y\nset format y '10^{%L}'\n", gp);
  }
  std::string energy_title = "energy";
  if (floored) {
    char buffer[96];
    std::snprintf(buffer, sizeof buffer, "energy (values below %.0e drawn at %.0e)", kLogFloor, kLogFloor);
    energy_title = buffer;
  }
  std::fprintf(gp, "plot %s using 1:2 with linespoints pt 7 ps 0.5 lw 1.5 lc rgb '#1f5fa8' title %s noenhanced",
               data_name.c_str(), gnuplot_string(energy_title).c_str());
  if (failed > 0) {
    std::fprintf(gp,
                 ", \\\n  %s using 1:($3 == 1 ? $2 : 1/0) with points pt 6 ps 1.6 lc rgb '#c0392b' "
                 "title 'failed solve'",
                 data_name.c_str());
  }
  if (jumped > 0) {
    std::fprintf(gp,
                 ", \\\n  %s using 1:($3 == 2 ? $2 : 1/0) with points pt 4 ps 1.6 lc rgb '#d68910' "
                 "title 'branch jump'",
                 data_name.c_str());
  }
  std::fputs("\nunset output\n", gp);
  script.close();
  render_gnuplot_script(gnuplot, script.path(), png, "--plot");
}

void plot_motion(const std::filesystem::path& gnuplot, const MotionAnalysis& motion, const std::string& title,
                 const std::filesystem::path& png) {
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
  std::fputs(
      "if (strstrt(GPVAL_TERMINALS, 'pngcairo') > 0) {\n"
      "  set terminal pngcairo size 1400,600 enhanced\n"
      "} else {\n"
      "  set terminal png size 1400,600 enhanced\n"
      "}\n",
      gp);
  std::fprintf(gp, "set output %s\n", gnuplot_string(png.string()).c_str());
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
  render_gnuplot_script(gnuplot, script.path(), png, "--plot");
}

void render_gnuplot_script(const std::filesystem::path& gnuplot, const std::filesystem::path& script,
                           const std::filesystem::path& png, const std::string& flag) {
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
  const auto size = std::filesystem::file_size(png, ec);
  if (ec || size == 0) throw EnvironmentError(flag + ": gnuplot exited normally but wrote no image");
}

}  // namespace loopfarm::cli
