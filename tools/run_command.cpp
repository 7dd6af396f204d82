// loopfarm run JOB.toml: the discovery farm (docs/guide/farm.md), alone or under
// `mpirun -np P`. This file parses the options, turns signals into a stop
// request, calls the farm library (loopfarm/farm/farm.hpp) and prints what it
// did; the work queue, the coordinator and MPI are in src/farm/.
//
// Stop: SIGINT, SIGTERM and SIGUSR1 only set a flag. No more work is handed
// out, the starts in hand finish, everything is committed, and the command
// exits with kExitStopped and a line saying how to resume. SIGXFSZ (a file
// size limit reached) is ignored, so that the write fails as on a full disk:
// the run stops with exit 1 and a message naming the database, which keeps
// its last commit and can be resumed.
#include "run_command.hpp"

#include <algorithm>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <optional>
#include <string>

#include "cli_support.hpp"
#include "loopfarm/farm/farm.hpp"
#include "loopfarm/farm/results_database.hpp"
#include "loopfarm/search/job.hpp"
#include "output_format.hpp"

// Under AddressSanitizer (scripts/test.sh --sanitize): the allocations Open MPI
// keeps until exit are suppressed by library name (scripts/sanitizers/lsan.supp),
// which needs whole allocation stacks; the default fast unwinder stops in
// Open MPI's components, which are built without frame pointers. Full
// unwinding costs every allocation a slow walk, so only the program that
// starts MPI asks for it, here, and the test programs keep the fast one
// (ASAN_OPTIONS in the environment still overrides this default).
#if defined(__SANITIZE_ADDRESS__)
#define LOOPFARM_ADDRESS_SANITIZER 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define LOOPFARM_ADDRESS_SANITIZER 1
#endif
#endif
#ifdef LOOPFARM_ADDRESS_SANITIZER
extern "C" const char* __asan_default_options() { return "fast_unwind_on_malloc=0"; }
#endif

