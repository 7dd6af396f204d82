// libFuzzer target: the job-file parser, parse_job (src/search/job.cpp).
//
// The contract (include/loopfarm/search/job.hpp, docs/guide/job-file.md): any text either
// parses into a Job that keeps the documented invariants, or throws JobError
// with one line naming the source. Anything else -- another exception type, a
// multi-line message, an accepted job that breaks an invariant, or a sanitizer
// report -- is a bug, and the fuzzer aborts on it so that libFuzzer records
// the input.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>
#include <string_view>

#include "loopfarm/core/loop.hpp"
#include "loopfarm/search/job.hpp"

namespace {

[[noreturn]] void fail(const std::string& what) {
  std::fprintf(stderr, "job_file_fuzzer: contract broken: %s\n", what.c_str());
  std::abort();
}

void check(bool condition, const char* what) {
  if (!condition) fail(what);
}

// What an accepted job promises to the rest of the program.
void check_invariants(const loopfarm::Job& job) {
  using loopfarm::ParameterSpec;
  const int n = job.loop.joints;
  check(n >= loopfarm::kMinJoints && n <= loopfarm::kMaxJoints, "joints outside [4, 8]");
  check(job.space.joints == n, "space.joints differs from loop.joints");
  check(job.space.specs.size() == static_cast<size_t>(loopfarm::kParameterKinds * n), "wrong number of specs");
  check(job.loop.samples >= 4 && job.loop.samples <= 100000, "samples outside [4, 100000]");
  check(job.loop.range > 0.0 && job.loop.range <= 2.0 * 3.14159265358979323846 + 1e-15, "range outside (0, 2 pi]");
  check(job.loop.stiffness_ratio > 0.0 && std::isfinite(job.loop.stiffness_ratio), "stiffness_ratio not > 0");
  check(job.loop.closure_tolerance > 0.0 && job.loop.closure_tolerance <= 1e-3, "closure_tolerance");
  check(job.loop.stationarity_tolerance > 0.0 && job.loop.stationarity_tolerance <= 1e-3, "stationarity_tolerance");
  check(job.loop.objective == "mean" || job.loop.objective == "max", "objective");
  check(loopfarm::is_known_algorithm(job.optimizer.algorithm), "unknown algorithm accepted");
  check(job.optimizer.max_evaluations >= 1, "max_evaluations < 1");
  check(job.optimizer.time_limit >= 0.0 && std::isfinite(job.optimizer.time_limit), "time_limit");
  check(std::isfinite(job.optimizer.stopval), "stopval not finite");
  check(job.search.starts > 0, "starts <= 0");
  check(job.search.zero_threshold > 0.0 && std::isfinite(job.search.zero_threshold), "zero_threshold");
  check(job.steering.min_travel > 0.0 && std::isfinite(job.steering.min_travel), "min_travel");
  check(job.steering.deflation_power > 0.0 && std::isfinite(job.steering.deflation_power), "deflation_power");
  check(job.steering.deflation_shift >= 0.0 && std::isfinite(job.steering.deflation_shift), "deflation_shift");
  check(!job.output.database.empty(), "empty database path");
  check(job.output.report_threshold > 0.0 && std::isfinite(job.output.report_threshold), "report_threshold");
  for (size_t i = 0; i < job.space.specs.size(); ++i) {
    const ParameterSpec& s = job.space.specs[i];
    switch (s.mode) {
      case ParameterSpec::Mode::fixed:
        check(std::isfinite(s.value), "fixed value not finite");
        break;
      case ParameterSpec::Mode::range:
        check(std::isfinite(s.lo) && std::isfinite(s.hi) && s.lo < s.hi, "range not finite or lo >= hi");
        // The sampler draws lo + (hi - lo) u: the width must be finite too.
        check(std::isfinite(s.hi - s.lo), "range width overflows");
        break;
      case ParameterSpec::Mode::tied:
        check(s.source >= 0 && static_cast<size_t>(s.source) < job.space.specs.size(), "tie source out of range");
        check(static_cast<size_t>(s.source) != i, "tied to itself");
        check(job.space.specs[static_cast<size_t>(s.source)].mode != ParameterSpec::Mode::tied, "tie chain");
        check(s.sign == 1.0 || s.sign == -1.0, "tie sign");
        break;
    }
  }
  // The geometry at the free parameters' lower bounds, midpoints and upper
  // bounds is a valid loop (lengths >= 0, finite) that the library accepts.
  const Eigen::VectorXd lo = job.space.lower_bounds();
  const Eigen::VectorXd hi = job.space.upper_bounds();
  for (const double t : {0.0, 0.5, 1.0}) {
    const Eigen::VectorXd x = lo + t * (hi - lo);
    try {
      const loopfarm::LoopGeometry geometry = job.space.geometry(x);
      loopfarm::validate_geometry(geometry);
      // Energies are divided by L^2: an accepted job must keep L finite.
      check(std::isfinite(loopfarm::length_scale(geometry)), "length scale overflows");
    } catch (const std::exception& error) {
      fail(std::string("accepted job gives an invalid geometry: ") + error.what());
    }
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  try {
    const loopfarm::Job job = loopfarm::parse_job(text, "fuzz.toml");
    check_invariants(job);
  } catch (const loopfarm::JobError& error) {
    const std::string message = error.what();
    // One line that starts with the source name, as the commands print it.
    if (message.find('\n') != std::string::npos || message.find('\r') != std::string::npos) {
      fail("JobError message is not one line: " + message);
    }
    if (message.rfind("fuzz.toml:", 0) != 0) fail("JobError message does not name the file: " + message);
  } catch (const std::exception& error) {
    fail(std::string("unexpected exception: ") + error.what());
  } catch (...) {
    fail("exception of unknown type");
  }
  return 0;
}
