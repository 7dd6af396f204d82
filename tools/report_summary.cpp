#include "report_summary.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include <nlohmann/json.hpp>

#include "candidate_display.hpp"

namespace loopfarm::cli {
namespace {

std::string run_where(const RunRow& r) {
  // Where its starts were computed: ranks of the last session, or the databases it was merged from.
  return r.merged_inputs > 0 ? "merged from " + std::to_string(r.merged_inputs) + " databases"
                             : count_of(r.ranks, "rank");
}

}  // namespace

SummaryData read_summary(const ResultsDatabase& db, const std::optional<std::int64_t>& run) {
  return {db.runs(), db.start_counts(run), db.status_counts(run), db.family_counts(run), db.energy_histogram(run)};
}

void print_summary_text(const ResultsDatabase& db, const SummaryData& s) {
  std::printf("database %s\n", db.path().c_str());
  std::printf("runs\n");
  for (const RunRow& r : s.runs) {
    const std::string slice = r.slice ? "  slice " + to_string(*r.slice) : "";
    std::printf("  run %lld  %s  seed %llu%s  %lld/%lld starts  %s  %s  %s .. %s\n", static_cast<long long>(r.run_id),
                r.job_path.c_str(), static_cast<unsigned long long>(r.seed), slice.c_str(),
                static_cast<long long>(r.starts_done), static_cast<long long>(r.starts), r.status.c_str(),
                run_where(r).c_str(), r.started_at.c_str(), r.updated_at.c_str());
  }
  const StartCounts& c = s.starts;
  std::printf("starts     %lld, zero minima %lld, verified %lld, mean %.4g s per start, %.4g core-seconds\n",
              static_cast<long long>(c.starts), static_cast<long long>(c.zeros), static_cast<long long>(c.verified),
              c.mean_seconds, c.total_seconds);
  std::printf("by status\n");
  for (const StatusCount& x : s.statuses) {
    std::printf("  %-18s %lld\n", x.status.c_str(), static_cast<long long>(x.starts));
  }
  std::printf("candidates by family (distinct linkages, starts that found them)\n");
  for (const FamilyCount& f : s.families) {
    std::printf("  %-23s %6lld %8lld\n", f.family.c_str(), static_cast<long long>(f.candidates),
                static_cast<long long>(f.hits));
  }
  const EnergyHistogram& h = s.histogram;
  std::int64_t most = 1;
  for (const auto& [decade, count] : h.decades) most = std::max(most, count);
  std::printf("histogram of log10(E_mean) over all starts\n");
  for (const auto& [decade, count] : h.decades) {
    const int width = static_cast<int>(std::lround(50.0 * static_cast<double>(count) / static_cast<double>(most)));
    std::printf("  [%4d, %4d) %7lld %s\n", decade, decade + 1, static_cast<long long>(count),
                std::string(static_cast<size_t>(width), '#').c_str());
  }
  if (h.zeros) std::printf("  exactly 0   %7lld\n", static_cast<long long>(h.zeros));
  if (h.missing) {
    std::printf("  no value    %7lld (the start could not be evaluated)\n", static_cast<long long>(h.missing));
  }
}

void print_summary_json(const ResultsDatabase& db, const SummaryData& s, const std::optional<std::int64_t>& run) {
  using nlohmann::ordered_json;
  ordered_json out;
  out["database"] = db.path();
  out["run"] = run ? ordered_json(*run) : ordered_json(nullptr);
  ordered_json runs = ordered_json::array();
  for (const RunRow& r : s.runs) {
    ordered_json row;
    row["run_id"] = r.run_id;
    row["job_path"] = r.job_path;
    row["seed"] = r.seed;
    row["slice"] = r.slice ? ordered_json(to_string(*r.slice)) : ordered_json(nullptr);
    row["joints"] = r.joints;
    row["starts"] = r.starts;
    row["starts_done"] = r.starts_done;
    row["status"] = r.status;
    row["ranks"] = r.ranks;
    row["merged_inputs"] = r.merged_inputs;
    row["started_at"] = r.started_at;
    row["updated_at"] = r.updated_at;
    runs.push_back(row);
  }
  out["runs"] = runs;
  const StartCounts& c = s.starts;
  ordered_json starts;
  starts["starts"] = c.starts;
  starts["zero_minima"] = c.zeros;
  starts["verified"] = c.verified;
  starts["mean_seconds"] = c.mean_seconds;
  starts["core_seconds"] = c.total_seconds;
  out["starts"] = starts;
  ordered_json statuses = ordered_json::array();
  for (const auto& status : s.statuses) statuses.push_back({{"status", status.status}, {"starts", status.starts}});
  out["by_status"] = statuses;
  ordered_json families = ordered_json::array();
  for (const auto& family : s.families) {
    families.push_back({{"family", family.family}, {"candidates", family.candidates}, {"hits", family.hits}});
  }
  out["families"] = families;
  ordered_json decades = ordered_json::array();
  for (const auto& [decade, count] : s.histogram.decades) {
    decades.push_back({{"log10_E_mean", decade}, {"starts", count}});
  }
  out["histogram"] = {{"decades", decades}, {"zeros", s.histogram.zeros}, {"missing", s.histogram.missing}};
  std::printf("%s\n", out.dump().c_str());
}

void print_summary_markdown(const ResultsDatabase& db, const SummaryData& s) {
  std::printf("Database `%s`\n\n", db.path().c_str());
  std::printf("| run | job | seed | slice | starts done | starts | status | where | started | updated |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|\n");
  for (const RunRow& r : s.runs) {
    std::printf("| %lld | `%s` | %llu | %s | %lld | %lld | %s | %s | %s | %s |\n", static_cast<long long>(r.run_id),
                r.job_path.c_str(), static_cast<unsigned long long>(r.seed), r.slice ? to_string(*r.slice).c_str() : "",
                static_cast<long long>(r.starts_done), static_cast<long long>(r.starts), r.status.c_str(),
                run_where(r).c_str(), r.started_at.c_str(), r.updated_at.c_str());
  }
  const StartCounts& c = s.starts;
  std::printf("\n| starts | zero minima | verified | mean seconds per start | core-seconds |\n|---|---|---|---|---|\n");
  std::printf("| %lld | %lld | %lld | %.4g | %.4g |\n", static_cast<long long>(c.starts),
              static_cast<long long>(c.zeros), static_cast<long long>(c.verified), c.mean_seconds, c.total_seconds);
  std::printf("\n| status | starts |\n|---|---|\n");
  for (const StatusCount& x : s.statuses)
    std::printf("| %s | %lld |\n", x.status.c_str(), static_cast<long long>(x.starts));
  std::printf("\n| family | candidates | hits |\n|---|---|---|\n");
  for (const FamilyCount& f : s.families) {
    std::printf("| %s | %lld | %lld |\n", f.family.c_str(), static_cast<long long>(f.candidates),
                static_cast<long long>(f.hits));
  }
  std::printf("\n| log10(E_mean) | starts |\n|---|---|\n");
  for (const auto& [decade, count] : s.histogram.decades) {
    std::printf("| [%d, %d) | %lld |\n", decade, decade + 1, static_cast<long long>(count));
  }
  if (s.histogram.zeros) std::printf("| exactly 0 | %lld |\n", static_cast<long long>(s.histogram.zeros));
  if (s.histogram.missing) std::printf("| no value | %lld |\n", static_cast<long long>(s.histogram.missing));
}

}  // namespace loopfarm::cli
