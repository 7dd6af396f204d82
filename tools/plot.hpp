// Plots through gnuplot, run as a separate program: the energy curve of a
// cycle, and the input-output curves of a loop's motion, as PNGs.
#pragma once

#include <filesystem>
#include <string>
#include <string_view>

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

struct EnergyPlotStyle {
  std::string title;       // plain text, one line
  bool log_scale = false;  // logarithmic energy axis
  // The x axis shows theta0_deg + (theta_in - theta0) in degrees, so that
  // the start angle appears exactly as the user gave it.
  double theta0_deg = 0.0;
  double theta0 = 0.0;  // [rad]
};

// Draws energy against input angle [deg] into `png` (overwritten). Failed and
// branch-jumping samples are marked. On a logarithmic axis, energies below
// kLogFloor (including exact zeros, which a log axis cannot show) are drawn
// at kLogFloor. Throws EnvironmentError if gnuplot fails or writes nothing,
// with gnuplot's first error line.
inline constexpr double kLogFloor = 1e-32;
void plot_energy_curve(const std::filesystem::path& gnuplot, const CycleSummary& summary, const EnergyPlotStyle& style,
                       const std::filesystem::path& png);

// Draws every circuit's joint angles [deg, unwrapped along the circuit]
// against the input angle (left) and against arclength (right) into `png`.
// Throws EnvironmentError as plot_energy_curve does.
void plot_motion(const std::filesystem::path& gnuplot, const MotionAnalysis& motion, const std::string& title,
                 const std::filesystem::path& png);

// Runs gnuplot on a finished script that writes `png`. Throws
// EnvironmentError naming `flag` if gnuplot fails (with its first error line)
// or writes nothing.
void render_gnuplot_script(const std::filesystem::path& gnuplot, const std::filesystem::path& script,
                           const std::filesystem::path& png, const std::string& flag);

}  // namespace loopfarm::cli
