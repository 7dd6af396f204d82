// Pieces every loopfarm subcommand shares: the error kinds that decide the
// exit code, strict parsing of numbers and comma-separated lists, number
// formatting for CSV, and output files that appear only when the
// whole command succeeded.
#pragma once

#include <cstdio>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace loopfarm::cli {

// Exit codes: results were produced; something unexpected went wrong (or the
// environment lacks a tool); the user's input was rejected.
inline constexpr int kExitSuccess = 0;
inline constexpr int kExitFailure = 1;
inline constexpr int kExitUsage = 2;
// loopfarm run stopped by a signal: everything finished is committed, and
// running the same command again resumes.
inline constexpr int kExitStopped = 3;
// loopfarm verify and loopfarm motion: the geometry was read and analysed,
// and no circuit of its rigid loop moves (not verified).
inline constexpr int kExitNotVerified = 4;

// Bad input: an option value, a geometry file, an output path. `where` names
// the flag ("--a") or the file position ("geom.toml:3 key \"a\"") so the user
// can find it; the message is "where: what". Exit code 2.
class UsageError : public std::runtime_error {
 public:
  UsageError(const std::string& where, const std::string& what) : std::runtime_error(where + ": " + what) {}
};

// The input was fine but something the command relies on is missing or broke
// (gnuplot not installed, gnuplot failed). Exit code 1.
class EnvironmentError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// `text` in double quotes with control characters escaped, for messages that
// quote what the user typed.
std::string quote_text(std::string_view text);

// Messages must stay on one line: newlines and tabs become spaces.
std::string one_line(std::string_view text);

// "SIGINT", "SIGTERM", "SIGUSR1", else "signal N": the stop signals a command
// names in its messages.
std::string signal_name(int signal);

// One finite decimal number: optional sign, digits, optional fraction and
// exponent, nothing else (no spaces, no "nan", no "inf", no hex).
double parse_number(std::string_view text, const std::string& where);

// A whole decimal integer, optional leading '-', nothing else.
long long parse_integer(std::string_view text, const std::string& where);

// Comma-separated finite numbers ("2,4,2,4"). Rejects an empty list, empty
// elements ("2,,4", "2,"), junk ("2,x", "4abc"), NaN and infinities.
std::vector<double> parse_number_list(std::string_view text, const std::string& where);

// %.17g: enough digits that the double reads back exactly.
std::string format_double(double value);

// For tables people read: `digits` significant digits (%.*g), "-" for NaN.
std::string format_significant(double value, int digits);
// The values so formatted, joined by `separator`.
std::string join_significant(const std::vector<double>& values, int digits, std::string_view separator);

// An output file that is written in full or not at all. The constructor
// creates a temporary file next to the target, which both proves the target
// can be written before any work is done and lets commit() replace the target
// in one rename, so a command that fails half-way leaves a previous file at
// the target untouched. The destructor removes the temporary file unless it
// was committed.
//
// The target "-" is standard output: the data go to a temporary file in the
// system's temporary directory, which commit() copies to standard output, so
// that a failed command prints nothing there either. A target that exists and
// is not a regular file (a device, a pipe, a socket, a directory), or that is
// or leads through /dev or /proc (/dev/stdout leads to whatever file the shell
// redirected standard output to), is refused: the final rename would replace
// it. A symbolic link to a regular file elsewhere is followed, so the file it
// names is replaced, not the link.
class PendingOutput {
 public:
  // `flag` names the option the path came from, for error messages.
  PendingOutput(std::filesystem::path target, std::string flag);
  ~PendingOutput();
  PendingOutput(const PendingOutput&) = delete;
  PendingOutput& operator=(const PendingOutput&) = delete;

  const std::filesystem::path& target() const { return target_; }
  bool to_standard_output() const { return to_standard_output_; }
  const std::filesystem::path& temporary() const { return temporary_; }
  // The open temporary file, for writing; nullptr after close().
  std::FILE* stream() const { return stream_; }

  // Flushes and closes the stream (a program such as gnuplot may then write
  // the temporary file itself). Throws UsageError if the data could not be
  // written (disk full, I/O error).
  void close();
  // Closes if needed and renames the temporary file onto the target.
  void commit();

 private:
  std::filesystem::path target_;
  std::string flag_;
  std::filesystem::path temporary_;
  std::FILE* stream_ = nullptr;
  bool committed_ = false;
  bool to_standard_output_ = false;
};

// True when an output option's value sends its file to standard output.
inline bool is_standard_output(const std::string& path) { return path == "-"; }

// A temporary file in the system's temporary directory, removed when the
// object goes away (gnuplot's data and script).
class ScratchFile {
 public:
  explicit ScratchFile(const std::string& suffix);
  ~ScratchFile();
  ScratchFile(const ScratchFile&) = delete;
  ScratchFile& operator=(const ScratchFile&) = delete;

  const std::filesystem::path& path() const { return path_; }
  std::FILE* stream() const { return stream_; }
  // Flushes and closes; throws EnvironmentError on a write error.
  void close();

 private:
  std::filesystem::path path_;
  std::FILE* stream_ = nullptr;
};

}  // namespace loopfarm::cli
