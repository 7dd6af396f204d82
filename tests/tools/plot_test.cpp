// The charts' gnuplot input (tools/plot.cpp): the format a path asks for,
// the terminal that writes it, a zero curve clamped at the zero threshold
// with the threshold drawn, the minima histogram's zero bar and labels, and
// the files gnuplot writes from them (by their first bytes).
#include "plot.hpp"

#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>
#include <vector>

#include "cli_support.hpp"

namespace loopfarm::cli {
namespace {

// The second column of every data line.
std::vector<double> drawn_energies(const std::string& data) {
  std::vector<double> energies;
  std::istringstream in(data);
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream fields(line);
    double theta = 0.0, energy = 0.0;
    fields >> theta >> energy;
    energies.push_back(energy);
  }
  return energies;
}

// A cycle whose energies are `energies`, one sample a degree.
CycleSummary cycle_of(const std::vector<double>& energies) {
  CycleSummary cycle;
  for (size_t i = 0; i < energies.size(); ++i) {
    CycleSample sample;
    sample.theta_in = static_cast<double>(i) * 3.14159265358979323846 / 180.0;
    sample.energy = energies[i];
    sample.status = SampleStatus::converged;
    cycle.samples.push_back(sample);
  }
  return cycle;
}

// The script's lines that contain `text`.
std::vector<std::string> lines_with(const std::string& script, const std::string& text) {
  std::vector<std::string> found;
  std::istringstream in(script);
  std::string line;
  while (std::getline(in, line)) {
    if (line.find(text) != std::string::npos) found.push_back(line);
  }
  return found;
}

std::string read_bytes(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

TEST(PlotFormat, TheExtensionPicksTheFormat) {
  EXPECT_EQ(plot_format("curve.png", "--plot"), PlotFormat::png);
  EXPECT_EQ(plot_format("dir/curve.PNG", "--plot"), PlotFormat::png);
  EXPECT_EQ(plot_format("curve.svg", "--plot"), PlotFormat::svg);
  EXPECT_EQ(plot_format("curve.pdf", "--plot"), PlotFormat::pdf);
  EXPECT_EQ(plot_format("-", "--plot"), PlotFormat::png);  // standard output
}

TEST(PlotFormat, AnyOtherNameIsRefusedNamingTheFlagAndTheExtensions) {
  for (const char* name : {"curve.txt", "curve", "curve.png.bak", "curve.jpg"}) {
    try {
      (void)plot_format(name, "--plot");
      ADD_FAILURE() << name << " was accepted";
    } catch (const UsageError& error) {
      const std::string message = error.what();
      EXPECT_EQ(message.rfind("--plot: ", 0), 0u) << message;
      EXPECT_NE(message.find(".png, .svg or .pdf"), std::string::npos) << message;
      EXPECT_NE(message.find(name), std::string::npos) << message;
    }
  }
}

TEST(PlotFormat, EachFormatHasItsTerminal) {
  EXPECT_NE(gnuplot_terminal(PlotFormat::png, 960, 600).find("set terminal pngcairo size 960,600"), std::string::npos);
  EXPECT_NE(gnuplot_terminal(PlotFormat::svg, 960, 600).find("set terminal svg size 960,600"), std::string::npos);
  EXPECT_NE(gnuplot_terminal(PlotFormat::pdf, 960, 600).find("set terminal pdfcairo size 9.6in,6in"),
            std::string::npos);
  // No terminal for one format writes another.
  EXPECT_EQ(gnuplot_terminal(PlotFormat::svg, 960, 600).find("png"), std::string::npos);
  EXPECT_EQ(gnuplot_terminal(PlotFormat::pdf, 960, 600).find("set terminal png"), std::string::npos);
}

TEST(EnergyCurve, RoundOffOfAZeroIsDrawnOnTheThresholdOfALogAxis) {
  const CycleSummary zero = cycle_of({0.0, 1e-32, 3e-28, 6e-31, 1e-27});
  EnergyPlotStyle style;
  style.log_scale = true;
  style.zero_threshold = 1e-12;
  style.threshold_source = "run 1's";
  const GnuplotInput input = energy_curve_gnuplot(zero, style, "/tmp/d.dat", "/tmp/out.png");
  const std::vector<double> drawn = drawn_energies(input.data);
  ASSERT_EQ(drawn.size(), 5u);  // the exact zero too
  for (double e : drawn) EXPECT_EQ(e, 1e-12);
  // The threshold is a labelled line, and the axis starts a decade below it.
  EXPECT_EQ(lines_with(input.script, "'zero threshold 1e-12 (run 1''s)'").size(), 1u) << input.script;
  EXPECT_EQ(lines_with(input.script, "set yrange [1e-13:").size(), 1u) << input.script;
  EXPECT_NE(input.script.find("5 of 5 samples below the threshold: drawn on it"), std::string::npos);
}

TEST(EnergyCurve, AZeroCurveOnALinearAxisIsFlatAtZero) {
  const CycleSummary zero = cycle_of({1e-32, 3e-28, 6e-31});
  EnergyPlotStyle style;
  style.zero_threshold = 1e-12;
  const GnuplotInput input = energy_curve_gnuplot(zero, style, "/tmp/d.dat", "/tmp/out.png");
  for (double e : drawn_energies(input.data)) EXPECT_EQ(e, 0.0);
  // A range around [0, threshold], not one autoscaled to the round-off.
  EXPECT_EQ(lines_with(input.script, "set yrange [-2.4999999999999999e-13:2e-12]").size(), 1u) << input.script;
  EXPECT_EQ(lines_with(input.script, "zero threshold 1e-12").size(), 1u) << input.script;
}

TEST(EnergyCurve, EnergiesAboveTheThresholdAreDrawnAsTheyAre) {
  const CycleSummary curve = cycle_of({1e-5, 2e-13, 4e-3});
  EnergyPlotStyle style;
  style.log_scale = true;
  style.zero_threshold = 1e-12;
  const std::vector<double> drawn = drawn_energies(energy_curve_gnuplot(curve, style, "d", "o.png").data);
  EXPECT_EQ(drawn, (std::vector<double>{1e-5, 1e-12, 4e-3}));
}

TEST(EnergyCurve, NotesAndTitleAreNotEnhancedText) {
  EnergyPlotStyle style;
  style.title = "candidate 3 (bricard_line_symmetric)";
  style.notes = {"E_mean 1.93e-33 as stored (the table's value); this curve: E_mean 6.27e-31"};
  const GnuplotInput input = energy_curve_gnuplot(cycle_of({1.0, 2.0}), style, "d", "o.svg");
  const std::vector<std::string> title = lines_with(input.script, "set title");
  ASSERT_EQ(title.size(), 1u);
  EXPECT_NE(title[0].find("'E_mean 1.93e-33 as stored"), std::string::npos) << title[0];
  EXPECT_NE(title[0].find("noenhanced"), std::string::npos) << title[0];
  // The key sits below the plot, off the data.
  EXPECT_EQ(lines_with(input.script, "set key outside bottom").size(), 1u) << input.script;
}

TEST(MinimaHistogram, DecadesBelowTheThresholdAreOneZeroBar) {
  const std::map<int, std::int64_t> decades = {{-33, 5}, {-30, 2}, {-13, 1}, {-12, 4}, {-5, 3}};
  const GnuplotInput input = minima_histogram_gnuplot(decades, 7, 1e-12, PlotFormat::png, "d.dat", "h.png");
  // -12 (1e-12 <= E < 1e-11) is not wholly below the threshold; the rest
  // below it and the exact zeros are one bar at -13.
  EXPECT_EQ(input.data, "-12 4 0\n-5 3 0\n-13 15 1\n");
  EXPECT_NE(input.script.find("15 starts, 7 exactly 0"), std::string::npos) << input.script;
  EXPECT_EQ(lines_with(input.script, "set arrow from -12, graph 0").size(), 1u) << input.script;
  // The zero bar's tic names it, at the bar's middle.
  EXPECT_EQ(lines_with(input.script, "'zero' -12.5)").size(), 1u) << input.script;
  EXPECT_EQ(lines_with(input.script, "zero threshold 1e-12").size(), 1u) << input.script;
}

TEST(MinimaHistogram, LabelsWithUnderscoresAreNotEnhancedText) {
  const GnuplotInput input = minima_histogram_gnuplot({{-3, 1}}, 0, 1e-12, PlotFormat::svg, "d.dat", "h.svg");
  const std::vector<std::string> labels = lines_with(input.script, "E_mean");
  ASSERT_FALSE(labels.empty());
  for (const std::string& line : labels) EXPECT_NE(line.find("noenhanced"), std::string::npos) << line;
  EXPECT_EQ(lines_with(input.script, "set xlabel 'log10(E_mean), E / (k_a L^2)' noenhanced").size(), 1u);
}

// A panel's x axis: logarithmic while every value on it is positive, linear
// from 0 with a value of 0, and empty with a note when nothing is drawn.
TEST(PanelAxis, LogarithmicOnlyWhileEveryDrawnValueIsPositive) {
  const double nan = std::nan("");
  const std::string positive = panel_x_axis_gnuplot({0.5, 42.0, nan}, "empty");
  EXPECT_EQ(lines_with(positive, "set logscale x").size(), 1u) << positive;
  EXPECT_EQ(lines_with(positive, "unset logscale x").size(), 0u) << positive;
  EXPECT_EQ(lines_with(positive, "unset label 90").size(), 1u) << positive;
  for (const std::vector<double>& values : {std::vector<double>{0.0, 42.0}, std::vector<double>{-1.0, nan}}) {
    const std::string linear = panel_x_axis_gnuplot(values, "empty");
    EXPECT_EQ(lines_with(linear, "unset logscale x").size(), 1u) << linear;
    EXPECT_EQ(lines_with(linear, "set xrange [0:*]").size(), 1u) << linear;
    EXPECT_EQ(lines_with(linear, "set label 90 '").size(), 0u) << linear;
  }
  for (const std::vector<double>& values :
       {std::vector<double>{}, std::vector<double>{nan, nan}, std::vector<double>{INFINITY}}) {
    const std::string empty = panel_x_axis_gnuplot(values, "nothing to draw: it's so");
    EXPECT_EQ(lines_with(empty, "unset logscale x").size(), 1u) << empty;
    EXPECT_EQ(lines_with(empty, "set xrange [0:1]").size(), 1u) << empty;
    EXPECT_EQ(lines_with(empty, "set label 90 'nothing to draw: it''s so' at graph 0.5, 0.5 center noenhanced").size(),
              1u)
        << empty;
  }
}

// Three panels with a logarithmic y axis, one per kind of x axis, drawn by
// gnuplot: none fails, the empty one carries its note.
TEST(PanelAxis, GnuplotDrawsEveryKindOfPanel) {
  const std::filesystem::path gnuplot = require_gnuplot("--plot");
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("plot_test_panels_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::filesystem::path data = dir / "d.dat";
  std::ofstream(data) << "0.5 1 NaN 0\n42 10 NaN 3\n";
  const std::filesystem::path output = dir / "panels.svg";
  std::string script = gnuplot_terminal(PlotFormat::svg, 900, 300) + "set output " + gnuplot_string(output.string()) +
                       "\nset multiplot layout 1,3\nset logscale y\nset yrange [0.1:100]\n";
  const std::vector<std::pair<int, std::vector<double>>> panels = {
      {1, {0.5, 42.0}}, {4, {0.0, 3.0}}, {3, {std::nan(""), std::nan("")}}};
  for (const auto& [column, values] : panels) {
    script += panel_x_axis_gnuplot(values, "no value in column " + std::to_string(column)) + "plot 1/0 notitle, " +
              gnuplot_string(data.string()) + " using " + std::to_string(column) + ":2 with points notitle\n";
  }
  script += "unset multiplot\nunset output\n";
  const std::filesystem::path script_path = dir / "panels.gp";
  std::ofstream(script_path) << script;
  EXPECT_NO_THROW(render_gnuplot_script(gnuplot, script_path, output, "--plot")) << script;
  const std::string svg = read_bytes(output);
  EXPECT_NE(svg.find("no value in column 3"), std::string::npos);
  EXPECT_EQ(svg.find("no value in column 1"), std::string::npos);
  std::filesystem::remove_all(dir);
}

// What gnuplot writes, by its first bytes, for each extension.
TEST(PlotFiles, GnuplotWritesTheFormatTheExtensionNames) {
  const std::filesystem::path gnuplot = find_program("gnuplot");
  if (gnuplot.empty()) GTEST_SKIP() << "gnuplot is not installed";
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("plot_test_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const CycleSummary zero = cycle_of({1e-32, 3e-28, 6e-31, 2e-30});
  for (const char* name : {"curve.png", "curve.svg", "curve.pdf"}) {
    EnergyPlotStyle style;
    style.title = "a zero curve";
    style.log_scale = true;
    style.format = plot_format(dir / name, "--plot");
    if (style.format == PlotFormat::pdf &&
        std::system(("\"" + gnuplot.string() + "\" -e \"set terminal\" 2>&1 | grep -q pdfcairo").c_str()) != 0) {
      continue;  // this gnuplot has no pdfcairo
    }
    plot_energy_curve(gnuplot, zero, style, dir / name);
    const std::string bytes = read_bytes(dir / name);
    ASSERT_GT(bytes.size(), 100u) << name;
    if (style.format == PlotFormat::png) {
      EXPECT_EQ(bytes.substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8));
    } else if (style.format == PlotFormat::svg) {
      EXPECT_EQ(bytes.substr(0, 5), "<?xml");
      EXPECT_NE(bytes.find("<svg"), std::string::npos);
    } else if (style.format == PlotFormat::pdf) {
      EXPECT_EQ(bytes.substr(0, 5), "%PDF-");
    }
  }
  const std::filesystem::path histogram = dir / "h.svg";
  plot_minima_histogram(gnuplot, {{-31, 4}, {-3, 2}}, 1, 1e-12, PlotFormat::svg, histogram, "--plot");
  EXPECT_NE(read_bytes(histogram).find("<svg"), std::string::npos);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace loopfarm::cli
