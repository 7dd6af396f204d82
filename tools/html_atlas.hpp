// The family atlas as one self-contained HTML page (`loopfarm report DB
// --html FILE.html`, html_atlas.cpp): the run summary, the histogram of all
// minima, the family table and, per family, its representative (the same
// choice as --atlas) moving in 3D on a canvas, its cycle-energy chart and its
// parameters. The motion is computed here and embedded as JSON; the page's
// own script only interpolates and draws it. Nothing is fetched: the page
// opens offline in any browser.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "cli_support.hpp"
#include "loopfarm/farm/results_database.hpp"

namespace loopfarm::cli {

// What the report selected, as the user gave it (empty: not given), shown on the page.
struct HtmlSelection {
  std::string family;
  std::optional<std::int64_t> run;
  std::string max_energy;
};

// Writes the page into `out`'s stream (the caller commits it). `rows` are
// every candidate selected, in the report's order; the summary and the
// histogram are of `selection.run` (every run without one), as `report
// --summary` gives them. Returns the number of families drawn.
int write_html_atlas(const ResultsDatabase& db, const HtmlSelection& selection, const std::vector<CandidateRow>& rows,
                     PendingOutput& out);

}  // namespace loopfarm::cli
