#include "start_command.hpp"

#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <string>

#include "candidate_output.hpp"
#include "cli_support.hpp"
#include "loopfarm/search/job.hpp"
#include "loopfarm/search/start.hpp"
#include "output_format.hpp"

namespace loopfarm::cli {
namespace {

struct StartArguments {
  std::string job;
  std::string index = "0";
  std::string count = "1";
  std::string algorithm;  // empty: the job's
  bool trace = false;
  FormatChoice format;
};

std::string readable(double value) {
  char buffer[40];
  std::snprintf(buffer, sizeof buffer, "%.6g", value);
  return buffer;
}

void print_geometry(const char* title, const LoopGeometry& g) {
  std::printf("%s\n", title);
  std::printf("  a                     %s\n", lengths_text(g.a).c_str());
  std::printf("  alpha_deg             %s\n", degrees_text(g.alpha).c_str());
  std::printf("  d                     %s\n", lengths_text(g.d).c_str());
}

void print_story(const Job& job, const StartSummary& s) {
  std::printf("start %llu of %s (seed %llu, %d joints, %d free parameters)\n", static_cast<unsigned long long>(s.index),
              job.path.c_str(), static_cast<unsigned long long>(job.search.seed), job.loop.joints,
              job.space.free_count());
  print_geometry("drawn geometry", s.initial_geometry);
  std::printf("  theta_deg             %s\n", degrees_text(s.initial_angles).c_str());
  std::printf("  E_mean                %s\n", readable(s.initial_E_mean).c_str());
  std::printf("local minimisation (%s)\n", s.algorithm.c_str());
  std::printf("  status                %s: %s\n", to_string(s.status), s.message.c_str());
  std::printf("  evaluations           %d cycles in %s s\n", s.evaluations, readable(s.seconds).c_str());
  std::printf("  objective             %s%s\n", readable(s.objective).c_str(),
              job.steering.nontrivial || !job.steering.deflate.empty() ? " (steered)" : "");
  print_geometry("final geometry", s.final_geometry);
  std::printf("  theta_deg             %s (assembled at theta0)\n", degrees_text(s.final_angles).c_str());
  std::printf("  E_mean                %s   [E / (k_a L^2)]\n", readable(s.E_mean).c_str());
  std::printf("  E_max                 %s\n", readable(s.E_max).c_str());
  std::printf("  failed samples        %d, branch jumps %d\n", s.failed_samples, s.branch_jumps);
  std::printf("zero                    %s (threshold %s)\n", s.zero ? "yes" : "no",
              readable(job.search.zero_threshold).c_str());
  if (s.zero) {
    std::printf("analysis                %s s\n", readable(s.analysis_seconds).c_str());
    const GeometryPolishSummary& p = s.candidate.polish;
    if (p.iterations > 0) {
      std::printf("polish onto the motion  %s: closure %s -> %s at %d poses in %d iterations, moved %s of L\n",
                  p.converged ? "converged" : "failed", readable(p.initial_residual).c_str(),
                  readable(p.final_residual).c_str(), p.poses_used, p.iterations, readable(p.displacement).c_str());
      if (p.converged) print_geometry("polished geometry", s.candidate.geometry);
    }
    print_candidate(s.candidate);
    if (s.candidate.verification.verified) print_local_dimension(s.candidate.local_dimension);
  }
}

nlohmann::ordered_json start_record(const StartSummary& s) {
  nlohmann::ordered_json record;
  record["index"] = s.index;
  record["algorithm"] = s.algorithm;
  record["status"] = to_string(s.status);
  record["message"] = s.message;
  record["E_mean"] = s.E_mean;
  record["E_max"] = s.E_max;
  record["objective"] = s.objective;
  record["initial_E_mean"] = s.initial_E_mean;
  record["zero"] = s.zero;
  record["evaluations"] = s.evaluations;
  record["seconds"] = s.seconds;
  record["analysis_seconds"] = s.analysis_seconds;
  record["failed_samples"] = s.failed_samples;
  record["branch_jumps"] = s.branch_jumps;
  record["initial_geometry"] = geometry_json(s.initial_geometry);
  record["final_geometry"] = geometry_json(s.final_geometry);
  // The same keys for every start (they are CSV columns): null but for a zero.
  record["polish"] = polish_json(s.candidate.polish, s.zero);
  nlohmann::ordered_json polished = geometry_json(s.candidate.geometry);
  if (!s.zero) {
    for (auto& value : polished) value = nullptr;
  }
  record["polished_geometry"] = polished;
  add_candidate_json(record, s.candidate, s.zero);
  return record;
}

int run_start_command(const StartArguments& args) {
  Job job;
  try {
    job = read_job_file(args.job);
  } catch (const JobError& error) {
    throw UsageError("job file", error.what());
  }
  if (!args.algorithm.empty()) {
    if (!is_known_algorithm(args.algorithm)) {
      throw UsageError("--algorithm", "unknown algorithm \"" + args.algorithm +
                                          "\"; expected gauss-newton or an NLopt name such as LD_LBFGS or LN_BOBYQA");
    }
    job.optimizer.algorithm = args.algorithm;
  }
  const long long index = parse_integer(args.index, "--index");
  if (index < 0 || index >= job.search.starts) {
    throw UsageError("--index", "got " + std::to_string(index) + "; the job has starts 0 to " +
                                    std::to_string(job.search.starts - 1) +
                                    " ([search] starts = " + std::to_string(job.search.starts) + ")");
  }
  const long long count = parse_integer(args.count, "--count");
  if (count < 1) throw UsageError("--count", "got " + std::to_string(count) + "; must be >= 1");
  // Compared as count > starts - index: index + count can overflow
  // (--count 9223372036854775807), and so can the last index in the message.
  if (count > job.search.starts - index) {
    const std::string last = count - 1 <= std::numeric_limits<long long>::max() - index
                                 ? std::to_string(index + (count - 1))
                                 : "beyond " + std::to_string(std::numeric_limits<long long>::max());
    throw UsageError("--count", "got " + std::to_string(count) + "; starts " + std::to_string(index) + " to " + last +
                                    " must lie in 0 to " + std::to_string(job.search.starts - 1));
  }
  const OutputFormat format = args.format.format;
  StartOptions options;
  if (args.trace) {
    // With a data format the trace goes to stderr, so that stdout holds the data alone.
    std::FILE* out = format == OutputFormat::text ? stdout : stderr;
    std::fprintf(out, "%5s %6s %-23s %-23s %-12s %-12s %-10s %s\n", "iter", "evals", "objective", "E_mean", "|grad|",
                 "|step|", "damping", "accepted");
    options.trace = [out](const SearchTraceRow& row) {
      std::fprintf(out, "%5d %6d %-23.17g %-23.17g %-12.4g %-12.4g %-10.3g %s\n", row.iteration, row.evaluations,
                   row.value, row.E_mean, row.gradient_norm, row.step_norm, row.damping,
                   row.accepted ? "yes" : (row.abandoned ? "no, abandoned" : "no"));
    };
  }
  RecordStream records(stdout, format);
  for (long long i = index; i < index + count; ++i) {
    const StartSummary summary = run_start(job, static_cast<std::uint64_t>(i), options);
    if (format == OutputFormat::text) {
      if (i > index) std::printf("\n");
      print_story(job, summary);
    } else {
      records.write(start_record(summary));
    }
    std::fflush(stdout);  // each start as it finishes, for long runs piped elsewhere
  }
  return kExitSuccess;
}

}  // namespace

Subcommand add_start_command(CLI::App& parent) {
  auto args = std::make_shared<StartArguments>();
  CLI::App* app = parent.add_subcommand(
      "start",
      "Run one start of a job: draw its geometry, minimise the cycle energy, and verify, classify and "
      "canonicalise the result if it reaches zero.");
  app->footer(
      "Examples:\n  loopfarm start jobs/paper-table1.toml --index 3 --trace\n"
      "  loopfarm start jobs/default.toml --count 100 --format csv > starts.csv\n"
      "Exit codes: 0 done (whatever the start found), 1 failure, 2 bad input (job file, index).\n");
  app->add_option("JOB", args->job, "job file (TOML, see docs/guide/job-file.md)")->required()->type_name("JOB.toml");
  app->add_option("--index", args->index, "start index, 0 <= I < [search] starts")
      ->type_name("I")
      ->capture_default_str();
  app->add_option("--count", args->count,
                  "run starts I to I+N-1: a story each, or one JSON line, CSV row or Markdown row each")
      ->type_name("N")
      ->capture_default_str();
  app->add_option("--algorithm", args->algorithm, "override [optimizer] algorithm of the job")->type_name("NAME");
  app->add_flag("--trace", args->trace, "print every iteration of the local minimisation");
  add_format_option(*app, args->format,
                    {OutputFormat::text, OutputFormat::json, OutputFormat::csv, OutputFormat::markdown},
                    "print each start as");
  return {app, [args] { return run_start_command(*args); }};
}

}  // namespace loopfarm::cli
