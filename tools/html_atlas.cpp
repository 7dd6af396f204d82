#include "html_atlas.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <set>
#include <span>
#include <string_view>

#include <nlohmann/json.hpp>

#include "atlas.hpp"
#include "candidate_display.hpp"
#include "loopfarm/core/motion.hpp"
#include "loopfarm/search/verify.hpp"

namespace loopfarm::cli {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDegreesPerRadian = 180.0 / kPi;
// Poses embedded per representative: every 3 deg of a full turn, which the
// page interpolates linearly between.
constexpr int kMotionFrames = 120;
// Decimals of the embedded coordinates (the canonical geometry has L = 1).
constexpr int kCoordinateDecimals = 5;
// A zero threshold no run states (a database without runs): the job file's default.
constexpr double kDefaultZeroThreshold = 1e-12;

std::string html_escape(std::string_view text) {
  std::string out;
  for (char c : text) {
    switch (c) {
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '&':
        out += "&amp;";
        break;
      case '"':
        out += "&quot;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

std::string g(double v, int digits = 4) { return format_significant(v, digits); }

// 1e-20 as "1e-20", 2.5e-12 as "2.5e-12".
std::string energy_text(double v) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.3g", v);
  return buffer;
}

// The double nearest to v rounded to `decimals` decimals, which JSON then
// prints in as few digits (the quotient of two exact integers is correctly
// rounded); -0 as 0.
double rounded(double v, int decimals = kCoordinateDecimals) {
  const double scale = std::pow(10.0, decimals);
  return std::round(v * scale) / scale + 0.0;
}

// The zero threshold of the run that first found a candidate; the smallest of
// every run's when that run is not there; the job default without runs.
double zero_threshold_of(const std::vector<RunRow>& runs, std::optional<std::int64_t> run) {
  double smallest = kNaN;
  for (const RunRow& r : runs) {
    if (!std::isfinite(r.zero_threshold) || r.zero_threshold <= 0.0) continue;
    if (run && r.run_id == *run) return r.zero_threshold;
    if (!(r.zero_threshold >= smallest)) smallest = r.zero_threshold;
  }
  return std::isfinite(smallest) ? smallest : kDefaultZeroThreshold;
}

// --- the summary ------------------------------------------------------------------

std::string summary_html(const ResultsDatabase& db, const HtmlSelection& selection) {
  const std::vector<RunRow> runs = db.runs();
  const StartCounts c = db.start_counts(selection.run);
  std::string out =
      "<h2 id=\"summary\">Run summary</h2>\n<table class=\"data\">\n<tr><th>run</th><th>job</th>"
      "<th>seed</th><th>slice</th><th>starts done</th><th>starts</th><th>status</th><th>where</th>"
      "<th>zero threshold</th><th>started</th><th>updated</th></tr>\n";
  for (const RunRow& r : runs) {
    const std::string where = r.merged_inputs > 0 ? "merged from " + std::to_string(r.merged_inputs) + " databases"
                                                  : count_of(r.ranks, "rank");
    out += "<tr><td>" + std::to_string(r.run_id) + "</td><td><code>" + html_escape(r.job_path) + "</code></td><td>" +
           std::to_string(r.seed) + "</td><td>" + (r.slice ? to_string(*r.slice) : "") + "</td><td>" +
           std::to_string(r.starts_done) + "</td><td>" + std::to_string(r.starts) + "</td><td>" +
           html_escape(r.status) + "</td><td>" + where + "</td><td>" + energy_text(r.zero_threshold) + "</td><td>" +
           html_escape(r.started_at) + "</td><td>" + html_escape(r.updated_at) + "</td></tr>\n";
  }
  out += "</table>\n";
  char buffer[256];
  std::snprintf(buffer, sizeof buffer,
                "<p>Starts %lld, zero minima %lld, verified %lld, mean %.4g s per start, %.4g core-seconds%s.</p>\n",
                static_cast<long long>(c.starts), static_cast<long long>(c.zeros), static_cast<long long>(c.verified),
                c.mean_seconds, c.total_seconds,
                selection.run ? (" (run " + std::to_string(*selection.run) + ")").c_str() : "");
  out += buffer;
  out += "<div class=\"row\"><table class=\"data\"><tr><th>status</th><th>starts</th></tr>\n";
  for (const StatusCount& s : db.status_counts(selection.run)) {
    out += "<tr><td>" + html_escape(s.status) + "</td><td>" + std::to_string(s.starts) + "</td></tr>\n";
  }
  out +=
      "</table>\n<table class=\"data\"><tr><th>family</th><th>candidates (distinct linkages)</th>"
      "<th>hits (starts that found them)</th></tr>\n";
  for (const FamilyCount& f : db.family_counts(selection.run)) {
    out += "<tr><td>" + html_escape(f.family) + "</td><td>" + std::to_string(f.candidates) + "</td><td>" +
           std::to_string(f.hits) + "</td></tr>\n";
  }
  out += "</table></div>\n";
  return out;
}

// The histogram of log10(E_mean) over all starts, one bar per decade, with
// each run's zero threshold as a vertical line.
std::string histogram_svg(const EnergyHistogram& h, const std::vector<RunRow>& runs) {
  std::set<double> thresholds;
  for (const RunRow& r : runs) {
    if (std::isfinite(r.zero_threshold) && r.zero_threshold > 0.0) thresholds.insert(r.zero_threshold);
  }
  int lo = 0, hi = 0;
  std::int64_t most = 1;
  bool any = false;
  for (const auto& [decade, count] : h.decades) {
    lo = any ? std::min(lo, decade) : decade;
    hi = any ? std::max(hi, decade + 1) : decade + 1;
    most = std::max(most, count);
    any = true;
  }
  for (double t : thresholds) {
    const int d = static_cast<int>(std::floor(std::log10(t)));
    lo = any ? std::min(lo, d) : d;
    hi = any ? std::max(hi, d + 1) : d + 1;
    any = true;
  }
  if (!any) lo = -1, hi = 0;
  constexpr double kWidth = 760, kHeight = 260, kLeft = 56, kRight = 16, kTop = 16, kBottom = 44;
  const double plot_w = kWidth - kLeft - kRight, plot_h = kHeight - kTop - kBottom;
  auto x_of = [&](double log10e) { return kLeft + (log10e - lo) / (hi - lo) * plot_w; };
  auto y_of = [&](double count) { return kTop + plot_h * (1.0 - count / static_cast<double>(most)); };
  char b[512];
  std::string svg;
  std::snprintf(b, sizeof b,
                "<svg class=\"chart\" width=\"%.0f\" height=\"%.0f\" viewBox=\"0 0 %.0f %.0f\" role=\"img\" "
                "aria-label=\"histogram of log10 of all minima\">\n",
                kWidth, kHeight, kWidth, kHeight);
  svg += b;
  std::snprintf(b, sizeof b,
                "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" class=\"axis\"/><line x1=\"%.1f\" y1=\"%.1f\" "
                "x2=\"%.1f\" y2=\"%.1f\" class=\"axis\"/>\n",
                kLeft, kTop + plot_h, kLeft + plot_w, kTop + plot_h, kLeft, kTop, kLeft, kTop + plot_h);
  svg += b;
  const int step = std::max(1, (hi - lo + 11) / 12);
  for (int d = lo; d <= hi; d += step) {
    std::snprintf(b, sizeof b,
                  "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" class=\"axis\"/><text x=\"%.1f\" y=\"%.1f\" "
                  "text-anchor=\"middle\">%d</text>\n",
                  x_of(d), kTop + plot_h, x_of(d), kTop + plot_h + 4, x_of(d), kTop + plot_h + 17, d);
    svg += b;
  }
  for (double f : {0.0, 0.5, 1.0}) {
    std::snprintf(b, sizeof b, "<text x=\"%.1f\" y=\"%.1f\" text-anchor=\"end\">%lld</text>\n", kLeft - 6,
                  y_of(f * static_cast<double>(most)) + 4, static_cast<long long>(std::llround(f * most)));
    svg += b;
  }
  for (const auto& [decade, count] : h.decades) {
    const double x0 = x_of(decade) + 1, x1 = x_of(decade + 1) - 1;
    std::snprintf(b, sizeof b,
                  "<rect class=\"bar\" x=\"%.1f\" y=\"%.1f\" width=\"%.1f\" height=\"%.1f\"><title>[%d, %d): %lld "
                  "starts</title></rect>\n",
                  x0, y_of(static_cast<double>(count)), std::max(1.0, x1 - x0), plot_h - y_of(count) + kTop, decade,
                  decade + 1, static_cast<long long>(count));
    svg += b;
  }
  for (double t : thresholds) {
    const double x = x_of(std::log10(t));
    std::snprintf(
        b, sizeof b,
        "<line class=\"threshold\" x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\"/><text class=\"threshold\" "
        "x=\"%.1f\" y=\"%.1f\">zero threshold %s</text>\n",
        x, kTop, x, kTop + plot_h, x + 4, kTop + 12, energy_text(t).c_str());
    svg += b;
  }
  std::snprintf(b, sizeof b,
                "<text x=\"%.1f\" y=\"%.1f\" text-anchor=\"middle\">log10(E_mean), E / (k_a L&#178;), every "
                "start</text>\n",
                kLeft + plot_w / 2, kHeight - 6);
  svg += b;
  svg += "</svg>\n";
  std::string notes;
  if (h.zeros) notes += "exactly 0: " + std::to_string(h.zeros) + " starts. ";
  if (h.missing) notes += "no value (the start could not be evaluated): " + std::to_string(h.missing) + " starts.";
  if (!notes.empty()) svg += "<p>" + notes + "</p>\n";
  return svg;
}

// --- one representative -------------------------------------------------------------

// The cycle energy against the input angle on a log axis, clamped below at the
// zero threshold: a verified zero is drawn on the threshold line, not as the
// decades of round-off its computed energy lies in. A cursor line (class
// "cursor") follows the page's input angle.
std::string energy_svg(const Representation& rep, double threshold, double lo_deg, double hi_deg) {
  // A sample's input angle [deg] on the chart: a full turn's folded into
  // [lo_deg, lo_deg + 360) (its cycle may start a little off 0, away from a
  // singular pose).
  const auto angle_deg = [&](const CycleSample* s) {
    const double deg = s->theta_in * kDegreesPerRadian;
    if (!rep.full_turn) return deg;
    const double turns = std::floor((deg - lo_deg) / 360.0);
    return deg - 360.0 * turns;
  };
  std::vector<const CycleSample*> samples;
  for (const CycleSample& s : rep.cycle.samples) samples.push_back(&s);
  std::sort(samples.begin(), samples.end(),
            [&](const CycleSample* x, const CycleSample* y) { return angle_deg(x) < angle_deg(y); });
  const double bottom = std::floor(std::log10(threshold));
  double top = bottom + 1;
  for (const CycleSample* s : samples) {
    if (s->status != SampleStatus::failed && std::isfinite(s->energy) && s->energy > threshold) {
      top = std::max(top, std::ceil(std::log10(s->energy)));
    }
  }
  constexpr double kWidth = 420, kHeight = 230, kLeft = 56, kRight = 12, kTop = 12, kBottom = 40;
  const double plot_w = kWidth - kLeft - kRight, plot_h = kHeight - kTop - kBottom;
  const double span = hi_deg > lo_deg ? hi_deg - lo_deg : 1.0;
  auto x_of = [&](double deg) { return kLeft + (deg - lo_deg) / span * plot_w; };
  auto y_of = [&](double log10e) { return kTop + plot_h * (1.0 - (log10e - bottom) / (top - bottom)); };
  char b[512];
  std::string svg;
  std::snprintf(b, sizeof b,
                "<svg class=\"chart energy\" width=\"%.0f\" height=\"%.0f\" viewBox=\"0 0 %.0f %.0f\" "
                "data-x0=\"%.2f\" data-x1=\"%.2f\" data-lo=\"%.6g\" data-hi=\"%.6g\" role=\"img\" "
                "aria-label=\"cycle energy\">\n",
                kWidth, kHeight, kWidth, kHeight, kLeft, kLeft + plot_w, lo_deg, hi_deg);
  svg += b;
  const int step = std::max(1, static_cast<int>((top - bottom + 5) / 6));
  for (double d = bottom; d <= top; d += step) {
    std::snprintf(b, sizeof b,
                  "<line class=\"grid\" x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\"/><text x=\"%.1f\" y=\"%.1f\" "
                  "text-anchor=\"end\">1e%.0f</text>\n",
                  kLeft, y_of(d), kLeft + plot_w, y_of(d), kLeft - 4, y_of(d) + 4, d);
    svg += b;
  }
  const double tick = span > 180 ? 90 : span > 60 ? 30 : span > 20 ? 10 : 5;
  for (double a = std::ceil(lo_deg / tick) * tick; a <= hi_deg + 1e-9; a += tick) {
    std::snprintf(b, sizeof b,
                  "<line class=\"axis\" x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\"/><text x=\"%.1f\" y=\"%.1f\" "
                  "text-anchor=\"middle\">%.0f</text>\n",
                  x_of(a), kTop + plot_h, x_of(a), kTop + plot_h + 4, x_of(a), kTop + plot_h + 16, a);
    svg += b;
  }
  const double log_threshold = std::log10(threshold);
  std::snprintf(b, sizeof b,
                "<line class=\"threshold\" x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\"/><text class=\"threshold\" "
                "x=\"%.1f\" y=\"%.1f\">zero threshold %s (energies below it drawn on it)</text>\n",
                kLeft, y_of(log_threshold), kLeft + plot_w, y_of(log_threshold), kLeft + 4, y_of(log_threshold) - 4,
                energy_text(threshold).c_str());
  svg += b;
  // The curve, broken where a sample failed.
  std::string points;
  auto flush = [&] {
    if (!points.empty()) svg += "<polyline class=\"curve\" points=\"" + points + "\"/>\n";
    points.clear();
  };
  for (const CycleSample* s : samples) {
    if (s->status == SampleStatus::failed || !std::isfinite(s->energy)) {
      flush();
      continue;
    }
    std::snprintf(b, sizeof b, "%.1f,%.1f ", x_of(angle_deg(s)), y_of(std::log10(std::max(s->energy, threshold))));
    points += b;
  }
  flush();
  std::snprintf(b, sizeof b,
                "<line class=\"cursor\" x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\"/>\n<text x=\"%.1f\" "
                "y=\"%.1f\" text-anchor=\"middle\">input angle %s [deg]</text>\n</svg>\n",
                kLeft, kTop, kLeft, kTop + plot_h, kLeft + plot_w / 2, kHeight - 6, input_name(rep).c_str());
  svg += b;
  return svg;
}

// A geometry as a table, a row per joint, round-off of a zero as 0.
std::string parameters_html(const CandidateRow& r) {
  const double length = kRoundOff;  // both forms of a stored geometry have L = 1
  std::string out = "<table class=\"data params\"><tr><th>joint</th><th>a</th><th>alpha [deg]</th><th>d</th></tr>\n";
  for (size_t i = 0; i < r.a.size(); ++i) {
    out += "<tr><td>" + std::to_string(i + 1) + "</td><td>" + shown(r.a[i], length, 6) + "</td><td>" +
           shown(i < r.alpha_deg.size() ? r.alpha_deg[i] : kNaN, kAngleRoundOffDeg, 6) + "</td><td>" +
           shown(i < r.d.size() ? r.d[i] : kNaN, length, 6) + "</td></tr>\n";
  }
  return out + "</table>\n";
}

// Poses along the motion and the input's range on it [deg].
struct MotionFrames {
  std::vector<std::vector<double>> theta;
  std::vector<double> input_deg;
  bool full_turn = true;
  double lo_deg = 0.0, hi_deg = 360.0;
};

// kMotionFrames poses of the rigid loop's verified motion (the circuit the
// cycle runs on, compute_cycle), evenly spaced in the driven joint's angle:
// a full turn from 0, or a rocker's range with both ends, shifted by whole
// turns to lie over the cycle's range. Empty when the cycle is not on a
// motion (a stored row is only data) or the circuit cannot be followed.
MotionFrames traced_frames(const LoopGeometry& geometry, const Representation& rep) {
  MotionFrames out;
  if (!rep.circuit || rep.circuit->points.empty() || rep.circuit->ranges.empty()) return out;
  const Circuit& circuit = *rep.circuit;
  MotionOptions options = VerificationOptions().motion();
  options.input_joint = rep.input_joint;
  const JointRange& range = circuit.input_range(rep.input_joint);
  out.full_turn = range.crank();
  double lo = 0.0, span = 2 * kPi;
  if (!out.full_turn) {
    lo = range.lo;
    span = range.hi - range.lo;
    if (!(span > 0.0)) return out;
    const double cycle_mid = rep.theta0;
    const double shift = std::round((cycle_mid - (lo + 0.5 * span)) / (2 * kPi)) * 2 * kPi;
    lo += shift;
  }
  for (int k = 0; k < kMotionFrames; ++k) {
    const double angle = lo + span * (out.full_turn ? static_cast<double>(k) / kMotionFrames
                                                    : static_cast<double>(k) / (kMotionFrames - 1));
    JointVector theta;
    if (!pose_at_input(geometry, circuit, angle, theta, options)) continue;
    out.theta.emplace_back(theta.data(), theta.data() + theta.size());
    out.input_deg.push_back(angle * kDegreesPerRadian);
  }
  out.lo_deg = lo * kDegreesPerRadian;
  out.hi_deg = (lo + span) * kDegreesPerRadian;
  return out;
}

// The motion as the page draws it: per pose the input angle and, per joint,
// the points o and p and the axis direction z (JointPlacement), flattened.
// The poses are the traced rigid motion's; without one, the cycle's (as the
// SVG strip of --atlas draws them).
nlohmann::json motion_json(const CandidateRow& r, const Representation& rep, double cycle_lo_deg, double cycle_hi_deg) {
  const LoopGeometry geometry = LoopGeometry::from_degrees(
      std::span<const double>(r.a), std::span<const double>(r.alpha_deg), std::span<const double>(r.d));
  MotionFrames frames = traced_frames(geometry, rep);
  if (frames.theta.size() < 2) {
    frames = MotionFrames{};
    pick_frames(rep, kMotionFrames, frames.theta, frames.input_deg);
    frames.full_turn = rep.full_turn;
    frames.lo_deg = cycle_lo_deg;
    frames.hi_deg = cycle_hi_deg;
  }
  const std::vector<std::vector<double>>& theta = frames.theta;
  const std::vector<double>& input_deg = frames.input_deg;
  const double lo_deg = frames.lo_deg, hi_deg = frames.hi_deg;
  const int n = geometry.joints();
  nlohmann::json j;
  j["joints"] = n;
  j["input"] = input_name(rep);
  j["full_turn"] = frames.full_turn;
  j["lo_deg"] = rounded(lo_deg, 4);
  j["hi_deg"] = rounded(hi_deg, 4);
  std::vector<double> axis_lo, axis_hi;
  for (int i = 0; i < n; ++i) {
    axis_lo.push_back(rounded(std::min(0.0, geometry.d[i]) - kAxisHalf));
    axis_hi.push_back(rounded(std::max(0.0, geometry.d[i]) + kAxisHalf));
  }
  j["axis_lo"] = axis_lo;
  j["axis_hi"] = axis_hi;
  nlohmann::json o = nlohmann::json::array(), p = nlohmann::json::array(), z = nlohmann::json::array();
  std::vector<double> angles;
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e300), hi = Eigen::Vector3d::Constant(-1e300);
  std::vector<Eigen::Vector3d> extent;
  for (size_t k = 0; k < theta.size(); ++k) {
    const std::vector<JointPlacement> joints = joint_placements(geometry, theta[k]);
    std::vector<double> fo, fp, fz;
    bool finite = true;
    for (int i = 0; i < n; ++i) {
      const JointPlacement& jp = joints[static_cast<size_t>(i)];
      finite = finite && jp.o.allFinite() && jp.p.allFinite() && jp.z.allFinite();
      for (int c = 0; c < 3; ++c) {
        fo.push_back(rounded(jp.o[c]));
        fp.push_back(rounded(jp.p[c]));
        fz.push_back(rounded(jp.z[c]));
      }
      for (const Eigen::Vector3d& v : {Eigen::Vector3d(jp.o + axis_lo[static_cast<size_t>(i)] * jp.z),
                                       Eigen::Vector3d(jp.o + axis_hi[static_cast<size_t>(i)] * jp.z)}) {
        lo = lo.cwiseMin(v);
        hi = hi.cwiseMax(v);
        extent.push_back(v);
      }
    }
    if (!finite) continue;
    angles.push_back(rounded(input_deg[k], 4));
    o.push_back(fo);
    p.push_back(fp);
    z.push_back(fz);
  }
  const Eigen::Vector3d centre = angles.empty() ? Eigen::Vector3d::Zero() : Eigen::Vector3d(0.5 * (lo + hi));
  double radius = 1e-9;
  for (const Eigen::Vector3d& v : extent) {
    if (v.allFinite()) radius = std::max(radius, (v - centre).norm());
  }
  j["centre"] = {rounded(centre[0]), rounded(centre[1]), rounded(centre[2])};
  j["radius"] = rounded(radius);
  j["input_deg"] = angles;
  j["o"] = std::move(o);
  j["p"] = std::move(p);
  j["z"] = std::move(z);
  return j;
}

const char* const kStyle = R"CSS(
body { font-family: sans-serif; margin: 1.5em auto; max-width: 1200px; padding: 0 1em; color: #222; }
h1 { font-size: 1.5em; } h2 { font-size: 1.25em; margin-top: 1.6em; border-bottom: 1px solid #ccc; }
table.data { border-collapse: collapse; margin: 0.5em 1.5em 0.5em 0; font-size: 0.9em; }
table.data th, table.data td { border: 1px solid #ccc; padding: 2px 8px; text-align: left; }
table.data th { background: #f3f3f3; }
.row { display: flex; flex-wrap: wrap; align-items: flex-start; gap: 1em; }
.row .side { max-width: 440px; }
.viewer { max-width: 490px; }
svg.chart { font-size: 11px; background: #fff; }
svg.chart .axis { stroke: #444; } svg.chart .grid { stroke: #ddd; }
svg.chart .bar { fill: #4a7fb5; } svg.chart .curve { fill: none; stroke: #1f77b4; stroke-width: 1.5; }
svg.chart line.threshold { stroke: #d62728; stroke-dasharray: 6,3; stroke-width: 1.5; }
svg.chart text.threshold { fill: #d62728; }
svg.chart .cursor { stroke: #888; stroke-dasharray: 2,2; }
.viewer canvas { border: 1px solid #ccc; cursor: grab; touch-action: none; display: block; }
.viewer .controls { display: flex; align-items: center; gap: 0.6em; margin-top: 0.3em; }
.viewer input[type=range] { width: 200px; }
.viewer button { white-space: nowrap; }
.viewer .angle { white-space: nowrap; min-width: 9em; }
.note { color: #555; font-size: 0.9em; }
)CSS";

// The page's script: per family, a viewer that interpolates the embedded poses
// at the slider's input angle and draws the axes and links with an
// orthographic projection; dragging turns the view (azimuth, elevation).
const char* const kScript = R"JS(
'use strict';
(function () {
  const data = JSON.parse(document.getElementById('loopfarm-data').textContent);
  const colours = ['#d62728', '#1f77b4', '#2ca02c', '#9467bd', '#ff7f0e', '#8c564b', '#e377c2', '#17becf'];

  function Viewer(root, m) {
    const canvas = root.querySelector('canvas');
    const slider = root.querySelector('input[type=range]');
    const play = root.querySelector('button.play');
    const reset = root.querySelector('button.reset');
    const label = root.querySelector('.angle');
    const section = document.getElementById(root.dataset.family);
    const chart = section ? section.querySelector('svg.energy') : null;
    const ctx = canvas.getContext('2d');
    const n = m.joints, frames = m.input_deg.length;
    // Start at 90 deg of a full turn (away from the folded poses a Bennett loop
    // passes at 0 and 180 deg), in the middle of a rocker's range.
    let azimuth = 35, elevation = 25, angle = m.full_turn ? 90 : 0.5 * (m.lo_deg + m.hi_deg);
    let playing = false, last = null, direction = 1;
    slider.min = m.lo_deg; slider.max = m.hi_deg; slider.step = 0.1; slider.value = angle;

    // The pose at input angle t: linear between the two embedded poses around
    // it (around the end of a full turn, between the last and the first).
    function pose(t) {
      const A = m.input_deg;
      if (frames === 1) return { o: m.o[0], p: m.p[0], z: m.z[0] };
      let i0, i1, w;
      if (m.full_turn) {
        t = A[0] + ((((t - A[0]) % 360) + 360) % 360);
        let k = 0;
        while (k + 1 < frames && A[k + 1] <= t) k++;
        const next = k + 1 < frames ? A[k + 1] : A[0] + 360;
        i0 = k; i1 = (k + 1) % frames; w = next > A[k] ? (t - A[k]) / (next - A[k]) : 0;
      } else {
        t = Math.min(Math.max(t, A[0]), A[frames - 1]);
        let k = 0;
        while (k + 2 < frames && A[k + 1] <= t) k++;
        i0 = k; i1 = k + 1; w = A[i1] > A[i0] ? (t - A[i0]) / (A[i1] - A[i0]) : 0;
      }
      w = Math.min(Math.max(w, 0), 1);
      const mix = (a, b) => a.map((v, i) => v + w * (b[i] - v));
      return { o: mix(m.o[i0], m.o[i1]), p: mix(m.p[i0], m.p[i1]), z: mix(m.z[i0], m.z[i1]) };
    }

    function draw() {
      const W = canvas.width, H = canvas.height;
      ctx.fillStyle = '#fff'; ctx.fillRect(0, 0, W, H);
      const az = azimuth * Math.PI / 180, el = elevation * Math.PI / 180;
      const right = [-Math.sin(az), Math.cos(az), 0];
      const up = [-Math.sin(el) * Math.cos(az), -Math.sin(el) * Math.sin(az), Math.cos(el)];
      const scale = 0.46 * Math.min(W, H) / m.radius, c = m.centre;
      const screen = (x, y, z) => {
        const v = [x - c[0], y - c[1], z - c[2]];
        return [W / 2 + scale * (v[0] * right[0] + v[1] * right[1] + v[2] * right[2]),
                H / 2 - scale * (v[0] * up[0] + v[1] * up[1] + v[2] * up[2])];
      };
      // The base frame's axes at the origin, short and grey.
      ctx.lineWidth = 1; ctx.setLineDash([]);
      const origin = screen(0, 0, 0);
      [[0.25, 0, 0, 'x'], [0, 0.25, 0, 'y'], [0, 0, 0.25, 'z']].forEach(([x, y, z, name]) => {
        const e = screen(x, y, z);
        ctx.strokeStyle = '#aaa'; ctx.beginPath(); ctx.moveTo(origin[0], origin[1]); ctx.lineTo(e[0], e[1]); ctx.stroke();
        ctx.fillStyle = '#aaa'; ctx.font = '11px sans-serif'; ctx.fillText(name, e[0] + 2, e[1] - 2);
      });
      if (!frames) return;
      const q = pose(angle);
      // Joint axes, dashed, in the joint's colour.
      ctx.lineWidth = 2; ctx.setLineDash([7, 4]);
      for (let i = 0; i < n; i++) {
        const o = q.o.slice(3 * i, 3 * i + 3);
        let z = q.z.slice(3 * i, 3 * i + 3);
        const len = Math.hypot(z[0], z[1], z[2]) || 1;
        z = z.map((v) => v / len);
        const a = screen(o[0] + m.axis_lo[i] * z[0], o[1] + m.axis_lo[i] * z[1], o[2] + m.axis_lo[i] * z[2]);
        const b = screen(o[0] + m.axis_hi[i] * z[0], o[1] + m.axis_hi[i] * z[1], o[2] + m.axis_hi[i] * z[2]);
        ctx.strokeStyle = colours[i % 8];
        ctx.beginPath(); ctx.moveTo(a[0], a[1]); ctx.lineTo(b[0], b[1]); ctx.stroke();
      }
      // Links: along axis i by the offset (o to p), then the common normal to the next o.
      ctx.setLineDash([]); ctx.lineWidth = 3.5; ctx.lineJoin = 'round'; ctx.strokeStyle = '#111';
      ctx.beginPath();
      for (let i = 0; i <= n; i++) {
        const k = i % n, o = screen(q.o[3 * k], q.o[3 * k + 1], q.o[3 * k + 2]);
        if (i === 0) ctx.moveTo(o[0], o[1]); else ctx.lineTo(o[0], o[1]);
        if (i === n) break;
        const p = screen(q.p[3 * k], q.p[3 * k + 1], q.p[3 * k + 2]);
        ctx.lineTo(p[0], p[1]);
      }
      ctx.stroke();
      // Joints: a dot where each link meets its axis, numbered 1..n.
      ctx.font = 'bold 13px sans-serif';
      for (let i = 0; i < n; i++) {
        const p = screen(q.p[3 * i], q.p[3 * i + 1], q.p[3 * i + 2]);
        ctx.fillStyle = colours[i % 8];
        ctx.beginPath(); ctx.arc(p[0], p[1], 5, 0, 2 * Math.PI); ctx.fill();
        ctx.fillText(String(i + 1), p[0] + 7, p[1] - 7);
      }
    }

    function show() {
      label.textContent = m.input + ' = ' + angle.toFixed(1) + ' deg';
      if (chart) {
        const x0 = +chart.dataset.x0, x1 = +chart.dataset.x1, lo = +chart.dataset.lo, hi = +chart.dataset.hi;
        // The chart's image of the angle (whole turns apart); none outside its range.
        let t = angle;
        if (m.full_turn) t = lo + ((((t - lo) % 360) + 360) % 360);
        else t -= 360 * Math.round((t - 0.5 * (lo + hi)) / 360);
        const x = x0 + (hi > lo ? (t - lo) / (hi - lo) : 0) * (x1 - x0);
        const cursor = chart.querySelector('.cursor');
        cursor.setAttribute('x1', x.toFixed(1)); cursor.setAttribute('x2', x.toFixed(1));
        cursor.style.visibility = t >= lo - 1e-6 && t <= hi + 1e-6 ? 'visible' : 'hidden';
      }
      draw();
    }

    function step(now) {
      if (!playing) return;
      if (last !== null) {
        const span = m.hi_deg - m.lo_deg;
        angle += direction * 60 * (now - last) / 1000;
        if (m.full_turn) {
          if (angle > m.hi_deg) angle -= span;
        } else if (angle > m.hi_deg || angle < m.lo_deg) {
          direction = -direction;
          angle = Math.min(Math.max(angle, m.lo_deg), m.hi_deg);
        }
        slider.value = angle;
        show();
      }
      last = now;
      requestAnimationFrame(step);
    }

    play.addEventListener('click', () => {
      playing = !playing;
      play.textContent = playing ? 'Pause' : 'Play';
      last = null;
      if (playing) requestAnimationFrame(step);
    });
    reset.addEventListener('click', () => { azimuth = 35; elevation = 25; show(); });
    slider.addEventListener('input', () => { angle = +slider.value; show(); });
    let drag = null;
    canvas.addEventListener('pointerdown', (e) => {
      drag = [e.clientX, e.clientY, azimuth, elevation];
      canvas.setPointerCapture(e.pointerId);
      canvas.style.cursor = 'grabbing';
    });
    canvas.addEventListener('pointermove', (e) => {
      if (!drag) return;
      azimuth = drag[2] - 0.5 * (e.clientX - drag[0]);
      elevation = Math.min(89, Math.max(-89, drag[3] + 0.5 * (e.clientY - drag[1])));
      draw();
    });
    const release = () => { drag = null; canvas.style.cursor = ''; };
    canvas.addEventListener('pointerup', release);
    canvas.addEventListener('pointercancel', release);
    show();
  }

  document.querySelectorAll('.viewer').forEach((root) => {
    const m = data.families[+root.dataset.index];
    if (m) Viewer(root, m);
  });
})();
)JS";

}  // namespace

int write_html_atlas(const ResultsDatabase& db, const HtmlSelection& selection, const std::vector<CandidateRow>& rows,
                     PendingOutput& out) {
  const std::vector<RunRow> runs = db.runs();
  const std::vector<FamilyGroup> groups = group_by_family(rows);
  std::string body;
  std::string chosen;
  if (!selection.family.empty()) chosen += ", family " + selection.family;
  if (selection.run) chosen += ", candidates run " + std::to_string(*selection.run) + " found first";
  if (!selection.max_energy.empty()) chosen += ", E_mean at most " + selection.max_energy;
  body += "<h1>loopfarm family atlas</h1>\n<p>Database <code>" + html_escape(db.path()) + "</code>" +
          html_escape(chosen) + ": " + count_of(static_cast<long long>(rows.size()), "candidate") + " in " +
          (groups.size() == 1 ? std::string("1 family") : std::to_string(groups.size()) + " families") + ".</p>\n";
  body += summary_html(db, selection);
  body += "<h2 id=\"histogram\">Histogram of all minima</h2>\n";
  body += histogram_svg(db.energy_histogram(selection.run), runs);

  body +=
      "<h2 id=\"families\">Families</h2>\n<p class=\"note\">Candidates are distinct verified movable linkages, hits "
      "the starts that found them. The local dimension (scale included) is found among the search's free "
      "parameters; the known one is the family's in the full 3n-parameter space. The representative is a "
      "full-turn candidate if there is one, with the smallest rigid-closure residual (as in <code>report "
      "--atlas</code>). Its parameters are shown in the conventional form (L = 1, twists in degrees, positive where "
      "the loop allows, as the report's table shows them), then in the canonical form, which gives the "
      "de-duplication key and from which the 3D view and the cycle-energy chart are drawn along the motion of the "
      "rigid loop, every circuit of which is traced here: driven by the first of its joints that turns fully on a "
      "circuit, over a full turn, or, when no joint does, by joint 1 over a window of its range on a circuit. Each "
      "family says which joint that is, in both forms. Unclassified candidates come first: a possible new "
      "family.</p>\n"
      "<table class=\"data\">"
      "<tr><th>family</th><th>joints</th><th>candidates</th><th>hits</th><th>local dimension found "
      "(candidates)</th><th>free parameters</th><th>known dimension</th><th>representative</th></tr>\n";
  for (const FamilyGroup& group : groups) {
    const std::optional<int> known = known_family_dimension(group.family, group.joints);
    body += "<tr><td><a href=\"#" + atlas_stem(group.family, group.joints) + "\">" + html_escape(group.family) +
            "</a></td><td>" + std::to_string(group.joints) + "</td><td>" + std::to_string(group.rows.size()) +
            "</td><td>" + std::to_string(group.hits) + "</td><td>" + dimension_counts(group) + "</td><td>" +
            free_parameter_counts(group) + "</td><td>" + (known ? std::to_string(*known) : "-") + "</td><td>" +
            std::to_string(representative(group).id) + "</td></tr>\n";
  }
  body += "</table>\n";
  if (groups.empty()) body += "<p>(no candidates)</p>\n";

  nlohmann::json families = nlohmann::json::array();
  for (size_t k = 0; k < groups.size(); ++k) {
    const FamilyGroup& group = groups[k];
    const CandidateRow& r = representative(group);
    const std::string stem = atlas_stem(group.family, group.joints);
    const Representation rep = compute_cycle(r);
    double lo_deg = 0.0, hi_deg = 360.0;
    if (!rep.full_turn) {
      lo_deg = 1e300, hi_deg = -1e300;
      for (const CycleSample& s : rep.cycle.samples) {
        lo_deg = std::min(lo_deg, s.theta_in * kDegreesPerRadian);
        hi_deg = std::max(hi_deg, s.theta_in * kDegreesPerRadian);
      }
      if (!(hi_deg > lo_deg)) lo_deg = r.range_lo_deg, hi_deg = r.range_hi_deg;
    }
    const double threshold = zero_threshold_of(runs, r.first_run);
    families.push_back(motion_json(r, rep, lo_deg, hi_deg));
    body += "<section id=\"" + stem + "\">\n<h2>" + html_escape(group.family) + " (" + std::to_string(group.joints) +
            "R): " + count_of(static_cast<long long>(group.rows.size()), "candidate") + ", " +
            count_of(group.hits, "hit") + "</h2>\n";
    body += "<p>" + html_escape(representative_sentence(r));
    if (!r.detail.empty()) body += " Classification: " + html_escape(r.detail) + ".";
    body += "</p>\n<div class=\"row\">\n<div class=\"viewer\" data-index=\"" + std::to_string(k) + "\" data-family=\"" +
            stem +
            "\"><canvas width=\"480\" height=\"400\" aria-label=\"the linkage in 3D\"></canvas>\n"
            "<div class=\"controls\"><button class=\"play\" type=\"button\">Play</button>"
            "<input type=\"range\" aria-label=\"input angle\"><span class=\"angle\"></span>"
            "<button class=\"reset\" type=\"button\">Reset view</button></div>\n"
            "<p class=\"note\">Drag to turn the view. Dashed: joint axes (joint i's colour), black: links (along "
            "the axis by the offset d, then the common normal a), dots: joints. Base frame: joint 1's.</p></div>\n";
    body +=
        "<div class=\"side\"><p class=\"note\">Cycle energy E / (k_a L&#178;) of the canonical geometry, recomputed (" +
        std::to_string(kAtlasCycleSamples) + " samples, log axis), E_mean " + g(rep.cycle.E_mean, 3) + ", E_max " +
        g(rep.cycle.E_max, 3) + ", " + std::to_string(rep.cycle.failed_samples) + " failed samples.</p>\n" +
        energy_svg(rep, threshold, lo_deg, hi_deg) +
        "<p class=\"note\">Parameters (conventional form, L = 1, twists in degrees):</p>\n" +
        parameters_html(conventional(r)) + "<p class=\"note\">Canonical form (L = 1, twists in degrees):</p>\n" +
        parameters_html(r) + "<p class=\"note\">" +
        html_escape(chart_joints_sentence(r, rep, "The 3D view and the cycle-energy chart")) + "</p>\n</div>\n</div>\n";
    body += "</section>\n";
  }

  nlohmann::json page;
  page["families"] = std::move(families);
  std::string json = page.dump();
  // The data sit in a script element: "</" must not end it.
  for (size_t at = json.find("</"); at != std::string::npos; at = json.find("</", at + 3)) json.replace(at, 2, "<\\/");

  std::string html = "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n";
  html += "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n";
  html += "<link rel=\"icon\" href=\"data:,\">\n";
  html += "<title>loopfarm atlas: " + html_escape(db.path()) + "</title>\n<style>" + kStyle + "</style>\n</head>\n";
  html += "<body>\n" + body;
  html += "<script type=\"application/json\" id=\"loopfarm-data\">" + json + "</script>\n";
  html += "<script>" + std::string(kScript) + "</script>\n</body>\n</html>\n";
  if (std::fwrite(html.data(), 1, html.size(), out.stream()) != html.size()) {
    throw EnvironmentError("--html: cannot write " + out.target().string());
  }
  return static_cast<int>(groups.size());
}

}  // namespace loopfarm::cli
