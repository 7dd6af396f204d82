// loopfarm merge OUT.sqlite IN.sqlite...: the databases of a job's slices (or
// of any runs of one job and seed) as one database, as one run of all their
// starts would have written it (docs/guide/database.md, "Merging"). This file
// parses the arguments, calls ResultsDatabase::merge and prints what it did.
#include "merge_command.hpp"

#include <cinttypes>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "cli_support.hpp"
#include "loopfarm/farm/results_database.hpp"
#include "output_format.hpp"

namespace loopfarm::cli {
namespace {

struct MergeArguments {
  std::string output;
  std::vector<std::string> inputs;
  FormatChoice format;
};

int run_merge(const MergeArguments& args) {
  MergeSummary summary;
  try {
    summary = ResultsDatabase::merge(args.output, args.inputs);
  } catch (const DatabaseError& error) {
    // An input refused (not loopfarm's, damaged, another job or seed, rows
    // that differ) or OUT already there: bad input, and nothing was written.
    if (error.cause() == DatabaseError::Cause::refused) throw UsageError("database", error.what());
    throw EnvironmentError(error.what());
  }
  if (args.format.format == OutputFormat::json) {
    nlohmann::ordered_json record;
    record["database"] = args.output;
    record["inputs"] = summary.inputs;
    record["starts"] = summary.starts;
    record["overlapping_starts"] = summary.overlapping_starts;
    record["target"] = summary.target;
    record["complete"] = summary.complete;
    record["verified"] = summary.verified;
    record["candidates"] = summary.candidates;
    write_record(stdout, record, OutputFormat::json);
    return kExitSuccess;
  }
  std::fprintf(stderr,
               "loopfarm merge: %" PRId64 " databases into %s: %" PRIu64 " starts (%" PRIu64
               " held by more than one input, kept once), %" PRId64 " verified, %" PRId64 " candidates\n",
               summary.inputs, args.output.c_str(), summary.starts, summary.overlapping_starts, summary.verified,
               summary.candidates);
  if (summary.complete) {
    std::fprintf(stderr, "loopfarm merge: every start of the job's %" PRIu64 " is there; the run is complete\n",
                 summary.target);
  } else {
    std::fprintf(stderr,
                 "loopfarm merge: %" PRIu64 " of the job's %" PRIu64
                 " starts are there; loopfarm run JOB --db %s runs the others\n",
                 summary.starts, summary.target, args.output.c_str());
  }
  return kExitSuccess;
}

}  // namespace

Subcommand add_merge_command(CLI::App& parent) {
  auto args = std::make_shared<MergeArguments>();
  CLI::App* app = parent.add_subcommand(
      "merge", "Merge the databases of one job's slices (loopfarm run --slice) into a new database, as one run.");
  app->footer(
      "Examples:\n"
      "  loopfarm merge all.sqlite slice-0.sqlite slice-1.sqlite slice-2.sqlite\n"
      "  loopfarm merge results/all.sqlite results/slice-*-of-16.sqlite\n"
      "The inputs must hold one run each of the same job (its text, the [output] table apart) and seed; a start\n"
      "held by several inputs must have the same row in each. Every start is kept once, the candidates are\n"
      "de-duplicated again as one run would, and merge_inputs records where each row came from.\n"
      "Exit codes: 0 merged, 1 failure, 2 bad input (OUT exists, an input refused, other jobs or seeds, rows that\n"
      "differ): nothing is written, and the inputs are never changed.\n");
  app->add_option("OUT", args->output, "the merged database: a new file")->required()->type_name("OUT.sqlite");
  app->add_option("IN", args->inputs, "databases written by loopfarm run (one run each)")
      ->required()
      ->type_name("IN.sqlite...");
  add_format_option(*app, args->format, {OutputFormat::text, OutputFormat::json},
                    "what it did: text (lines on stderr) or json (one object on stdout), as");
  return {app, [args] { return run_merge(*args); }};
}

}  // namespace loopfarm::cli
