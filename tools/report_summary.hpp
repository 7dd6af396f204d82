// The summary of a results database (`loopfarm report DB --summary`): its
// runs, the counts of starts per status, candidates and hits per family, and
// the histogram of log10 of every start's minimum; as text, JSON or Markdown.
#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include "loopfarm/farm/results_database.hpp"

namespace loopfarm::cli {

// What the summary shows, read in one go (of one run, or of every run).
struct SummaryData {
  std::vector<RunRow> runs;
  StartCounts starts;
  std::vector<StatusCount> statuses;
  std::vector<FamilyCount> families;
  EnergyHistogram histogram;
};

// The summary of `run`'s starts, or of every run's without one.
SummaryData read_summary(const ResultsDatabase& db, const std::optional<std::int64_t>& run);

// Lines for people, the histogram drawn with '#'.
void print_summary_text(const ResultsDatabase& db, const SummaryData& s);
// One JSON object: database, run, runs, starts, by_status, families, histogram.
void print_summary_json(const ResultsDatabase& db, const SummaryData& s, const std::optional<std::int64_t>& run);
// Markdown tables.
void print_summary_markdown(const ResultsDatabase& db, const SummaryData& s);

}  // namespace loopfarm::cli
