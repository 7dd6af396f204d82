#include "cli_support.hpp"

#include <sys/stat.h>
#include <unistd.h>

#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <csignal>
#include <cstdlib>
#include <cstring>
#include <system_error>

namespace loopfarm::cli {
namespace {

bool is_digit(char c) { return c >= '0' && c <= '9'; }

// Length of the longest prefix of `text` that is a decimal number as a
// person writes it: [+-] (digits [. [digits]] | . digits) [(e|E) [+-] digits].
// Returns 0 when there is none. Written out because std::from_chars and
// strtod both also accept "nan", "inf", "infinity" and (strtod) hex and
// leading spaces, none of which belong in a linkage's dimensions.
size_t number_prefix(std::string_view text) {
  size_t i = 0;
  if (i < text.size() && (text[i] == '+' || text[i] == '-')) ++i;
  const size_t integer_start = i;
  while (i < text.size() && is_digit(text[i])) ++i;
  size_t digits = i - integer_start;
  if (i < text.size() && text[i] == '.') {
    ++i;
    const size_t fraction_start = i;
    while (i < text.size() && is_digit(text[i])) ++i;
    digits += i - fraction_start;
  }
  if (digits == 0) return 0;
  if (i < text.size() && (text[i] == 'e' || text[i] == 'E')) {
    size_t j = i + 1;
    if (j < text.size() && (text[j] == '+' || text[j] == '-')) ++j;
    const size_t exponent_start = j;
    while (j < text.size() && is_digit(text[j])) ++j;
    if (j > exponent_start) i = j;  // "2e" is not a number with an exponent
  }
  return i;
}

// Parses one non-empty token; `element` says which list element it is for
// the message ("element 2 of \"2,x\""), or is empty for a single value.
double parse_number_token(std::string_view token, const std::string& where, const std::string& element) {
  const std::string describe = element.empty() ? quote_text(token) : element + " is " + quote_text(token);
  const size_t length = number_prefix(token);
  if (length != token.size() || length == 0) {
    std::string lowered(token);
    for (char& c : lowered) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    if (lowered.find("nan") != std::string::npos || lowered.find("inf") != std::string::npos) {
      throw UsageError(where, describe + ": not a finite number");
    }
    throw UsageError(where, describe + ": not a number");
  }
  // from_chars does not take a leading '+'.
  std::string_view digits = token;
  if (!digits.empty() && digits.front() == '+') digits.remove_prefix(1);
  double value = 0.0;
  const auto [end, error] = std::from_chars(digits.data(), digits.data() + digits.size(), value);
  if (error == std::errc::result_out_of_range || !std::isfinite(value)) {
    throw UsageError(where, describe + ": out of the range of a double");
  }
  if (error != std::errc{} || end != digits.data() + digits.size()) {
    throw UsageError(where, describe + ": not a number");
  }
  return value;
}

}  // namespace

std::string quote_text(std::string_view text) {
  std::string out = "\"";
  for (const char c : text) {
    const auto u = static_cast<unsigned char>(c);
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (u < 0x20 || u == 0x7f) {
      char buffer[8];
      std::snprintf(buffer, sizeof buffer, "\\x%02x", u);
      out += buffer;
    } else {
      out += c;
    }
  }
  out += '"';
  return out;
}

std::string one_line(std::string_view text) {
  std::string out(text);
  for (char& c : out) {
    if (c == '\n' || c == '\r' || c == '\t') c = ' ';
  }
  while (!out.empty() && out.back() == ' ') out.pop_back();
  return out;
}

double parse_number(std::string_view text, const std::string& where) {
  if (text.empty()) throw UsageError(where, "empty value; expected a number");
  return parse_number_token(text, where, "");
}

long long parse_integer(std::string_view text, const std::string& where) {
  if (text.empty()) throw UsageError(where, "empty value; expected an integer");
  long long value = 0;
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (error == std::errc::result_out_of_range) throw UsageError(where, quote_text(text) + " is out of range");
  if (error != std::errc{} || end != text.data() + text.size()) {
    throw UsageError(where, quote_text(text) + " is not an integer");
  }
  return value;
}

std::vector<double> parse_number_list(std::string_view text, const std::string& where) {
  if (text.empty()) throw UsageError(where, "empty list; expected comma-separated numbers such as 2,4,2,4");
  std::vector<double> values;
  size_t start = 0;
  for (int index = 1;; ++index) {
    const size_t comma = text.find(',', start);
    const std::string_view token =
        text.substr(start, comma == std::string_view::npos ? std::string_view::npos : comma - start);
    const std::string describe = "element " + std::to_string(index) + " of " + quote_text(text);
    if (token.empty()) throw UsageError(where, describe + " is empty");
    values.push_back(parse_number_token(token, where, describe));
    if (comma == std::string_view::npos) break;
    start = comma + 1;
  }
  return values;
}

std::string format_double(double value) {
  char buffer[40];
  std::snprintf(buffer, sizeof buffer, "%.17g", value);
  return buffer;
}

std::string format_significant(double value, int digits) {
  if (std::isnan(value)) return "-";
  char buffer[40];
  std::snprintf(buffer, sizeof buffer, "%.*g", digits, value);
  return buffer;
}

std::string join_significant(const std::vector<double>& values, int digits, std::string_view separator) {
  std::string out;
  for (size_t i = 0; i < values.size(); ++i) {
    if (i > 0) out += separator;
    out += format_significant(values[i], digits);
  }
  return out;
}

// ---------------------------------------------------------------------------

namespace {

// Permissions a newly created file would get under the current umask (mkstemp
// creates 0600, which would surprise whoever reads the results later).
mode_t default_file_mode() {
  const mode_t mask = ::umask(0);
  ::umask(mask);
  return static_cast<mode_t>(0666 & ~mask);
}

// mkstemps() on a template built from `prefix`; returns the open stream and
// fills `path`, or nullptr with errno set.
std::FILE* create_unique(const std::string& prefix, const std::string& suffix, std::filesystem::path& path) {
  std::string name = prefix + "XXXXXX" + suffix;
  const int fd = ::mkstemps(name.data(), static_cast<int>(suffix.size()));
  if (fd < 0) return nullptr;
  std::FILE* stream = ::fdopen(fd, "w");
  if (stream == nullptr) {
    const int saved = errno;
    ::close(fd);
    ::unlink(name.c_str());
    errno = saved;
    return nullptr;
  }
  path = name;
  return stream;
}

// Whether `path`, or a link on the way from it to a file, names something in
// /dev or /proc. /dev/stdout is a link to /proc/self/fd/1, which is a link to
// whatever standard output is: a regular file when the shell redirects it,
// which a rename onto /dev/stdout's resolved path would replace.
bool reaches_a_device_path(std::filesystem::path path) {
  std::error_code ec;
  for (int hop = 0; hop < 40; ++hop) {
    const std::filesystem::path absolute = std::filesystem::absolute(path, ec).lexically_normal();
    if (ec) return false;
    const std::string text = absolute.string();
    if (text.rfind("/dev/", 0) == 0 || text.rfind("/proc/", 0) == 0) return true;
    if (!std::filesystem::is_symlink(std::filesystem::symlink_status(absolute, ec))) return false;
    const std::filesystem::path next = std::filesystem::read_symlink(absolute, ec);
    if (ec) return false;
    path = next.is_absolute() ? next : absolute.parent_path() / next;
  }
  return true;  // a loop of links: not a file to write
}

}  // namespace

PendingOutput::PendingOutput(std::filesystem::path target, std::string flag)
    : target_(std::move(target)), flag_(std::move(flag)) {
  if (target_.empty()) throw UsageError(flag_, "empty file name");
  if (is_standard_output(target_.string())) {
    to_standard_output_ = true;
    std::error_code ec;
    std::filesystem::path directory = std::filesystem::temp_directory_path(ec);
    if (ec) directory = "/tmp";
    stream_ = create_unique((directory / "loopfarm-stdout-").string(), "", temporary_);
    if (stream_ == nullptr) {
      throw EnvironmentError("cannot create a temporary file in " + quote_text(directory.string()) + ": " +
                             std::strerror(errno));
    }
    return;
  }
  std::error_code ec;
  const std::filesystem::file_status status = std::filesystem::status(target_, ec);
  if (std::filesystem::is_directory(status)) {
    throw UsageError(flag_, "cannot write " + quote_text(target_.string()) + ": it is a directory");
  }
  if ((std::filesystem::exists(status) && !std::filesystem::is_regular_file(status)) ||
      reaches_a_device_path(target_)) {
    throw UsageError(flag_, "will not write over " + quote_text(target_.string()) +
                                ": it is not a regular file (a device, a pipe, a socket or a descriptor such as "
                                "/dev/stdout); give '-' for standard output");
  }
  if (std::filesystem::is_symlink(std::filesystem::symlink_status(target_, ec))) {
    const std::filesystem::path resolved = std::filesystem::canonical(target_, ec);
    if (!ec) target_ = resolved;
  }
  // The temporary file goes into the target's own directory so that the final
  // rename cannot cross file systems.
  const std::filesystem::path directory = target_.has_parent_path() ? target_.parent_path() : ".";
  // Hidden name, built by appending (GCC 12 raises a false -Wrestrict on
  // "." + string, GCC bug 105329).
  std::string hidden = ".";
  hidden += target_.filename().string();
  hidden += ".tmp-";
  const std::string prefix = (directory / hidden).string();
  stream_ = create_unique(prefix, "", temporary_);
  if (stream_ == nullptr) {
    throw UsageError(flag_, "cannot write " + quote_text(target_.string()) + ": " + std::strerror(errno));
  }
  ::fchmod(::fileno(stream_), default_file_mode());
}

PendingOutput::~PendingOutput() {
  if (stream_ != nullptr) std::fclose(stream_);
  if (!committed_ && !temporary_.empty()) {
    std::error_code ignored;
    std::filesystem::remove(temporary_, ignored);
  }
}

void PendingOutput::close() {
  if (stream_ == nullptr) return;
  const bool write_failed = std::ferror(stream_) != 0;
  const bool close_failed = std::fclose(stream_) != 0;
  stream_ = nullptr;
  if (write_failed || close_failed) {
    throw UsageError(flag_, "cannot write " + quote_text(target_.string()) + ": " + std::strerror(errno));
  }
}

void PendingOutput::commit() {
  close();
  if (to_standard_output_) {
    std::FILE* in = std::fopen(temporary_.c_str(), "rb");
    if (in == nullptr) throw EnvironmentError("cannot read back " + quote_text(temporary_.string()));
    char buffer[1 << 16];
    size_t got = 0;
    bool failed = false;
    while (!failed && (got = std::fread(buffer, 1, sizeof buffer, in)) > 0) {
      failed = std::fwrite(buffer, 1, got, stdout) != got;
    }
    failed = failed || std::ferror(in) != 0;
    std::fclose(in);
    if (failed || std::fflush(stdout) != 0) throw EnvironmentError(flag_ + ": cannot write to standard output");
    committed_ = false;  // the temporary file is removed by the destructor
    return;
  }
  std::error_code ec;
  std::filesystem::rename(temporary_, target_, ec);
  if (ec) throw UsageError(flag_, "cannot write " + quote_text(target_.string()) + ": " + ec.message());
  committed_ = true;
}

ScratchFile::ScratchFile(const std::string& suffix) {
  std::error_code ec;
  std::filesystem::path directory = std::filesystem::temp_directory_path(ec);
  if (ec) directory = "/tmp";
  stream_ = create_unique((directory / "loopfarm-").string(), suffix, path_);
  if (stream_ == nullptr) {
    throw EnvironmentError("cannot create a temporary file in " + quote_text(directory.string()) + ": " +
                           std::strerror(errno));
  }
}

ScratchFile::~ScratchFile() {
  if (stream_ != nullptr) std::fclose(stream_);
  if (!path_.empty()) {
    std::error_code ignored;
    std::filesystem::remove(path_, ignored);
  }
}

void ScratchFile::close() {
  if (stream_ == nullptr) return;
  const bool failed = std::ferror(stream_) != 0;
  const bool close_failed = std::fclose(stream_) != 0;
  stream_ = nullptr;
  if (failed || close_failed) {
    throw EnvironmentError("cannot write temporary file " + quote_text(path_.string()) + ": " + std::strerror(errno));
  }
}

std::string signal_name(int signal) {
  switch (signal) {
    case SIGINT:
      return "SIGINT";
    case SIGTERM:
      return "SIGTERM";
    case SIGUSR1:
      return "SIGUSR1";
    default:
      return "signal " + std::to_string(signal);
  }
}

}  // namespace loopfarm::cli