namespace loopfarm::cli {
namespace {

// Set by the signal handlers; read by the farm.
StopFlag g_stop;

extern "C" void on_stop_signal(int signal) { g_stop.request(signal); }

void install_stop_handlers() {
  struct sigaction action {};
  action.sa_handler = on_stop_signal;
  sigemptyset(&action.sa_mask);
  for (int signal : {SIGINT, SIGTERM, SIGUSR1}) sigaction(signal, &action, nullptr);
  std::signal(SIGXFSZ, SIG_IGN);
}

struct RunArguments {
  std::string job;
  std::string starts;
  std::string seed;
  std::string db;
  std::string slice;
  // At most 64 starts per request: a worker waits for its next chunk up to
  // one 2 ms polling period of rank 0 (longer where rank 0's threads wait
  // for a core); on 2 ranks the default job's wall time was 0.754 of its
  // core-seconds of local minimisation with chunks of 16, 0.725 with 64 or
  // 256 (docs/performance.md).
  std::string chunk = "64";
  std::string progress = "auto";
  bool new_run = false;
  bool quiet = false;
  FormatChoice format;
};

// The job and the farm's options, as the arguments say.
struct RunRequest {
  Job job;
  FarmOptions farm;
};

// --slice I/K: 0 <= I < K.
StartSlice parse_slice(const std::string& text) {
  const size_t slash = text.find('/');
  if (slash == std::string::npos) {
    throw UsageError("--slice", "got " + quote_text(text) + "; expected I/K, slice I (from 0) of K, e.g. 2/8");
  }
  const long long index = parse_integer(std::string_view(text).substr(0, slash), "--slice I");
  const long long count = parse_integer(std::string_view(text).substr(slash + 1), "--slice K");
  if (count < 1 || count > (1LL << 53)) throw UsageError("--slice", "got " + text + "; K must be >= 1");
  if (index < 0 || index >= count) {
    throw UsageError("--slice", "got " + text + "; I must be in [0, " + std::to_string(count - 1) + "]");
  }
  return StartSlice{static_cast<std::uint64_t>(index), static_cast<std::uint64_t>(count)};
}

RunRequest read_settings(const RunArguments& args) {
  RunRequest s;
  try {
    s.job = read_job_file(args.job);
  } catch (const JobError& error) {
    throw UsageError("job file", error.what());
  }
  if (!args.starts.empty()) {
    const long long starts = parse_integer(args.starts, "--starts");
    if (starts < 1 || starts > (1LL << 53)) throw UsageError("--starts", "got " + args.starts + "; must be >= 1");
    s.job.search.starts = static_cast<long>(starts);
  }
  if (!args.seed.empty()) {
    const long long seed = parse_integer(args.seed, "--seed");
    if (seed < 0) throw UsageError("--seed", "got " + args.seed + "; must be >= 0");
    s.job.search.seed = static_cast<std::uint64_t>(seed);
  }
  if (!args.db.empty()) s.job.output.database = args.db;
  if (!args.slice.empty()) s.farm.slice = parse_slice(args.slice);
  const long long chunk = parse_integer(args.chunk, "--chunk");
  if (chunk < 1 || chunk > 100000) throw UsageError("--chunk", "got " + args.chunk + "; must be in [1, 100000]");
  s.farm.chunk = static_cast<int>(chunk);
  if (args.quiet) {
    s.farm.progress = ProgressStyle::silent;
  } else if (args.progress == "auto") {
    s.farm.progress = default_progress_style();
  } else if (args.progress == "bar") {
    s.farm.progress = ProgressStyle::bar;
  } else if (args.progress == "log") {
    s.farm.progress = ProgressStyle::log;
  } else if (args.progress == "none") {
    s.farm.progress = ProgressStyle::none;
  } else {
    throw UsageError("--progress", "got " + quote_text(args.progress) + "; expected auto, bar, log or none");
  }
  s.farm.new_run = args.new_run;
  return s;
}

// This process's rank as the MPI launcher tells it (Open MPI, PMIx, MPICH,
// Slurm), read before MPI starts, so that a usage error knows it too; 0 when
// not launched by one.
long launcher_rank() {
  for (const char* name : {"OMPI_COMM_WORLD_RANK", "PMIX_RANK", "PMI_RANK", "SLURM_PROCID"}) {
    if (const char* value = std::getenv(name)) return std::strtol(value, nullptr, 10);
  }
  return 0;
}

// The command that resumes the run, as far as this program knows it: mpirun's
// other options (hosts, a script that launched it) are not visible here.
std::string resume_command(const RunArguments& args, const RunRequest& s, int ranks) {
  std::string command =
      (ranks > 1 ? "mpirun -np " + std::to_string(ranks) + " " : std::string()) + "loopfarm run " + args.job;
  if (!args.starts.empty()) command += " --starts " + args.starts;
  if (!args.seed.empty()) command += " --seed " + args.seed;
  if (s.farm.slice) command += " --slice " + to_string(*s.farm.slice);
  command += " --db " + s.job.output.database;
  return command;
}

int run_run_command(const RunArguments& args) {
  install_stop_handlers();
  const MpiSession mpi;
  // Every rank reads the job (the same file gives the same verdict), so a
  // bad job ends every rank before any collective call; rank 0 says why.
  std::optional<RunRequest> settings;
  try {
    settings = read_settings(args);
  } catch (...) {
    if (mpi.rank() == 0) throw;
    return kExitUsage;
  }
  const RunRequest& s = *settings;
  // Destroyed before `mpi`: the code is on disk before MPI_Finalize.
  struct ExitRecord {
    int code = kExitFailure;
    ~ExitRecord() { record_exit_code(code); }
  } exit_record;
  FarmSummary summary;
  try {
    summary = run_farm(s.job, mpi.world(), g_stop, s.farm);
  } catch (const DatabaseError& error) {
    // A database that is not loopfarm's, or holds another job: bad input.
    // The system's failure (a full disk, an I/O error): exit 1, the
    // database as its last commit left it, to be resumed.
    if (error.cause() == DatabaseError::Cause::failed) throw EnvironmentError(std::string("database: ") + error.what());
    exit_record.code = kExitUsage;
    throw UsageError("database", error.what());
  }
  switch (summary.status) {
    case FarmStatus::refused:
      return exit_record.code = kExitUsage;
    case FarmStatus::failed:
      return exit_record.code = kExitFailure;
    case FarmStatus::complete:
    case FarmStatus::stopped:
      break;
  }
  // Every rank exits with rank 0's code, so that mpirun passes it on (3 for a
  // stopped run); only rank 0 reports.
  const int code = summary.status == FarmStatus::complete ? kExitSuccess : kExitStopped;
  exit_record.code = code;
  if (mpi.rank() != 0) return code;
  const std::string& database = s.job.output.database;
  std::string slice;
  if (s.farm.slice) {
    const IndexRange range = slice_range(s.farm.slice, static_cast<std::uint64_t>(s.job.search.starts));
    slice = " of slice " + to_string(*s.farm.slice) + " (start indices [" + std::to_string(range.first) + ", " +
            std::to_string(range.last) + ") of " + std::to_string(s.job.search.starts) + ")";
  }
  const double wall = summary.run.wall_s;
  if (args.format.format == OutputFormat::json) {
    nlohmann::ordered_json record;
    record["status"] = summary.status == FarmStatus::complete ? "complete" : "stopped";
    record["database"] = database;
    record["slice"] = s.farm.slice ? nlohmann::ordered_json(to_string(*s.farm.slice)) : nlohmann::ordered_json(nullptr);
    record["starts_done"] = summary.run.done;
    record["starts_total"] = summary.run.total;
    record["zeros"] = summary.run.zeros;
    record["candidates"] = summary.run.candidates;
    record["session_starts"] = summary.run.done_here;
    record["session_seconds"] = wall;
    record["ranks"] = summary.ranks;
    record["coordination_seconds"] = summary.run.coordination_s;
    record["messages"] = summary.run.messages;
    record["peak_mb_rank0"] = summary.peak_mb_rank0;
    record["peak_mb_max"] = summary.peak_mb_max;
    record["stop_signal"] = summary.status == FarmStatus::stopped
                                ? nlohmann::ordered_json(signal_name(summary.stop_signal))
                                : nlohmann::ordered_json(nullptr);
    record["resume_command"] = summary.status == FarmStatus::stopped
                                   ? nlohmann::ordered_json(resume_command(args, s, summary.ranks))
                                   : nlohmann::ordered_json(nullptr);
    write_record(stdout, record, OutputFormat::json);
  } else if (!args.quiet) {
    std::fprintf(stderr, "loopfarm run: %ld of %ld starts%s committed to %s, %ld zero minima, %ld candidates\n",
                 summary.run.done, summary.run.total, slice.c_str(), database.c_str(), summary.run.zeros,
                 summary.run.candidates);
    std::fprintf(stderr,
                 "loopfarm run: this session %ld starts in %.1f s on %d %s (%.3g starts/s); rank 0 coordination "
                 "%.3f s (%.2f%% of the wall time, %ld messages); peak memory per rank %.1f MB (rank 0) .. %.1f MB\n",
                 summary.run.done_here, wall, summary.ranks, summary.ranks == 1 ? "rank" : "ranks",
                 wall > 0 ? static_cast<double>(summary.run.done_here) / wall : 0.0, summary.run.coordination_s,
                 wall > 0 ? 100.0 * summary.run.coordination_s / wall : 0.0, summary.run.messages,
                 summary.peak_mb_rank0, summary.peak_mb_max);
  }
  if (summary.status == FarmStatus::stopped) {
    std::fprintf(stderr, "loopfarm run: stopped by %s; resume with: %s\n", signal_name(summary.stop_signal).c_str(),
                 resume_command(args, s, summary.ranks).c_str());
  }
  return code;
}

}  // namespace

Subcommand add_run_command(CLI::App& parent) {
  auto args = std::make_shared<RunArguments>();
  CLI::App* app = parent.add_subcommand(
      "run", "Run a job's starts (alone or under mpirun) into the results database; resumes where it stopped.");
  app->footer(
      "Examples:\n"
      "  loopfarm run jobs/default.toml\n"
      "  mpirun -np 8 loopfarm run jobs/default.toml --db /scratch/default.sqlite\n"
      "  loopfarm run jobs/default.toml --slice 2/8 --db /tmp/slice-2.sqlite   # then: loopfarm merge\n"
      "Stop with SIGINT, SIGTERM or SIGUSR1 (under mpirun: SIGUSR1): the starts in hand finish and are committed;\n"
      "running the same command again resumes.\n"
      "Exit codes: 0 all starts committed, 1 failure, 2 bad input (job file, options, a database holding another\n"
      "job or slice, not a loopfarm database or damaged: left untouched), 3 stopped by a signal (resumable).\n");
  app->add_option("JOB", args->job, "job file (TOML, see docs/guide/job-file.md)")->required()->type_name("JOB.toml");
  app->add_option("--starts", args->starts, "override [search] starts")->type_name("N");
  app->add_option("--seed", args->seed, "override [search] seed")->type_name("S");
  app->add_option("--db", args->db, "override [output] database")->type_name("PATH");
  app->add_option("--slice", args->slice,
                  "run only slice I (from 0) of K equal, contiguous slices of the starts, as a run of its own "
                  "(for a Slurm array; loopfarm merge joins the slices' databases)")
      ->type_name("I/K");
  app->add_flag("--new-run", args->new_run, "add a new run to a database that holds another job");
  app->add_option("--chunk", args->chunk, "start indices handed out per request")
      ->type_name("K")
      ->capture_default_str();
  CLI::Option* progress =
      app->add_option("--progress", args->progress,
                      "auto (a bar on a terminal, else a line within 2 s and then every 10 s), bar, log or none")
          ->type_name("STYLE")
          ->check(CLI::IsMember({"auto", "bar", "log", "none"}))
          ->capture_default_str();
  app->add_flag("--quiet,-q", args->quiet,
                "no progress and no summary on stderr: only errors and, when stopped, the line that resumes")
      ->excludes(progress);
  add_format_option(*app, args->format, {OutputFormat::text, OutputFormat::json},
                    "the summary at the end: text (lines on stderr) or json (one object on stdout), as");
  return {app, [args] { return run_run_command(*args); }};
}

void record_exit_code(int code) {
  const char* path = std::getenv("LOOPFARM_EXIT_FILE");
  if (path == nullptr || *path == '\0' || launcher_rank() != 0) return;
  if (std::FILE* file = std::fopen(path, "w")) {
    std::fprintf(file, "%d\n", code);
    std::fclose(file);
  }
}

}  // namespace loopfarm::cli
